// SPDX-License-Identifier: MIT
// Exact k-nearest-neighbour search over the 6-D projected descriptors (stage 3's candidate search).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// A kd-tree built for this one job: low dimension, a few dozen thousand to a few million points, k <= 16.
// Leaves hold their points contiguously in blocks of kLane as structure of arrays, so a leaf is scanned by
// loops the compiler turns into SSE2 code; the tree itself is a flat array in depth-first order.
//
// The answer is exact and a function of the data alone: the k smallest (squared distance, index) pairs,
// where the squared distance is the float sum of (query[d] - point[d])^2 taken in dimension order 0..kDim-1
// (the same value nanoflann's L2_Simple_Adaptor computes, so both give the same neighbours). Subtrees are
// pruned with a lower bound built from the same differences in the same order, which rounding can never
// push above a point's computed distance, so no tie is ever lost.
class ProjectedKdTree {
public:
    static constexpr int kDim = 6;
    static constexpr int kMaxK = 16;

    // Copies `points` (n * kDim floats, row-major). Points with a non-finite coordinate are left out: their
    // distance is never finite, so they could never be returned.
    ProjectedKdTree(const float *points, std::size_t n);

    // Writes the min(k, finite points) nearest to `query` in ascending (squared distance, index) order and
    // returns how many. k must be in [1, kMaxK]. A distance that overflows to infinity never counts as found.
    // `slot`, when given, receives each neighbour's slot (see below).
    int nearest(const float *query, int k, std::uint32_t *index, float *dist2, std::uint32_t *slot = nullptr) const;

    // The tree keeps its points in slots, leaf after leaf in depth-first order: points close together in
    // space are close together in slot order, so data a caller lays out by slot (and queries it visits in
    // slot order) is read from neighbouring memory. A few slots at leaf ends are padding.
    static constexpr std::uint32_t kNoPoint = 0xFFFFFFFFu;
    std::size_t num_slots() const { return index_.size(); }
    // The original index of the point in `slot`, or kNoPoint for padding.
    std::uint32_t slot_index(std::size_t slot) const { return index_[slot]; }
    // The coordinates of the point in `slot` (bit for bit those given to the constructor).
    void slot_point(std::size_t slot, float *out) const {
        const float *block = &blocks_[slot / kLane * kDim * kLane + slot % kLane];
        for (int d = 0; d < kDim; ++d) out[d] = block[d * kLane];
    }
    // Memory held, in bytes: the object and its arrays.
    std::size_t bytes() const {
        return sizeof(*this) + nodes_.capacity() * sizeof(Node) + blocks_.capacity() * sizeof(float) +
               index_.capacity() * sizeof(std::uint32_t);
    }

private:
    static constexpr int kLane = 4; // points per block: one SSE2 register per dimension
    // Points per leaf (a multiple of kLane); every leaf is full but the last. 48 was as fast as 24 or 32 on
    // small clouds and the fastest on large ones (docs/parameters.md, "Candidate search", the timings per
    // leaf size).
    static constexpr int kLeafPoints = 48;
    static_assert(kLeafPoints % kLane == 0 && kLeafPoints <= 64, "a leaf's hits fit one 64-bit mask");

    struct Node {
        float low_max;      // internal: largest coordinate of the low child along `dim`
        float high_min;     // internal: smallest coordinate of the high child along `dim`
        std::uint32_t link; // internal: index of the high child (the low child follows its parent); leaf: first block
        std::uint32_t info; // internal: dim; leaf: kLeafBit | number of points
    };
    static constexpr std::uint32_t kLeafBit = 0x80000000u;

    struct Search;

    std::uint32_t build(std::uint32_t *begin, std::uint32_t *end, const float *points);
    void descend(Search &s) const;

    std::vector<Node> nodes_;
    std::vector<float> blocks_;        // per block: kDim rows of kLane coordinates
    std::vector<std::uint32_t> index_; // per block: kLane original indices (kNoPoint for padding)
    float box_lo_[kDim] = {}, box_hi_[kDim] = {};
};

KISSM_DETAIL_END
