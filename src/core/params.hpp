// SPDX-License-Identifier: MIT
// Plain C++ mirror of kissm_config, as the pipeline sees it (already validated at the boundary).
// Defaults as in the paper's Sec. IV-B ("Parameters of KISS-Matcher"): r_normal = 3.5 v, r_FPFH = 5.0 v,
// tau_num = 3, tau_lin = 0.99. Not the paper's: the pruning bound (beta = 1.5 v there) and N_tau (3000
// there); docs/parameters.md has the evidence for every default.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

enum class NonFinitePolicy { Reject, Drop };
// SignFree: descriptors blind to the normals' signs (pair_features.hpp, NormalSigns). Local: each normal turned
// away from its neighbourhood's centroid (normals.hpp). Neither depends on the cloud's frame.
enum class ViewpointMode { Fixed, CloudCenter, SignFree, Local };
// Stage 6 (refine.hpp): none, GICP (plane-to-plane) or point-to-plane.
enum class RefineMode { None, Gicp, PointToPlane };
// Before keypoints (ground.hpp): nothing, or the ground voxels around the sensor.
enum class Suppression { None, Ground };

struct Params {
    int num_threads = 0; // 0 = hardware concurrency
    double voxel_size = 0.3;
    double normal_radius_gain = 3.5;
    double fpfh_radius_gain = 5.0;
    double max_linearity = 0.99;
    double ratio_test = 0.9;
    double prune_noise_bound_gain = 1.0;
    double solver_noise_bound_gain = 0.75;
    double noise_bound_max = 0.0; // 0 = no cap
    std::array<double, 3> viewpoint{{0.0, 0.0, 0.0}};
    int min_normal_neighbors = 3;
    int max_correspondences = 0; // 0 = automatic: grows with the keypoints (matching.hpp)
    int min_inliers = 15;
    NonFinitePolicy nonfinite = NonFinitePolicy::Reject;
    ViewpointMode viewpoint_mode = ViewpointMode::Local; // no frame dependence (docs/design/frames.md)
    RefineMode refine_mode = RefineMode::None;
    int refine_max_iterations = 30;
    double refine_max_distance_gain = 3.0;
    double refine_kernel_gain = 1.0;
    double refine_normal_radius_gain = 2.0;        // the planes refinement aligns, from neighbours within gain * v
    double refine_rotation_epsilon = 5e-4;         // radians
    double refine_translation_epsilon_gain = 5e-3; // times voxel_size
    double max_rotation_uncertainty = 0.03490658503988659; // radians (2 degrees): validity without refinement
    int refine_min_inliers = 10;                           // validity with refinement
    double min_overlap = 0.2;                              // validity with refinement
    double min_inlier_coverage = 0.25;                     // validity with refinement
    double min_refine_condition = 0.01;                    // validity with refinement
    Suppression suppression = Suppression::None;
    int rotation_dof = 3;                      // 3, or 1: yaw about `up` only (yaw_solver.hpp)
    std::array<double, 3> up{{0.0, 0.0, 1.0}}; // in each cloud's own frame; normalised at the boundary
    double sensor_height = 0.0;                // metres above the ground; 0 = estimate
    double max_refine_rmse_gain = 0.45;        // validity with refinement: refine_rmse <= gain * voxel_size
    double max_ambiguity = 0.7;                // validity: the best distinct competitor's share of the support
    int allow_degenerate = 0;                  // 1: a degenerate refined pose may be valid (flagged)

    double normal_radius() const { return normal_radius_gain * voxel_size; }
    double fpfh_radius() const { return fpfh_radius_gain * voxel_size; }
    double prune_noise_bound() const { return capped(prune_noise_bound_gain * voxel_size); }
    double solver_noise_bound() const { return capped(solver_noise_bound_gain * voxel_size); }
    double refine_max_distance() const { return refine_max_distance_gain * voxel_size; }
    double max_refine_rmse() const { return max_refine_rmse_gain * voxel_size; }
    // Within the descriptors' normal radius: the planes are fitted to a subset of the same neighbours.
    double refine_normal_radius() const { return std::min(refine_normal_radius_gain, normal_radius_gain) * voxel_size; }

private:
    double capped(double b) const { return (noise_bound_max > 0.0 && b > noise_bound_max) ? noise_bound_max : b; }
};

KISSM_DETAIL_END
