// SPDX-License-Identifier: MIT
// Stage 5's one interface: the pose from the pruned correspondences, by the full solver (gnc_solver.hpp: any
// rotation) or the yaw solver (yaw_solver.hpp: rotation about `up` only), as Params::rotation_dof says. Both
// solve on the max core and polish over every match the same way; only the rotation model differs.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "gnc_solver.hpp"
#include "params.hpp"
#include "run_context.hpp"

KISSM_DETAIL_BEGIN

struct PoseSolution {
    SolverOutput solver;
    // Yaw solver only: how far the best free rotation on its inliers turns `up` (yaw_solver.hpp's
    // residual_tilt), radians. NaN for the full solver, or when the yaw solver found no pose.
    double tilt;
};

class PoseSolver {
public:
    explicit PoseSolver(const Params &params);

    bool yaw_only() const { return yaw_only_; }
    std::size_t max_measurements() const { return params_.max_tims; }
    double noise_bound() const { return params_.noise_bound; }

    // The pose of the correspondences (a[k], b[k]) from the translation-invariant measurements `pairs` (empty =
    // strided_pairs()).
    PoseSolution solve(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                       std::vector<IndexPair> pairs, RunContext &ctx) const;

    // The least-squares polish of (R, t) over (a, b) in this solver's rotation model; returns the inlier count,
    // `inlier` the mask.
    std::size_t polish(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, Eigen::Matrix3d &R,
                       Eigen::Vector3d &t, std::vector<std::uint8_t> &inlier) const;

private:
    SolverParams params_;
    bool yaw_only_;
    Eigen::Vector3d up_;
};

KISSM_DETAIL_END
