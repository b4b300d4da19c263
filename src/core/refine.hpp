// SPDX-License-Identifier: MIT
// Stage 6: fine registration of the voxelised clouds from a pose (the solver's, or the caller's prior), the
// paper's "Proposed + G-ICP" row (Sec. IV, Table of KITTI results) done in the same call.
//
// Correspondences: each source voxel, moved by the current pose, to its nearest target voxel within
// max_distance (RefineIndex), both with a normal. Cost (Segal et al., "Generalized-ICP", RSS 2009):
//   GICP:            r^2 = e^T (C_b + R C_a R^T)^-1 e,   e = b - (R a + t),
//   point-to-plane:  r^2 = (n_b . e)^2,
// where C = (n n^T + (I - n n^T) / eps) / 2 is the plane-regularised covariance of a voxel with normal n
// (eps = 1e-3, as in the GICP paper), scaled so that for agreeing normals r is the distance to the plane in
// metres in both modes. The normals are the planes the features stage fits in its normals' pass (radius
// refine_normal_radius_gain * v, a subset of the same neighbours): no second neighbour search. Robust kernel: Cauchy
// weights w = 1 / (1 + r^2 / k^2) recomputed at every iteration (IRLS). Each iteration solves the weighted Gauss-Newton
// system with Levenberg-Marquardt damping (the step is kept only when it lowers the weighted cost of the iteration's
// correspondences; otherwise the damping grows tenfold, up to 10 tries). Converged when a kept step turns
// the pose by less than rotation_epsilon radians and moves it by less than translation_epsilon metres.
//
// Sums over correspondences run in fixed chunks added in chunk order (RunContext::map_fold), so the result is
// the same for any thread count.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "params.hpp"
#include "refine_index.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

struct RefineParams {
    RefineMode mode = RefineMode::Gicp;
    int max_iterations = 30;
    double max_distance = 1.0;         // metres: correspondence gate and the overlap's distance
    double kernel_scale = 0.3;         // metres: Cauchy k
    double rotation_epsilon = 1e-4;    // radians
    double translation_epsilon = 1e-3; // metres
};

// One cloud as refinement reads it: voxel points and normals in its local frame.
struct RefineCloud {
    const std::vector<Vec3f> *points = nullptr;
    const Normals *normals = nullptr;
};

struct RefineOutput {
    // Local frames: p_target_local = rotation * p_source_local + translation.
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    int iterations = 0;
    bool converged = false;
    std::size_t num_correspondences = 0; // at the final pose
    // The numbers below are those of the point-to-plane term at the final pose, whichever cost was minimised
    // (GICP's along-plane weights are its regularisation, not information).
    double weight_sum = 0.0;      // sum of the Cauchy weights
    double rmse = 0.0;            // sqrt(sum w r^2 / sum w): the weighted RMS distance to the target's planes, metres
    double residual_median = 0.0; // median |r| over the correspondences, unweighted, metres
    double overlap = 0.0;         // share of source voxels with a target voxel within max_distance
    // How well the correspondences pin the pose down in its weakest direction: the smallest over the largest
    // eigenvalue of the information with rotations turned into displacements at the matched points' RMS
    // radius about their centroid (1 = every direction alike, 0 = a direction the data leaves free).
    double condition = 0.0;
    // The eigen-directions behind `condition`, weakest first: column i is a perturbation xi_local of the pose
    // (rotation, translation; see `hessian`) whose scaled information is direction_ratio[i] times the strongest
    // direction's. Ratios in [0, 1]; with no correspondence every ratio is 0 and the columns span everything.
    Matrix6d directions = Matrix6d::Identity();
    Vector6d direction_ratio = Vector6d::Zero();
    // Standard deviation of the matched source voxels along their principal axis (metres): how far the aligned
    // overlap extends, against which the solver's inliers are measured (validity.hpp, inlier coverage).
    double overlap_spread = 0.0;
    // Gauss-Newton information sum w J^T n n^T J at the final pose, for the right perturbation
    // T exp(xi), xi = (rotation, translation), in the source's local frame; not yet scaled by the residual
    // variance (information_in_caller_frame does that).
    Matrix6d hessian = Matrix6d::Zero();
};

// Refines (R0, t0) (local frames). `target_index` indexes target.points. Needs nothing but the clouds: a
// source with no normal anywhere simply finds no correspondence.
RefineOutput refine_pose(const RefineCloud &source, const RefineCloud &target, const RefineIndex &target_index,
                         const Eigen::Matrix3d &R0, const Eigen::Vector3d &t0, const RefineParams &params,
                         RunContext &ctx);

// The variance the reported information is scaled by, so that its NEES means what it says (docs/design/accuracy.md,
// "A calibrated information matrix"): kResidualShare times the square of the residuals' robust spread,
// 1.4826 * median |r|, floored at (1e-3 * floor_length)^2 (a perfect fit is not infinitely certain). The median reads
// the bulk of the surfaces, which is what moves the pose; the RMS is ruled by a few voxels on edges and corners whose
// pulls cancel, and reads a clean room 4x too uncertain while it reads KITTI's keyframes 3x too confident.
// kResidualShare counts each residual as a twelfth of an independent measurement (neighbouring voxels share their
// points' neighbourhoods, planes and the scanner's systematic error); measured feasible from 7.2 to 18.8 on every real
// and simulated set, and taken near the middle of that range.
constexpr double kResidualShare = 12.0;
double calibrated_variance(const RefineOutput &out, double floor_length);

// The information matrix of the pose in the callers' frames, rotation then translation, for the right
// perturbation T exp(xi) (GTSAM's Pose3 convention; g2o's with its blocks swapped): the Gauss-Newton
// information of refine_pose moved from the source's local frame (origin `source_origin` in the caller's
// frame) and divided by `variance` (calibrated_variance).
Matrix6d information_in_caller_frame(const RefineOutput &out, const Eigen::Vector3d &source_origin, double variance);

// The directions the data leave free (degeneracy): out.directions whose ratio is below min_condition, weakest
// first, moved to the callers' frame as the information is (the perturbation xi = (rotation [rad], translation
// [m]) of T exp(xi) in the source's frame) and scaled to unit length; each with its largest component positive,
// so the sign is defined. Empty when every direction's ratio reaches min_condition. Ratios are of the
// information with rotations as displacements at the matched points' RMS radius about their centroid, so the
// threshold is one number for every scene size.
std::vector<Vector6d> weak_directions_in_caller_frame(const RefineOutput &out, const Eigen::Vector3d &source_origin,
                                                      double min_condition);

KISSM_DETAIL_END
