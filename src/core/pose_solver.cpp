// SPDX-License-Identifier: MIT
#include "pose_solver.hpp"

#include <limits>
#include <utility>

#include "yaw_solver.hpp"

KISSM_DETAIL_BEGIN

PoseSolver::PoseSolver(const Params &params)
    : yaw_only_(params.rotation_dof == 1), up_(params.up[0], params.up[1], params.up[2]) {
    params_.noise_bound = params.solver_noise_bound();
}

PoseSolution PoseSolver::solve(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                               std::vector<IndexPair> pairs, RunContext &ctx) const {
    PoseSolution out{SolverOutput{}, std::numeric_limits<double>::quiet_NaN()};
    if (!yaw_only_) {
        out.solver = solve_pose(a, b, std::move(pairs), params_, ctx);
        return out;
    }
    out.solver = solve_pose_yaw(a, b, pairs, up_, params_, ctx);
    // The tilt check is what keeps a tilted pair from a wrong yaw pose (validity.hpp, yaw_pose_refuted).
    if (out.solver.solved) out.tilt = residual_tilt(a, b, pairs, out.solver, up_, params_, ctx);
    return out;
}

std::size_t PoseSolver::polish(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                               Eigen::Matrix3d &R, Eigen::Vector3d &t, std::vector<std::uint8_t> &inlier) const {
    return yaw_only_ ? polish_pose_yaw(a, b, params_.noise_bound, up_, R, t, inlier)
                     : polish_pose(a, b, params_.noise_bound, R, t, inlier);
}

KISSM_DETAIL_END
