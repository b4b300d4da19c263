// SPDX-License-Identifier: MIT
// Stage 3's search structure over one cloud's descriptors, built once with the cloud's features: a cloud
// described once (a map) is searched by every later registration without being indexed again, so matching a
// scan against it costs in proportion to the scan (docs/design/frames.md, "Scan-to-map cost").
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "descriptor_tree.hpp"
#include "detail_namespace.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"
#include "uninitialized.hpp"

KISSM_DETAIL_BEGIN

class KeypointGrid; // keypoint_grid.hpp

// A kd-tree in 33-D backtracks into near brute force; in a few dimensions it does not. The index keeps the
// descriptors projected on the kDim leading principal components of this cloud's own descriptors (so it is
// a function of this cloud alone), and a search re-ranks the projected candidates by exact 33-D distance.
struct DescriptorProjection {
    static constexpr int kDim = ProjectedKdTree::kDim;
    Eigen::Matrix<float, kDescriptorDim, 1> mean = Eigen::Matrix<float, kDescriptorDim, 1>::Zero();
    Eigen::Matrix<float, kDim, kDescriptorDim> basis = Eigen::Matrix<float, kDim, kDescriptorDim>::Zero();

    // `descriptor` (33 floats) in this projection's space (kDim floats).
    void apply(const float *descriptor, float *out) const;
};

// The nearest few of a query by exact 33-D distance, ties by the lower index, so that the answer is a function
// of the data alone.
class RankedNeighbours {
public:
    static constexpr int kMaxK = 4;
    explicit RankedNeighbours(int k) : k_(k) {}
    void add(float dist, std::uint32_t index);
    int found() const { return count_; }
    std::uint32_t index(int i) const { return index_[i]; }
    float dist(int i) const { return dist_[i]; }

private:
    int k_, count_ = 0;
    std::uint32_t index_[kMaxK] = {};
    float dist_[kMaxK] = {};
};

// Squared 33-D distance, summed in dimension order.
float descriptor_dist2(const float *a, const float *b);

class DescriptorIndex {
public:
    // A search takes the kCandidates nearest in the projection and re-ranks them by exact 33-D distance, which
    // keeps the exact search's success rate (docs/parameters.md, "Descriptor matching": instructions and
    // successes per projection size).
    static constexpr int kCandidates = 16;

    DescriptorIndex() = default;

    bool empty() const { return !tree_; }
    const DescriptorProjection &projection() const { return projection_; }
    const ProjectedKdTree &tree() const { return *tree_; }
    // The descriptor in tree slot `slot` (33 floats); laid out by slot so that a search's candidates, which
    // sit in a few neighbouring leaves, are read from neighbouring memory.
    const float *slot_descriptor(std::size_t slot) const { return &by_slot_[slot * kDescriptorDim]; }
    std::size_t bytes() const; // heap memory held (the tree, itself on the heap, whole)

    // The k (at most RankedNeighbours::kMaxK) nearest of `query` (33 floats, from any cloud) by exact distance,
    // among the kCandidates nearest in this index's projection; indexes are keypoint indexes of this cloud.
    RankedNeighbours nearest(const float *query, int k) const;

    // Indexes of several clouds' descriptors (empty descriptors give an empty index). The principal axes and
    // projections use every thread; the trees, one thread each, are built side by side.
    static std::vector<DescriptorIndex> build(const std::vector<const Descriptors *> &clouds, RunContext &ctx);

private:
    DescriptorProjection projection_;
    std::unique_ptr<const ProjectedKdTree> tree_;
    UninitVector<float> by_slot_;
};

// A cloud's descriptors with their index (DescriptorIndex::build of those descriptors), its voxels (which
// descriptors->keypoint indexes) and the grid of its keypoints, all borrowed. Without points (and, on the
// larger side, the grid), no place is ever singled out.
struct IndexedDescriptors {
    const Descriptors *descriptors;
    const DescriptorIndex *index;
    const std::vector<Vec3f> *points = nullptr;
    const KeypointGrid *grid = nullptr;
};

KISSM_DETAIL_END
