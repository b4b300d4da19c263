// SPDX-License-Identifier: MIT
// kissm_result: checked, reset to "no pose" before any work, filled from the core's Registration.
#include <cmath>
#include <cstring>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "core/validity.hpp"

KISSM_DETAIL_BEGIN
namespace capi {

namespace {

// The reason codes of kissm.h for the core's reasons; no default, so a new Reason without a code fails the
// build.
constexpr int32_t reason_code(Reason reason) {
    switch (reason) {
    case Reason::None: return KISSM_REASON_NONE;
    case Reason::TooFewVoxels: return KISSM_REASON_TOO_FEW_VOXELS;
    case Reason::TooFewFeatures: return KISSM_REASON_TOO_FEW_FEATURES;
    case Reason::TooFewCorrespondences: return KISSM_REASON_TOO_FEW_CORRESPONDENCES;
    case Reason::SolverFailed: return KISSM_REASON_SOLVER_FAILED;
    case Reason::TooFewInliers: return KISSM_REASON_TOO_FEW_INLIERS;
    case Reason::Degenerate: return KISSM_REASON_DEGENERATE;
    case Reason::LowOverlap: return KISSM_REASON_LOW_OVERLAP;
    case Reason::Unconstrained: return KISSM_REASON_UNCONSTRAINED;
    case Reason::UncertainRotation: return KISSM_REASON_UNCERTAIN_ROTATION;
    case Reason::ClusteredInliers: return KISSM_REASON_CLUSTERED_INLIERS;
    case Reason::NotConverged: return KISSM_REASON_NOT_CONVERGED;
    case Reason::Tilted: return KISSM_REASON_TILTED;
    }
    return KISSM_REASON_NONE;
}
static_assert(reason_code(Reason::None) == 0 && reason_code(Reason::Degenerate) == 6 &&
                  reason_code(Reason::NotConverged) == 11 && reason_code(Reason::Tilted) == 12,
              "reason codes are pinned");

// 4x4 row-major from R and t.
void write_transform(const Eigen::Matrix3d &R, const Eigen::Vector3d &t, double out[16]) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) out[4 * i + j] = R(i, j);
        out[4 * i + 3] = t[i];
    }
    out[12] = out[13] = out[14] = 0.0;
    out[15] = 1.0;
}

} // namespace

void check_result(const kissm_result *r) {
    require_non_null(r, "result");
    check_struct_size("result->struct_size", r->struct_size, kResultSizes);
}

namespace {

// A whole result of this kissm with no pose: zero counts, NaN where "not computed" is not 0.
void reset_full(kissm_result *r) noexcept {
    std::memset(static_cast<void *>(r), 0, sizeof *r);
    r->struct_size = sizeof *r;
    const double nan = std::nan("");
    for (double &v : r->transform) v = nan;
    for (double &v : r->rotation) v = nan;
    for (double &v : r->translation) v = nan;
    r->residual_rms = nan;
    for (double &v : r->coarse_transform) v = nan;
    for (double &v : r->information) v = nan;
    r->overlap = nan;
    r->refine_rmse = nan;
    r->refine_condition = nan;
    r->rotation_uncertainty = nan;
    r->inlier_coverage = nan;
    r->tilt = nan;
}

} // namespace

void reset_result(kissm_result *r) noexcept {
    kissm_result full;
    reset_full(&full);
    store_struct(r, r->struct_size, &full, sizeof full); // an older caller's struct gets its fields only
}

void fill_result(const Registration &g, kissm_result *caller) {
    kissm_result full;
    kissm_result *r = &full;
    reset_full(r);
    r->valid = g.solved && g.reason == Reason::None;
    r->reason = reason_code(g.reason);
    if (g.solved) {
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) r->rotation[3 * i + j] = g.rotation(i, j);
            r->translation[i] = g.translation[i];
        }
        write_transform(g.rotation, g.translation, r->transform);
        write_transform(g.coarse_rotation, g.coarse_translation, r->coarse_transform);
        r->rotation_uncertainty = g.rotation_uncertainty;
        r->inlier_coverage = g.inlier_coverage;
    }
    if (g.refined) {
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j) r->information[6 * i + j] = g.information(i, j);
        r->overlap = g.overlap;
        r->refine_rmse = g.refine_rmse;
        r->refine_condition = g.refine_condition;
        r->num_refine_correspondences = g.num_refine_correspondences;
        r->refine_iterations = g.refine_iterations;
        r->refine_converged = g.refine_converged ? 1 : 0;
    }
    r->num_source_points = g.num_source_points;
    r->num_target_points = g.num_target_points;
    r->num_source_nonfinite = g.num_source_nonfinite;
    r->num_target_nonfinite = g.num_target_nonfinite;
    r->num_source_voxels = g.num_source_voxels;
    r->num_target_voxels = g.num_target_voxels;
    r->num_source_keypoints = g.num_source_keypoints;
    r->num_target_keypoints = g.num_target_keypoints;
    r->num_initial_correspondences = g.num_initial_correspondences;
    r->num_pruned_correspondences = g.num_pruned_correspondences;
    r->num_rotation_inliers = g.num_rotation_inliers;
    r->num_final_inliers = g.num_final_inliers;
    r->max_core_number = g.max_core_number;
    r->inlier_ratio = g.inlier_ratio;
    r->residual_rms = g.residual_rms;
    r->noise_bound = g.noise_bound;
    for (int i = 0; i < 3; ++i) r->inlier_extent[i] = g.inlier_extent[i];
    r->time_voxelize_ms = g.time_voxelize_ms;
    r->time_features_ms = g.time_features_ms;
    r->time_matching_ms = g.time_matching_ms;
    r->time_pruning_ms = g.time_pruning_ms;
    r->time_solver_ms = g.time_solver_ms;
    r->time_refine_ms = g.time_refine_ms;
    r->num_source_suppressed = g.num_source_suppressed;
    r->num_target_suppressed = g.num_target_suppressed;
    r->time_suppression_ms = g.time_suppression_ms;
    r->tilt = g.tilt;
    r->time_total_ms = g.time_voxelize_ms + g.time_features_ms + g.time_matching_ms + g.time_pruning_ms +
                       g.time_solver_ms + g.time_refine_ms;
    store_struct(caller, caller->struct_size, &full, sizeof full);
}

} // namespace capi
KISSM_DETAIL_END

using namespace kissm::detail::capi;

extern "C" {

int32_t kissm_result_init(kissm_result *result, uint32_t struct_size) {
    return guarded("kissm_result_init", [&] {
        require_non_null(result, "result");
        check_struct_size("struct_size", struct_size, kResultSizes);
        result->struct_size = struct_size;
        reset_result(result);
        return ok();
    });
}

} // extern "C"
