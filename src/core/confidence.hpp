// SPDX-License-Identifier: MIT
// kissm_result.confidence: the probability that a pose is within the success tolerance (5 degrees, and 2 m for
// LiDAR, 0.3 m indoors, 1 cm on the bunny: about 4 to 7 voxels at the suggested sizes), a fixed logistic function
// of numbers the result carries. Not in the paper: an addition of this library (issue 33, part 4).
#pragma once

#include <cstdint>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

struct ConfidenceInput {
    bool has_pose = false;           // a pose was estimated (by the solver, or refined from a prior)
    bool solver = false;             // by the global solver (inliers and ambiguity are set)
    bool refined = false;            // refinement ran (overlap and rmse are set)
    std::uint64_t inliers = 0;       // the solver's final inliers
    double ambiguity = 0.0;          // ambiguity.hpp
    double overlap = 0.0;            // the refined overlap
    double refine_rmse_voxels = 0.0; // refine_rmse over the voxel size
};

// 0 without a pose; else a logistic model of the evidence, by kind of result, rising with the evidence for the pose
// (docs/design/accuracy.md, "Confidence"; fitted by bench/confidence_fit.py):
//   registered:             ln(1 + inliers);
//   registered and refined: ln(1 + inliers), the overlap and refine_rmse in voxels, at most 10 (falling);
//   refined from a prior:   the overlap, and refine_rmse in voxels, at most 10 (falling);
// and for a registration times a factor falling with the ambiguity: 1 up to 0.6, from 0.8 on the share of right
// poses among the study's runs of its kind that ambiguous (a pick among equals), linear between. NaN inputs count
// as the worst.
// It reads none of the caller's thresholds (a degeneracy flag, set by min_refine_condition, would make it one), and
// not the inliers' coverage (its fitted weight came out negative: repetitive scenes' wrong poses cover as much).
double pose_confidence(const ConfidenceInput &in);

KISSM_DETAIL_END
