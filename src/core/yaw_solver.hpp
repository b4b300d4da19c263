// SPDX-License-Identifier: MIT
// Stage 5, 4-DoF variant: rotation about a known `up` axis (yaw) and a 3-D translation, for ground vehicles
// whose roll and pitch are near zero or removed beforehand (an IMU, or the caller pre-rotating both clouds so
// they share `up`). The method follows Quatro (Lim et al., ICRA 2022, "A Single Correspondence Is Enough"):
// the translation-invariant measurements (TIMs) of solve_pose, projected onto the plane perpendicular to `up`,
// give the angle in closed form by a 2-D weighted Procrustes, theta = atan2(sum w (a x b).up, sum w a.b); GNC-TLS
// (Yang et al., RA-L 2020) over that angle; then the translation as in solve_pose and a polish that keeps the
// rotation about `up`. One inlier TIM fixes the angle, so far fewer inliers are needed than for SO(3).
// Everything comes from the arguments: no statics, so two calls with different noise bounds are independent.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "gnc_solver.hpp"
#include "run_context.hpp"

KISSM_DETAIL_BEGIN

// The rotation by `angle` (radians, right-handed) about the unit `axis`, by Rodrigues' formula, so that
// R * axis == axis to rounding whatever the angle.
Eigen::Matrix3d rotation_about(const Eigen::Vector3d &axis, double angle);

// polish_pose restricted to rotations about `up`: the least-squares angle and translation on the inliers
// (centred, closed form), repeated while the inlier set grows or stays and changes; a step that would lose
// inliers is not taken. R is rebuilt by rotation_about, so it stays exactly about `up` (the caller's R is used
// only to find the first inliers). Returns the inlier count; `inlier` the mask. PoseSolver::polish (pose_solver.hpp)
// picks it in yaw mode.
std::size_t polish_pose_yaw(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                            const Eigen::Vector3d &up, Eigen::Matrix3d &R, Eigen::Vector3d &t,
                            std::vector<std::uint8_t> &inlier);

// Rotation exactly about `up` (unit; source and target already share it: the caller pre-rotates when the
// clouds' up directions differ), 3-D translation. Same inputs and output type as solve_pose. A TIM's vertical
// parts must agree within the bound too: under the zero roll/pitch model a difference there is an outlier.
// solved = false when fewer than 3 correspondences, `up` is zero or not finite, or fewer than 2 TIMs agree.
// The result depends only on the inputs' content, never on threads.
SolverOutput solve_pose_yaw(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                            std::vector<IndexPair> pairs, const Eigen::Vector3d &up, const SolverParams &params,
                            RunContext &ctx);

// How far the best unconstrained rotation on the yaw solution's inliers tilts `up`: the angle between R up and up,
// in radians, R being the centred Kabsch fit of the yaw inliers, grown as polish_pose grows an inlier set (under
// a real tilt the yaw inliers are a patch around the tilt axis; growing pins the tilt down). When the yaw model
// explains fewer than 3 correspondences (a large tilt, or no overlap) it runs solve_pose on the same input
// instead. Zero roll/pitch gives noise-level values; above kTiltThreshold the pair's relative roll/pitch is not
// zero and the yaw pose is wrong. NaN when nothing can be measured (up invalid, or neither model finds 3
// inliers). a, b, pairs, params: as given to solve_pose_yaw; yaw: what it returned.
double residual_tilt(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                     const std::vector<IndexPair> &pairs, const SolverOutput &yaw, const Eigen::Vector3d &up,
                     const SolverParams &params, RunContext &ctx);

// A scale for residual_tilt (1 degree), used by the tests. On synthetic LiDAR-like pairs (60 m wide, noise up to
// half the bound, 50-90% outliers) zero-tilt pairs measure at most 0.06 degrees and tilted pairs their true tilt
// within 0.06 degrees, from 0.5 to 30 (tests/core/test_yaw_solver.cpp). The pipeline refuses a pose whose tilt
// exceeds Params::max_rotation_uncertainty (2 degrees by default): real car pairs tilt by up to 1.4 degrees
// between keyframes (docs/reports/ground.md), and a yaw pose off by that much is still right.
constexpr double kTiltThreshold = 0.017453292519943295;

KISSM_DETAIL_END
