// SPDX-License-Identifier: MIT
// Stage 2c: FPFH descriptors (33 bins) of the keypoints: the SPFH sums over each point's neighbours and the
// FPFH weighted sums. The features of one pair (kBinsPerFeature, pair_feature_bins) are in pair_features.hpp.
// Paper: Sec. III-C (\label{subsec:fpfh}); SPFH is its Eq. (A4) (\label{eqn:each_of_spfh}), FPFH its
// Eq. (A5) (\label{eqn:fpfh}). Deviations are noted at compute_spfh and compute_fpfh.
#pragma once

#include "detail_namespace.hpp"
#include "pair_features.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// SPFH (n x 33, row-major) of every point with a normal: the bins of its pairs with each neighbour that has a
// normal, each block scaled by 100 / (number of pairs with a frame); zero rows for points without a normal.
// Paper Eq. (A4) divides by |I_valid| instead, which counts the point itself and pairs without a frame that
// add no bin; dividing by the pairs counted makes every block sum to exactly 100.
// Bitwise identical to evaluating every ordered pair with pair_feature_bins, for any thread count.
UninitVector<float> compute_spfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                                 NormalSigns signs, RunContext &ctx);

// SPFH of every point with a normal (neighbours without a normal are skipped), then FPFH of each keypoint:
// its SPFH plus the mean of its neighbours' SPFH weighted by (voxel_size / distance)^weight_power, each 11-bin block
// rescaled to sum to 100. Distances are normalised by the voxel size so that descriptors do not depend on
// the unit of the coordinates. Paper Eq. (A5) with deviations: the weight 1/omega_k there is 1/distance
// (weight_power 1 up to the factor v; the pipeline uses 2, see pipeline.cpp), the mean runs over the
// neighbours other than the point itself, and the paper does not rescale the blocks afterwards.
Descriptors compute_fpfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                         NormalSigns signs, std::vector<std::uint32_t> keypoints, float voxel_size, int weight_power,
                         RunContext &ctx);

KISSM_DETAIL_END
