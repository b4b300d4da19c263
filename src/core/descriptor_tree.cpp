// SPDX-License-Identifier: MIT
#include "descriptor_tree.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "lowest_bit.hpp"

// SSE2 is part of every x86-64 target (see pair_features.cpp for why not 32-bit x86).
#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__))
#  define KISSM_KDTREE_SSE2 1
#  include <emmintrin.h>
#else
#  define KISSM_KDTREE_SSE2 0
#endif

KISSM_DETAIL_BEGIN

namespace {

// The largest float below FLT_MAX: until k points are found a candidate must be strictly closer than
// FLT_MAX, as in nanoflann, so "at most this" is the one comparison used throughout.
constexpr float kNotFull = 0x1.fffffcp+127f;

// Squared distances from q to a leaf's points, block by block, and a bit mask of the slots whose distance
// is <= limit (bit i for slot i of the leaf), so that the caller visits only those: a whole leaf is usually
// dismissed with one test, and the few candidates of the others are found without a pass over every slot
// (docs/design/performance.md, second pass, "What changed"). Lane by lane the vector code performs the same
// operations in the same order as the scalar loop over the dimensions. x - q rather than q - x: the same square
// (rounding is symmetric in sign). Starting from the first square equals starting from 0 + it: a square is
// never -0.
template <int Dim, int Lane>
std::uint64_t leaf_distances(const float *__restrict q, const float *__restrict x, std::size_t blocks, float limit,
                             float *__restrict out) {
    std::uint64_t mask = 0;
#if KISSM_KDTREE_SSE2
    static_assert(Lane == 4, "one SSE2 register per dimension and block");
    __m128 vq[Dim];
    for (int d = 0; d < Dim; ++d) vq[d] = _mm_set1_ps(q[d]);
    const __m128 vlimit = _mm_set1_ps(limit);
    for (std::size_t b = 0; b < blocks; ++b, x += Dim * Lane, out += Lane) {
        __m128 t = _mm_sub_ps(_mm_loadu_ps(x), vq[0]);
        __m128 acc = _mm_mul_ps(t, t);
        for (int d = 1; d < Dim; ++d) {
            t = _mm_sub_ps(_mm_loadu_ps(x + d * Lane), vq[d]);
            acc = _mm_add_ps(acc, _mm_mul_ps(t, t));
        }
        _mm_storeu_ps(out, acc);
        mask |= static_cast<std::uint64_t>(_mm_movemask_ps(_mm_cmple_ps(acc, vlimit))) << (b * Lane);
    }
#else
    for (std::size_t b = 0; b < blocks; ++b, x += Dim * Lane, out += Lane) {
        float acc[Lane];
        for (int j = 0; j < Lane; ++j) {
            const float t = x[j] - q[0];
            acc[j] = t * t;
        }
        for (int d = 1; d < Dim; ++d)
            for (int j = 0; j < Lane; ++j) {
                const float t = x[d * Lane + j] - q[d];
                acc[j] += t * t;
            }
        for (int j = 0; j < Lane; ++j) {
            out[j] = acc[j];
            mask |= static_cast<std::uint64_t>(acc[j] <= limit) << (b * Lane + static_cast<std::size_t>(j));
        }
    }
#endif
    return mask;
}

} // namespace

// (squared distance, index) as one integer with the same order: the distance is a sum of squares, never
// negative, never -0 and (once accepted) never NaN, and the bits of such floats order like the values.
inline std::uint64_t rank_key(float dist, std::uint32_t index) {
    std::uint32_t bits;
    std::memcpy(&bits, &dist, sizeof bits);
    return static_cast<std::uint64_t>(bits) << 32 | index;
}

struct ProjectedKdTree::Search {
    float query[kDim];
    float gap2[kDim]; // per dimension, a squared lower bound on |query - point| over the current subtree
    float limit;      // accept a distance <= limit: the k-th best once k are found
    int k;
    int count = 0;
    std::uint64_t heap[kMaxK]; // rank keys, a max-heap: the k-th best on top
    std::uint32_t slot[kMaxK]; // each key's slot, moved with it

    // A binary heap rather than a sorted list: most accepted points are replaced again later, and a sorted
    // insertion shifts half the list each time. A tie with the k-th distance goes to the lower index.
    void add(float d, std::uint32_t id, std::uint32_t at) {
        const std::uint64_t key = rank_key(d, id);
        int i;
        if (count < k) {
            for (i = count++; i > 0 && heap[(i - 1) / 2] < key; i = (i - 1) / 2) {
                heap[i] = heap[(i - 1) / 2];
                slot[i] = slot[(i - 1) / 2];
            }
            heap[i] = key;
            slot[i] = at;
            if (count < k) return;
        } else {
            if (!(key < heap[0])) return;
            for (i = 0;;) {
                int c = 2 * i + 1;
                if (c >= k) break;
                if (c + 1 < k && heap[c] < heap[c + 1]) ++c;
                if (!(key < heap[c])) break;
                heap[i] = heap[c];
                slot[i] = slot[c];
                i = c;
            }
            heap[i] = key;
            slot[i] = at;
        }
        const std::uint32_t bits = static_cast<std::uint32_t>(heap[0] >> 32);
        std::memcpy(&limit, &bits, sizeof limit);
    }
};

ProjectedKdTree::ProjectedKdTree(const float *points, std::size_t n) {
    std::vector<std::uint32_t> order;
    order.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        bool finite = true;
        for (int d = 0; d < kDim; ++d) finite = finite && std::isfinite(points[i * kDim + d]);
        if (finite) order.push_back(static_cast<std::uint32_t>(i));
    }
    if (order.empty()) return;
    for (int d = 0; d < kDim; ++d) box_lo_[d] = box_hi_[d] = points[static_cast<std::size_t>(order[0]) * kDim + d];
    for (const std::uint32_t i : order)
        for (int d = 0; d < kDim; ++d) {
            box_lo_[d] = std::min(box_lo_[d], points[static_cast<std::size_t>(i) * kDim + d]);
            box_hi_[d] = std::max(box_hi_[d], points[static_cast<std::size_t>(i) * kDim + d]);
        }
    const std::size_t blocks = order.size() / kLane + 2 * (order.size() / kLeafPoints + 1);
    nodes_.reserve(4 * (order.size() / kLeafPoints + 1));
    blocks_.reserve(blocks * kDim * kLane);
    index_.reserve(blocks * kLane);
    build(order.data(), order.data() + order.size(), points);
}

std::uint32_t ProjectedKdTree::build(std::uint32_t *begin, std::uint32_t *end, const float *points) {
    const std::size_t count = static_cast<std::size_t>(end - begin);
    const std::uint32_t id = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(Node{});
    const auto coord = [points](std::uint32_t i, int d) { return points[static_cast<std::size_t>(i) * kDim + d]; };

    if (count <= static_cast<std::size_t>(kLeafPoints)) {
        const std::size_t first = index_.size() / kLane;
        const std::size_t nblocks = (count + kLane - 1) / kLane;
        // Padding lanes sit at infinity: their distance is never finite, so they are never accepted.
        blocks_.resize(blocks_.size() + nblocks * kDim * kLane, INFINITY);
        index_.resize(index_.size() + nblocks * kLane, kNoPoint);
        for (std::size_t i = 0; i < count; ++i) {
            const std::size_t block = first + i / kLane, lane = i % kLane;
            for (int d = 0; d < kDim; ++d)
                blocks_[(block * kDim + static_cast<std::size_t>(d)) * kLane + lane] = coord(begin[i], d);
            index_[block * kLane + lane] = begin[i];
        }
        nodes_[id] = Node{0.0f, 0.0f, static_cast<std::uint32_t>(first), kLeafBit | static_cast<std::uint32_t>(count)};
        return id;
    }

    // Split the widest dimension so that the low side holds whole leaves, half of them (rounded up): every
    // leaf is full but the last. With median splits leaves held between half and all of kLeafPoints
    // depending on where the point count fell between powers of two, and the search cost per query swung
    // with it (more leaves per search when they are emptier; docs/design/performance.md, "kd-tree leaves").
    float lo[kDim], hi[kDim];
    for (int d = 0; d < kDim; ++d) lo[d] = hi[d] = coord(*begin, d);
    for (const std::uint32_t *p = begin + 1; p != end; ++p)
        for (int d = 0; d < kDim; ++d) {
            lo[d] = std::min(lo[d], coord(*p, d));
            hi[d] = std::max(hi[d], coord(*p, d));
        }
    int dim = 0;
    for (int d = 1; d < kDim; ++d)
        if (hi[d] - lo[d] > hi[dim] - lo[dim]) dim = d;
    const std::size_t leaves = (count + kLeafPoints - 1) / kLeafPoints;
    const std::size_t left = (leaves + 1) / 2 * kLeafPoints;
    std::uint32_t *mid = begin + left;
    // (coordinate, index) is a total order, so which points go to which side depends on the data alone.
    std::nth_element(begin, mid, end, [&](std::uint32_t a, std::uint32_t b) {
        const float ca = coord(a, dim), cb = coord(b, dim);
        return ca < cb || (ca == cb && a < b);
    });
    float low_max = coord(*begin, dim);
    for (const std::uint32_t *p = begin + 1; p != mid; ++p) low_max = std::max(low_max, coord(*p, dim));
    const float high_min = coord(*mid, dim);

    build(begin, mid, points);
    const std::uint32_t high = build(mid, end, points);
    nodes_[id] = Node{low_max, high_min, high, static_cast<std::uint32_t>(dim)};
    return id;
}

void ProjectedKdTree::descend(Search &s) const {
    // Depth first, nearer child first, without recursion: the far children still worth a visit wait on a
    // stack with their lower bound and per-dimension gaps. Median splits keep the depth below 64 for any
    // 32-bit point count.
    struct Pending {
        std::uint32_t node;
        float bound;
        float gap2[kDim];
    };
    Pending stack[64];
    int top = 0;
    std::uint32_t n = 0;
    float gap2[kDim];
    for (int i = 0; i < kDim; ++i) gap2[i] = s.gap2[i];
    for (;;) {
        const Node *node = &nodes_[n];
        while (!(node->info & kLeafBit)) {
            const int d = static_cast<int>(node->info);
            const float q = s.query[d];
            const bool low_first = (q - node->low_max) + (q - node->high_min) < 0.0f;
            // The far child lies beyond its boundary along d: max(0, boundary - query) bounds every
            // coordinate difference there from below, also after rounding (subtraction rounds
            // monotonically), and the sum in dimension order bounds the rounded distances.
            float gap = low_first ? node->high_min - q : q - node->low_max;
            if (!(gap > 0.0f)) gap = 0.0f;
            Pending &far = stack[top];
            for (int i = 0; i < kDim; ++i) far.gap2[i] = gap2[i];
            far.gap2[d] = std::max(gap2[d], gap * gap);
            float bound = 0.0f;
            for (int i = 0; i < kDim; ++i) bound += far.gap2[i];
            far.bound = bound;
            far.node = low_first ? node->link : n + 1;
            if (bound <= s.limit) ++top;
            n = low_first ? n + 1 : node->link;
            node = &nodes_[n];
        }

        const std::size_t first = node->link, count = node->info & ~kLeafBit;
        const std::size_t blocks = (count + kLane - 1) / kLane;
        float dist[kLeafPoints];
        std::uint64_t hits =
            leaf_distances<kDim, kLane>(s.query, &blocks_[first * kDim * kLane], blocks, s.limit, dist);
        if (hits != 0) {
            const std::uint32_t *id = &index_[first * kLane];
            float limit = s.limit; // kept in a register between insertions
            // Slots in ascending order, each tested against the limit as it stands then (it only shrinks).
            while (hits != 0) {
                const std::size_t i = lowest_bit(hits);
                hits &= hits - 1;
                if (dist[i] <= limit) {
                    s.add(dist[i], id[i], static_cast<std::uint32_t>(first * kLane + i));
                    limit = s.limit;
                }
            }
        }

        do {
            if (top == 0) return;
            --top;
        } while (!(stack[top].bound <= s.limit));
        n = stack[top].node;
        for (int i = 0; i < kDim; ++i) gap2[i] = stack[top].gap2[i];
    }
}

int ProjectedKdTree::nearest(const float *query, int k, std::uint32_t *index, float *dist2, std::uint32_t *slot) const {
    if (nodes_.empty() || k < 1) return 0;
    Search s;
    s.k = std::min(k, kMaxK);
    s.limit = kNotFull;
    for (int d = 0; d < kDim; ++d) {
        const float q = query[d];
        s.query[d] = q;
        float gap = 0.0f;
        if (q < box_lo_[d])
            gap = box_lo_[d] - q;
        else if (q > box_hi_[d])
            gap = q - box_hi_[d];
        s.gap2[d] = gap * gap;
    }
    descend(s);
    // Insertion sort of at most kMaxK (key, slot) pairs; keys are distinct (they hold the index).
    for (int i = 1; i < s.count; ++i) {
        const std::uint64_t key = s.heap[i];
        const std::uint32_t at = s.slot[i];
        int j = i;
        for (; j > 0 && s.heap[j - 1] > key; --j) {
            s.heap[j] = s.heap[j - 1];
            s.slot[j] = s.slot[j - 1];
        }
        s.heap[j] = key;
        s.slot[j] = at;
    }
    for (int i = 0; i < s.count; ++i) {
        index[i] = static_cast<std::uint32_t>(s.heap[i]);
        const std::uint32_t bits = static_cast<std::uint32_t>(s.heap[i] >> 32);
        std::memcpy(&dist2[i], &bits, sizeof bits);
        if (slot) slot[i] = s.slot[i];
    }
    return s.count;
}

KISSM_DETAIL_END
