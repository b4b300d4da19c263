// SPDX-License-Identifier: MIT
// The nearest voxel of a cloud to a 3-D query within a distance bound: refinement's correspondence search and
// the aligned overlap (stage 6). Built once per target cloud; features built for refinement keep it, so a map
// is indexed once and matched against many scans.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "cloud.hpp"
#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// A 3-D kd-tree over a cloud's voxel points (local frame), for one-nearest queries within a radius. Exact and
// a function of the data alone: the nearest point, ties broken by the lower index, whatever the traversal
// order; so results never depend on threads. Leaves hold up to kLeafPoints points contiguously (x, y, z as
// separate rows) so the distance loop vectorises; nodes are a flat array in depth-first order.
class PointIndex {
public:
    static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

    PointIndex() = default;
    explicit PointIndex(const std::vector<Vec3f> &points);

    bool empty() const { return index_.empty(); }
    std::size_t size() const { return index_.size(); }

    // The index of the point nearest to q with squared distance <= max_dist2 (ties: the lower index), or kNone.
    // *dist2 receives its squared distance (float, computed as (x-qx)^2 + (y-qy)^2 + (z-qz)^2 in that order).
    std::uint32_t nearest(const Vec3f &q, float max_dist2, float *dist2) const;

    // Bytes held (for the features' memory accounting in docs).
    std::size_t bytes() const;

private:
    static constexpr int kLeafPoints = 16;
    struct Node {
        float split;        // internal: the splitting coordinate (low child <= split <= high child)
        std::uint32_t link; // internal: index of the high child (the low child follows its parent); leaf: first slot
        std::uint32_t info; // internal: dim; leaf: kLeafBit | number of points
    };
    static constexpr std::uint32_t kLeafBit = 0x80000000u;

    std::uint32_t build(std::uint32_t *begin, std::uint32_t *end, const std::vector<Vec3f> &points);

    std::vector<Node> nodes_;
    std::vector<float> xs_, ys_, zs_;  // by slot
    std::vector<std::uint32_t> index_; // by slot: the point's original index
};

KISSM_DETAIL_END
