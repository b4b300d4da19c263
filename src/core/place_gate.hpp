// SPDX-License-Identifier: MIT
// Stage 3, before the matching: the place in a map a scan is most likely in. Not in the paper, whose map-level
// registration (Sec. V-C) matches against the whole map. A scan's nearest descriptor in a city-sized map is ever
// more often some other place's look-alike (docs/design/frames.md, "Scan-to-map cost"), so against a much larger cloud
// a sample of the scan's keypoints vote with their nearest map descriptors for the map cells those lie in; when
// one window of cells the size of the scan wins clearly, the whole scan matches only the map's keypoints around
// it, which it then matches as well as it matches a map of its own size.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "descriptor_index.hpp"
#include "descriptor_tree.hpp"
#include "detail_namespace.hpp"
#include "keypoint_grid.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// The keypoints of a map in the place a scan's votes single out, with a search tree of their own in the map's
// projection (so a search in the region finds what the map's index would, were the rest of the map absent).
class PlaceRegion {
public:
    PlaceRegion() = default;

    // Empty (search the whole map) unless `map` has at least kMinSizeRatio times the keypoints of `scan`, the
    // winning window has at least kMinMargin times the votes of the best window sharing no cell with it, and
    // the region holds at most half of the map's keypoints. A function of the data alone (never of threads).
    static PlaceRegion find(const IndexedDescriptors &scan, const IndexedDescriptors &map, RunContext &ctx);

    bool empty() const { return keypoints_.empty(); }
    std::size_t size() const { return keypoints_.size(); }
    const std::vector<std::uint32_t> &keypoints() const { return keypoints_; } // map keypoint indexes, ascending

    // As DescriptorIndex::nearest of the map's index, among the region's keypoints only.
    RankedNeighbours nearest(const float *query, int k) const;

    static constexpr std::size_t kMinSizeRatio = 2;
    static constexpr double kMinMargin = 2.0;

private:
    const Descriptors *descriptors_ = nullptr;
    const DescriptorProjection *projection_ = nullptr;
    std::vector<std::uint32_t> keypoints_;
    std::unique_ptr<const ProjectedKdTree> tree_;
};

KISSM_DETAIL_END
