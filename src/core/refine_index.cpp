// SPDX-License-Identifier: MIT
#include "refine_index.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "failure.hpp"

KISSM_DETAIL_BEGIN

namespace {
constexpr int kCellBits = 21; // per axis in a cell key, as the voxel keys of voxelize.cpp
constexpr std::uint64_t kCellMax = (std::uint64_t{1} << kCellBits) - 1;
// Cell ranges are widened by this share of a cell: more than the rounding of the double-precision index
// arithmetic and of the float distances it stands for, so no point within the radius is ever outside them.
constexpr double kCellMargin = 1e-5;

std::uint64_t cell_key(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
    return x | (y << kCellBits) | (z << (2 * kCellBits));
}

std::size_t cell_hash(std::uint64_t key) { return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20); }
} // namespace

RefineIndex::RefineIndex(const std::vector<Vec3f> &points, double cell) {
    if (points.size() >= static_cast<std::size_t>(kLeafBit))
        fail(ErrorKind::InvalidArgument, "too many points for the refinement index");
    std::vector<std::uint32_t> order(points.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    xs_.reserve(points.size()), ys_.reserve(points.size()), zs_.reserve(points.size());
    index_.reserve(points.size());
    nodes_.reserve(2 * (points.size() / (kLeafPoints / 2) + 1));
    if (!points.empty()) build(order.data(), order.data() + order.size(), points);
    slot_.resize(index_.size());
    for (std::size_t s = 0; s < index_.size(); ++s) slot_[index_[s]] = static_cast<std::uint32_t>(s);
    build_cells(cell);
}

std::uint32_t RefineIndex::build(std::uint32_t *begin, std::uint32_t *end, const std::vector<Vec3f> &points) {
    const auto here = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(Node{0.0f, 0, 0});
    const std::size_t n = static_cast<std::size_t>(end - begin);
    if (n <= static_cast<std::size_t>(kLeafPoints)) {
        nodes_[here].link = static_cast<std::uint32_t>(index_.size());
        nodes_[here].info = kLeafBit | static_cast<std::uint32_t>(n);
        for (const std::uint32_t *p = begin; p != end; ++p) {
            xs_.push_back(points[*p].x()), ys_.push_back(points[*p].y()), zs_.push_back(points[*p].z());
            index_.push_back(*p);
        }
        return here;
    }
    // Split the widest side of the bounding box at the median; (coordinate, index) order makes the split a
    // function of the data alone.
    Vec3f lo = points[*begin], hi = lo;
    for (const std::uint32_t *p = begin; p != end; ++p) lo = lo.cwiseMin(points[*p]), hi = hi.cwiseMax(points[*p]);
    int dim = 0;
    const Vec3f ext = hi - lo;
    if (ext.y() > ext[dim]) dim = 1;
    if (ext.z() > ext[dim]) dim = 2;
    std::uint32_t *mid = begin + n / 2;
    std::nth_element(begin, mid, end, [&](std::uint32_t a, std::uint32_t b) {
        const float ca = points[a][dim], cb = points[b][dim];
        return ca < cb || (ca == cb && a < b);
    });
    nodes_[here].split = points[*mid][dim];
    nodes_[here].info = static_cast<std::uint32_t>(dim);
    build(begin, mid, points);
    const std::uint32_t high = build(mid, end, points);
    nodes_[here].link = high;
    return here;
}

void RefineIndex::build_cells(double cell) {
    if (!(cell > 0.0) || index_.empty()) return;
    for (int d = 0; d < 3; ++d) cell_origin_[d] = std::numeric_limits<double>::infinity();
    for (std::size_t s = 0; s < index_.size(); ++s) {
        cell_origin_[0] = std::min(cell_origin_[0], static_cast<double>(xs_[s]));
        cell_origin_[1] = std::min(cell_origin_[1], static_cast<double>(ys_[s]));
        cell_origin_[2] = std::min(cell_origin_[2], static_cast<double>(zs_[s]));
    }
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(index_.size());
    for (std::size_t s = 0; s < index_.size(); ++s) {
        const double c[3] = {static_cast<double>(xs_[s]), static_cast<double>(ys_[s]), static_cast<double>(zs_[s])};
        std::uint64_t ix[3];
        for (int d = 0; d < 3; ++d) {
            const double f = std::floor((c[d] - cell_origin_[d]) / cell);
            if (!(f <= static_cast<double>(kCellMax))) return; // too wide for the keys: the tree alone serves
            ix[d] = static_cast<std::uint64_t>(f);
        }
        keyed[s] = {cell_key(ix[0], ix[1], ix[2]), static_cast<std::uint32_t>(s)};
    }
    std::sort(keyed.begin(), keyed.end());
    std::size_t num_cells = 0;
    for (std::size_t s = 0; s < keyed.size(); ++s) num_cells += s == 0 || keyed[s].first != keyed[s - 1].first;
    std::size_t capacity = 16;
    while (capacity < 2 * num_cells) capacity *= 2;
    cells_.assign(capacity, Cell{kNoCell, 0, 0});
    cell_slots_.resize(keyed.size());
    for (std::size_t s = 0; s < keyed.size();) {
        std::size_t e = s;
        while (e < keyed.size() && keyed[e].first == keyed[s].first) cell_slots_[e] = keyed[e].second, ++e;
        std::size_t h = cell_hash(keyed[s].first) & (capacity - 1);
        while (cells_[h].key != kNoCell) h = (h + 1) & (capacity - 1);
        cells_[h] = Cell{keyed[s].first, static_cast<std::uint32_t>(s), static_cast<std::uint32_t>(e - s)};
        s = e;
    }
    cell_ = cell;
}

const RefineIndex::Cell *RefineIndex::find_cell(std::uint64_t key) const {
    const std::size_t mask = cells_.size() - 1;
    for (std::size_t h = cell_hash(key) & mask;; h = (h + 1) & mask) {
        if (cells_[h].key == key) return &cells_[h];
        if (cells_[h].key == kNoCell) return nullptr;
    }
}

// One point against the best so far: the one distance expression of the index, so hints, cells and leaves give
// the same bits for the same point.
inline void RefineIndex::scan(std::size_t slot, float qx, float qy, float qz, float &best_d2,
                              std::uint32_t &best) const {
    const float dx = xs_[slot] - qx, dy = ys_[slot] - qy, dz = zs_[slot] - qz;
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < best_d2 || (d2 == best_d2 && index_[slot] < best)) best_d2 = d2, best = index_[slot];
}

bool RefineIndex::search_cells(float qx, float qy, float qz, float &best_d2, std::uint32_t &best) const {
    const double r = std::sqrt(static_cast<double>(best_d2));
    if (cells_.empty() || !(r <= cell_)) return false;
    const double q[3] = {qx, qy, qz};
    std::uint64_t lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
        const double a = std::floor((q[d] - r - cell_origin_[d]) / cell_ - kCellMargin);
        const double b = std::floor((q[d] + r - cell_origin_[d]) / cell_ + kCellMargin);
        if (b < 0.0 || a > static_cast<double>(kCellMax)) return true; // no cell of the index is within reach
        lo[d] = a < 0.0 ? 0 : static_cast<std::uint64_t>(a);
        hi[d] = b > static_cast<double>(kCellMax) ? kCellMax : static_cast<std::uint64_t>(b);
    }
    for (std::uint64_t z = lo[2]; z <= hi[2]; ++z)
        for (std::uint64_t y = lo[1]; y <= hi[1]; ++y)
            for (std::uint64_t x = lo[0]; x <= hi[0]; ++x) {
                const Cell *c = find_cell(cell_key(x, y, z));
                if (c == nullptr) continue;
                for (std::uint32_t k = c->first; k < c->first + c->count; ++k)
                    scan(cell_slots_[k], qx, qy, qz, best_d2, best);
            }
    return true;
}

std::uint32_t RefineIndex::search_tree(float qx, float qy, float qz, float &best_d2, std::uint32_t best) const {
    // A far child waits on the stack with the lower bound (q[dim] - split)^2 of its points' squared distance.
    // Rounding is monotone, so no point's computed distance can fall below that bound: pruning on "bound >
    // best" loses no point at the best distance, and ties go to the lower index wherever they are found.
    struct Pending {
        std::uint32_t node;
        float bound;
    };
    Pending stack[64];
    int top = 0;
    std::uint32_t node = 0;
    float bound = 0.0f;
    const float qv[3] = {qx, qy, qz};
    for (;;) {
        if (bound <= best_d2) {
            for (;;) {
                const Node &nd = nodes_[node];
                if (nd.info & kLeafBit) {
                    const std::size_t first = nd.link, count = nd.info & ~kLeafBit;
                    for (std::size_t s = first; s < first + count; ++s) scan(s, qx, qy, qz, best_d2, best);
                    break;
                }
                const float diff = qv[nd.info] - nd.split;
                const std::uint32_t low = node + 1, high = nd.link;
                // Points equal to the split may sit on either side: the far side's bound is then 0. At most one
                // entry per level waits, and fewer than 2^31 points make fewer than 28 levels.
                stack[top++] = Pending{diff <= 0.0f ? high : low, diff * diff};
                node = diff <= 0.0f ? low : high;
            }
        }
        if (top == 0) break;
        --top;
        node = stack[top].node;
        bound = stack[top].bound;
    }
    return best;
}

std::uint32_t RefineIndex::nearest(const Vec3f &q, float max_dist2, float *dist2, std::uint32_t hint) const {
    std::uint32_t best = kNone;
    float best_d2 = max_dist2;
    if (!nodes_.empty() && max_dist2 >= 0.0f) {
        const float qx = q.x(), qy = q.y(), qz = q.z();
        if (hint < slot_.size()) scan(slot_[hint], qx, qy, qz, best_d2, best);
        if (best == kNone || !search_cells(qx, qy, qz, best_d2, best)) best = search_tree(qx, qy, qz, best_d2, best);
    }
    if (dist2 != nullptr) *dist2 = best == kNone ? std::numeric_limits<float>::infinity() : best_d2;
    return best;
}

std::size_t RefineIndex::bytes() const {
    return nodes_.capacity() * sizeof(Node) + (xs_.capacity() + ys_.capacity() + zs_.capacity()) * sizeof(float) +
           (index_.capacity() + slot_.capacity() + cell_slots_.capacity()) * sizeof(std::uint32_t) +
           cells_.capacity() * sizeof(Cell);
}

KISSM_DETAIL_END
