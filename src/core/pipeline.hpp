// SPDX-License-Identifier: MIT
// The whole registration: stages wired together, with counts and per-stage times.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "descriptor_index.hpp"
#include "detail_namespace.hpp"
#include "keypoint_grid.hpp"
#include "params.hpp"
#include "refine.hpp"
#include "refine_index.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"
#include "validity.hpp"

KISSM_DETAIL_BEGIN

// A cloud described once: voxels (local frame), their normals, keypoint descriptors with their search index
// and, when it was described for refinement, the index of its voxels (so a map is indexed once). Immutable
// after construction.
struct CloudFeatures {
    Params params; // the config it was computed under (descriptor-relevant fields are compared on use)
    std::uint64_t num_points = 0;
    std::uint64_t num_nonfinite = 0;
    VoxelCloud voxels;
    Normals normals;         // per voxel (the descriptors'); all invalid when the cloud had too few voxels
    Normals plane_normals;   // per voxel, within refine_normal_radius: the planes refinement aligns (has_planes)
    bool has_planes = false; // described for refinement; else refinement fits the planes on its call
    Descriptors descriptors;
    DescriptorIndex descriptor_index; // empty when there are no descriptors
    KeypointGrid keypoint_grid;       // the keypoints by position (columns of kKeypointColumnVoxels voxels)
    RefineIndex index;                // empty unless params.refine_mode != None
    std::uint64_t num_suppressed = 0; // voxels suppression kept from becoming keypoints
    double time_voxelize_ms = 0.0;
    double time_features_ms = 0.0;
    double time_suppression_ms = 0.0; // part of time_features_ms
};

struct Registration {
    bool solved = false;
    Reason reason = Reason::None;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
    Eigen::Vector3d translation = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    std::uint64_t num_source_points = 0, num_target_points = 0;
    std::uint64_t num_source_nonfinite = 0, num_target_nonfinite = 0;
    std::uint64_t num_source_voxels = 0, num_target_voxels = 0;
    std::uint64_t num_source_keypoints = 0, num_target_keypoints = 0;
    std::uint64_t num_initial_correspondences = 0, num_pruned_correspondences = 0;
    std::uint64_t num_rotation_inliers = 0, num_final_inliers = 0, max_core_number = 0;
    double inlier_ratio = 0.0;
    double residual_rms = std::numeric_limits<double>::quiet_NaN();
    double noise_bound = 0.0;
    Eigen::Vector3d inlier_extent = Eigen::Vector3d::Zero();
    // The solver's pose (NaN when none); rotation/translation above become the refined pose when refinement ran.
    Eigen::Matrix3d coarse_rotation = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
    Eigen::Vector3d coarse_translation = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    // Stage 6 (NaN / 0 when it did not run).
    bool refined = false;
    Matrix6d information = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
    double overlap = std::numeric_limits<double>::quiet_NaN();
    double refine_rmse = std::numeric_limits<double>::quiet_NaN();
    int refine_iterations = 0;
    bool refine_converged = false;
    std::uint64_t num_refine_correspondences = 0;
    double refine_condition = std::numeric_limits<double>::quiet_NaN(); // see refine.hpp
    // Degeneracy: refine_condition below min_refine_condition; weak_directions as
    // weak_directions_in_caller_frame gives them (empty unless degenerate; refinement only).
    bool degenerate = false;
    std::vector<Vector6d> weak_directions;
    double rotation_uncertainty = std::numeric_limits<double>::quiet_NaN(); // radians, see validity.hpp
    double ambiguity = std::numeric_limits<double>::quiet_NaN();            // see ambiguity.hpp (solver only)
    double confidence = 0.0;                                                // confidence.hpp; 0 without a pose
    double inlier_coverage = std::numeric_limits<double>::quiet_NaN();      // see validity.hpp
    double overlap_spread = std::numeric_limits<double>::quiet_NaN();       // metres, of the refined overlap
    // Suppression (ground.hpp) and the yaw-only solver (NaN unless rotation_dof = 1 solved).
    std::uint64_t num_source_suppressed = 0, num_target_suppressed = 0;
    double tilt = std::numeric_limits<double>::quiet_NaN(); // radians, see yaw_solver.hpp
    double voxel_size_used = 0.0; // the voxel the clouds were described with (the suggestion's under voxel_size 0)
    double time_voxelize_ms = 0, time_features_ms = 0, time_matching_ms = 0, time_pruning_ms = 0, time_solver_ms = 0,
           time_refine_ms = 0, time_suppression_ms = 0;
};

// The keypoint grid's column side, in voxels: a KITTI scan's place-gate box (about 300 m at 0.5 m voxels) spans
// about 20 columns each way, and a column holds a few dozen keypoints.
constexpr double kKeypointColumnVoxels = 32.0;

// The keypoint grid of `f` (its voxels and keypoints), as describe_cloud and the features loader build it.
KeypointGrid keypoint_grid_of(const CloudFeatures &f);

// Heap memory held by the features, in bytes (the struct itself not included).
std::size_t features_bytes(const CloudFeatures &f);

// Throws Failure for unacceptable input (empty, too few points, non-finite under Reject, voxel range).
CloudFeatures describe_cloud(const PointsView &view, const Params &params, const std::string &name, RunContext &ctx);

// Both clouds of a registration: voxelised one after the other, then described (progress stays monotone).
std::pair<CloudFeatures, CloudFeatures> describe_pair(const PointsView &source, const PointsView &target,
                                                      const Params &params, RunContext &ctx);

// True when features computed under `a` can be matched under `b` (same descriptor-relevant settings).
bool same_descriptor_settings(const Params &a, const Params &b);

// Per point of `view`: 1 when suppression's ground model labels its voxel ground (kissm_ground_mask()).
std::vector<std::uint8_t> ground_mask(const PointsView &view, const Params &params, RunContext &ctx);

Registration register_described(const CloudFeatures &source, const CloudFeatures &target, const Params &params,
                                RunContext &ctx);

// The operations behind the C API's entry points, one call each.
// kissm_register: both clouds described, then registered; their voxelise and feature times included.
Registration register_points(const PointsView &source, const PointsView &target, const Params &params, RunContext &ctx);
// kissm_register_features: Failure(FeaturesMismatch) unless both were described under params' descriptor
// settings. Voxelise and feature times are 0 (nothing was described in this call).
Registration register_features(const CloudFeatures &source, const CloudFeatures &target, const Params &params,
                               RunContext &ctx);

// kissm_refine: both clouds voxelised and given normals (no descriptors), then refined from `initial` (the
// callers' frames, p_target = R p_source + t; checked by the C boundary: finite and rigid).
Registration refine_points(const PointsView &source, const PointsView &target, const Eigen::Matrix3d &initial_rotation,
                           const Eigen::Vector3d &initial_translation, const Params &params, RunContext &ctx);
// kissm_refine_features: the same from features; Failure(FeaturesMismatch) as register_features.
Registration refine_features(const CloudFeatures &source, const CloudFeatures &target,
                             const Eigen::Matrix3d &initial_rotation, const Eigen::Vector3d &initial_translation,
                             const Params &params, RunContext &ctx);

KISSM_DETAIL_END
