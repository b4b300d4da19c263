// SPDX-License-Identifier: MIT
// Stage 5b: whether a solved pose can be trusted.
// Paper: Sec. III-E (\label{subsec:nonminimal_solver}): valid when the final inlier set I_final is large
// enough (no numbered equation). The test that the inliers span a volume is an addition of this library.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

enum class Reason {
    None = 0,
    TooFewVoxels,
    TooFewFeatures,
    TooFewCorrespondences,
    SolverFailed,
    TooFewInliers,
    Degenerate,
    LowOverlap,
    Unconstrained,
};

struct Validity {
    Reason reason = Reason::None;
    Eigen::Vector3d extent = Eigen::Vector3d::Zero(); // sqrt of the inliers' covariance eigenvalues, descending
};

// Valid when there are at least min_inliers inliers and they span a volume: a collinear or planar inlier set
// (second or third extent below the noise bound) pins the pose down only up to a rotation or reflection
// that the data cannot see.
Validity check_validity(const std::vector<Eigen::Vector3d> &inlier_points, std::size_t min_inliers, double noise_bound,
                        const Eigen::Matrix3d &rotation, const Eigen::Vector3d &translation);

// What refinement (stage 6) found, as the refined rule reads it.
struct RefinedEvidence {
    std::uint64_t num_final_inliers = 0;   // the solver's (0 for a refinement from the caller's pose)
    std::uint64_t num_correspondences = 0; // refinement's, at the final pose
    double overlap = 0.0;                  // share of source voxels with a target voxel within the distance
    double rmse = 0.0;                     // metres
    double condition = 0.0;                // see RefineOutput::condition
    bool converged = false;
};

struct RefinedRule {
    double min_overlap;
    double min_condition;
};

// The rule with refinement: the coarse reason (None for a refinement from the caller's pose) unless the
// refined evidence overrules it, then the overlap and the conditioning of the refined pose.
Reason check_refined_validity(Reason coarse, const RefinedEvidence &e, const RefinedRule &rule);

KISSM_DETAIL_END
