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
    }
    return KISSM_REASON_NONE;
}
static_assert(reason_code(Reason::None) == 0 && reason_code(Reason::Degenerate) == 6, "reason codes are pinned");

} // namespace

void check_result(const kissm_result *r) {
    require_non_null(r, "result");
    check_struct_size("result->struct_size", r->struct_size, sizeof(kissm_result), "kissm_result");
}

void reset_result(kissm_result *r) noexcept {
    const uint32_t size = r->struct_size;
    std::memset(static_cast<void *>(r), 0, size);
    r->struct_size = size;
    const double nan = std::nan("");
    for (double &v : r->transform) v = nan;
    for (double &v : r->rotation) v = nan;
    for (double &v : r->translation) v = nan;
    r->residual_rms = nan;
}

void fill_result(const Registration &g, kissm_result *r) {
    reset_result(r);
    r->valid = g.solved && g.reason == Reason::None;
    r->reason = reason_code(g.reason);
    if (g.solved) {
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                r->rotation[3 * i + j] = g.rotation(i, j);
                r->transform[4 * i + j] = g.rotation(i, j);
            }
            r->translation[i] = g.translation[i];
            r->transform[4 * i + 3] = g.translation[i];
        }
        r->transform[12] = r->transform[13] = r->transform[14] = 0.0;
        r->transform[15] = 1.0;
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
    r->time_total_ms =
        g.time_voxelize_ms + g.time_features_ms + g.time_matching_ms + g.time_pruning_ms + g.time_solver_ms;
}

} // namespace capi
KISSM_DETAIL_END

using namespace kissm::detail::capi;

extern "C" {

int32_t kissm_result_init(kissm_result *result, uint32_t struct_size) {
    return guarded("kissm_result_init", [&] {
        require_non_null(result, "result");
        check_struct_size("struct_size", struct_size, sizeof(kissm_result), "kissm_result");
        result->struct_size = struct_size;
        reset_result(result);
        return ok();
    });
}

} // extern "C"
