// SPDX-License-Identifier: MIT
// Stage 2c: FPFH descriptors (33 bins) of the keypoints: the SPFH sums over each point's neighbours and the
// FPFH weighted sums. The features of one pair (kBinsPerFeature, pair_feature_bins) are in pair_features.hpp.
#pragma once

#include "cloud.hpp"
#include "detail_namespace.hpp"
#include "pair_features.hpp"
#include "run_context.hpp"

KISSM_DETAIL_BEGIN

// SPFH (n x 33, row-major) of every point with a normal: the bins of its pairs with each neighbour that has a
// normal, each block scaled by 100 / (number of pairs with a frame); zero rows for points without a normal.
// Bitwise identical to evaluating every ordered pair with pair_feature_bins, for any thread count.
UninitVector<float> compute_spfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                                 RunContext &ctx);

// SPFH of every point with a normal (neighbours without a normal are skipped), then FPFH of each keypoint:
// its SPFH plus the mean of its neighbours' SPFH weighted by (voxel_size / distance)^weight_power, each 11-bin block
// rescaled to sum to 100. Distances are normalised by the voxel size so that descriptors do not depend on
// the unit of the coordinates.
Descriptors compute_fpfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                         std::vector<std::uint32_t> keypoints, float voxel_size, int weight_power, RunContext &ctx);

KISSM_DETAIL_END
