// SPDX-License-Identifier: MIT
// Stage 3's search structure over one cloud's descriptors, built once with the cloud's features: a cloud
// described once (a map) is searched by every later registration without being indexed again, so matching a
// scan against it costs in proportion to the scan (docs/frames.md, "Scan-to-map cost").
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "cloud.hpp"
#include "detail_namespace.hpp"
#include "kdtree.hpp"
#include "run_context.hpp"
#include "uninitialized.hpp"

KISSM_DETAIL_BEGIN

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

class DescriptorIndex {
public:
    DescriptorIndex() = default;

    bool empty() const { return !tree_; }
    const DescriptorProjection &projection() const { return projection_; }
    const ProjectedKdTree &tree() const { return *tree_; }
    // The descriptor in tree slot `slot` (33 floats); laid out by slot so that a search's candidates, which
    // sit in a few neighbouring leaves, are read from neighbouring memory.
    const float *slot_descriptor(std::size_t slot) const { return &by_slot_[slot * kDescriptorDim]; }
    std::size_t bytes() const; // heap memory held (the tree, itself on the heap, whole)

    // Indexes of several clouds' descriptors (empty descriptors give an empty index). The principal axes and
    // projections use every thread; the trees, one thread each, are built side by side.
    static std::vector<DescriptorIndex> build(const std::vector<const Descriptors *> &clouds, RunContext &ctx);

private:
    DescriptorProjection projection_;
    std::unique_ptr<const ProjectedKdTree> tree_;
    UninitVector<float> by_slot_;
};

KISSM_DETAIL_END
