// SPDX-License-Identifier: MIT
// Stage 5b: whether a solved pose can be trusted.
// Paper: Sec. III-E (\label{subsec:nonminimal_solver}): valid when the final inlier set I_final is large
// enough (no numbered equation). The test that the inliers span a volume is an addition of this library.
#pragma once

#include <Eigen/Core>
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
    Degenerate
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

KISSM_DETAIL_END
