// SPDX-License-Identifier: MIT
#include "place_gate.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Core>

KISSM_DETAIL_BEGIN

namespace {

// Voters: an evenly spread sample of the scan's keypoints, each voting once for every cell among those of its
// kVotes nearest map descriptors. A thousand voters cost about a twelfth of the matching that follows, and in
// the scan-to-map benchmark the winning window held 4-8 times the votes of the next (docs/design/frames.md).
constexpr std::size_t kVoters = 1024;
constexpr int kVotes = 4;
static_assert(kVotes <= RankedNeighbours::kMaxK, "a ranked search keeps at most kMaxK neighbours");

// Cells are half the scan's radius (its keypoints' largest distance from their mean). A window of +-kWindow
// cells around a cell spans the scan's extent either way; the region, one cell wider each way, still holds
// the whole scan when the winning window's centre cell is a neighbour of the one the scan's centre lies in.
constexpr int kWindow = 2;
constexpr int kRegion = kWindow + 1;

// Cell coordinates are packed 21 bits each; a cloud whose cells do not fit is searched whole.
constexpr std::int64_t kCellBias = std::int64_t(1) << 20;
constexpr std::int64_t kCellMask = (std::int64_t(1) << 21) - 1;
constexpr std::int64_t kNoKey = -1;

struct Cell {
    std::int64_t c[3];
};

// The cell of `p`, for cells of size 1 / `inverse`; false when it does not fit the packed key (or is not finite).
bool cell_of(const Vec3f &p, double inverse, Cell &out) {
    for (int d = 0; d < 3; ++d) {
        const double v = std::floor(static_cast<double>(p[d]) * inverse);
        if (!(std::abs(v) < static_cast<double>(kCellBias - 4 * kRegion))) return false; // NaN fails too
        out.c[d] = static_cast<std::int64_t>(v);
    }
    return true;
}

std::int64_t key_of(std::int64_t x, std::int64_t y, std::int64_t z) {
    return ((x + kCellBias) << 42) | ((y + kCellBias) << 21) | (z + kCellBias);
}

Cell cell_of_key(std::int64_t key) {
    return Cell{{(key >> 42) - kCellBias, ((key >> 21) & kCellMask) - kCellBias, (key & kCellMask) - kCellBias}};
}

struct CellVotes {
    std::int64_t key;
    std::uint64_t votes;
};

// Votes in the window of +-kWindow cells around `centre`. Keys of one (x, y) column are consecutive in z, so
// each of the window's columns is one binary search and a short scan.
std::uint64_t window_votes(const std::vector<CellVotes> &cells, const Cell &centre) {
    std::uint64_t sum = 0;
    for (int dx = -kWindow; dx <= kWindow; ++dx)
        for (int dy = -kWindow; dy <= kWindow; ++dy) {
            const std::int64_t x = centre.c[0] + dx, y = centre.c[1] + dy;
            const std::int64_t lo = key_of(x, y, centre.c[2] - kWindow), hi = key_of(x, y, centre.c[2] + kWindow);
            auto it = std::lower_bound(cells.begin(), cells.end(), lo,
                                       [](const CellVotes &a, std::int64_t k) { return a.key < k; });
            for (; it != cells.end() && it->key <= hi; ++it) sum += it->votes;
        }
    return sum;
}

bool within(const Cell &a, const Cell &b, std::int64_t reach) {
    return std::abs(a.c[0] - b.c[0]) <= reach && std::abs(a.c[1] - b.c[1]) <= reach &&
           std::abs(a.c[2] - b.c[2]) <= reach;
}

} // namespace

PlaceRegion PlaceRegion::find(const IndexedDescriptors &scan, const IndexedDescriptors &map, RunContext &ctx) {
    PlaceRegion none;
    const Descriptors &sd = *scan.descriptors, &md = *map.descriptors;
    const std::size_t ns = sd.keypoint.size(), nm = md.keypoint.size();
    if (!scan.points || !map.points || !map.grid || ns == 0 || nm < kMinSizeRatio * ns || map.index->empty())
        return none;

    // The scan's extent, in its own frame (the map's frame is unknown to it; only the size carries over).
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::uint32_t v : sd.keypoint) mean += (*scan.points)[v].cast<double>();
    mean /= static_cast<double>(ns);
    double radius = 0.0;
    for (std::uint32_t v : sd.keypoint) radius = std::max(radius, ((*scan.points)[v].cast<double>() - mean).norm());
    if (!(radius > 0.0) || !std::isfinite(radius)) return none;
    const double inverse = 2.0 / radius; // cells of half the radius

    // Votes: per voter its distinct cells (kNoKey fills the rest), all sorted, then counted per cell.
    const std::size_t step = std::max<std::size_t>(1, ns / kVoters);
    const std::size_t voters = (ns + step - 1) / step;
    std::vector<std::int64_t> keys(voters * kVotes, kNoKey);
    std::vector<unsigned char> unplaceable(voters, 0); // not std::vector<bool>: written from several threads
    ctx.parallel_for(voters, 64, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            std::int64_t *mine = &keys[i * kVotes];
            const RankedNeighbours r = map.index->nearest(&sd.values[i * step * kDescriptorDim], kVotes);
            for (int k = 0; k < r.found(); ++k) {
                Cell c;
                if (!cell_of((*map.points)[md.keypoint[r.index(k)]], inverse, c)) {
                    unplaceable[i] = 1;
                    break;
                }
                mine[k] = key_of(c.c[0], c.c[1], c.c[2]);
            }
            std::sort(mine, mine + kVotes);
            for (int k = kVotes - 1; k > 0; --k)
                if (mine[k] == mine[k - 1]) mine[k] = kNoKey;
        }
    });
    if (std::find(unplaceable.begin(), unplaceable.end(), 1) != unplaceable.end()) return none;
    std::sort(keys.begin(), keys.end());
    std::vector<CellVotes> cells;
    for (std::int64_t k : keys) {
        if (k == kNoKey) continue;
        if (!cells.empty() && cells.back().key == k)
            ++cells.back().votes;
        else
            cells.push_back(CellVotes{k, 1});
    }
    if (cells.empty()) return none;

    // The winning window (centred on a voted cell; ties by the lower key), and the best window sharing no cell
    // with it: a scan that looks alike in two places gets no region.
    std::vector<std::uint64_t> score(cells.size());
    for (std::size_t i = 0; i < cells.size(); ++i) score[i] = window_votes(cells, cell_of_key(cells[i].key));
    const std::size_t best = static_cast<std::size_t>(std::max_element(score.begin(), score.end()) - score.begin());
    const Cell centre = cell_of_key(cells[best].key);
    std::uint64_t rival = 0;
    for (std::size_t i = 0; i < cells.size(); ++i)
        if (!within(cell_of_key(cells[i].key), centre, 2 * kWindow)) rival = std::max(rival, score[i]);
    if (static_cast<double>(score[best]) < kMinMargin * static_cast<double>(rival)) return none;

    // The region: the keypoints with a cell's floor(x * inverse) = c tested as c <= x * inverse < c + 1, taken
    // from the map's keypoint grid (only the columns the box overlaps are read).
    double lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
        lo[d] = static_cast<double>(centre.c[d] - kRegion);
        hi[d] = static_cast<double>(centre.c[d] + kRegion + 1);
    }
    std::vector<std::uint32_t> region = map.grid->select(*map.points, md.keypoint, inverse, lo, hi);
    if (region.empty() || 2 * region.size() > nm) return none;

    PlaceRegion out;
    out.descriptors_ = &md;
    out.projection_ = &map.index->projection();
    std::vector<float> projected(region.size() * DescriptorProjection::kDim);
    ctx.parallel_for(region.size(), 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i)
            out.projection_->apply(&md.values[static_cast<std::size_t>(region[i]) * kDescriptorDim],
                                   &projected[i * DescriptorProjection::kDim]);
    });
    out.tree_ = std::make_unique<const ProjectedKdTree>(projected.data(), region.size());
    out.keypoints_ = std::move(region);
    return out;
}

RankedNeighbours PlaceRegion::nearest(const float *query, int k) const {
    constexpr int kCandidates = DescriptorIndex::kCandidates;
    float projected[DescriptorProjection::kDim];
    projection_->apply(query, projected);
    std::uint32_t cand[kCandidates];
    float cand_dist[kCandidates];
    const int found = tree_->nearest(projected, kCandidates, cand, cand_dist);
    RankedNeighbours best(k);
    for (int i = 0; i < found; ++i) {
        const std::uint32_t m = keypoints_[cand[i]];
        best.add(descriptor_dist2(query, &descriptors_->values[static_cast<std::size_t>(m) * kDescriptorDim]), m);
    }
    return best;
}

KISSM_DETAIL_END
