// SPDX-License-Identifier: MIT
// A cloud's global signature: a fixed-length summary of its described keypoints for telling which scans see the
// same place (loop candidates among thousands of scans), compared by Euclidean distance. Built from what the
// features keep (and serialise), so described, loaded and rotated copies of a cloud agree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// Three blocks, each scaled to unit length (all zero for a cloud without keypoints) so that none outweighs the
// others: the mean of the keypoints' FPFH, its standard deviation per bin, and the square roots of the shares of
// keypoints per band of distance from their centroid (kSignatureRingVoxels voxels wide, the last band open).
// The descriptors say what kinds of surfaces the scan holds, the rings how they are spread around it; both are
// independent of the cloud's frame. The choice among the variants tried: docs/multiway.md, "Loop candidates by
// similarity".
constexpr std::size_t kSignatureRings = 16;
constexpr double kSignatureRingVoxels = 12.0;
constexpr std::size_t kSignatureSize = 2 * static_cast<std::size_t>(kDescriptorDim) + kSignatureRings;

// Writes kSignatureSize numbers to `out`. `points` are the voxels (metres, any frame), `keypoint` indexes them,
// `descriptors` holds kDescriptorDim values per keypoint. Sums run over the keypoints in their order, in double,
// on one thread: the same features give the same bits.
void cloud_signature(const std::vector<Vec3f> &points, const std::vector<std::uint32_t> &keypoint,
                     const float *descriptors, double voxel_size, double *out);

KISSM_DETAIL_END
