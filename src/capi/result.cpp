// SPDX-License-Identifier: MIT
// kissm_result: checked, reset to "no pose" before any work, filled from the core's Registration.
#include <cmath>
#include <cstring>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "core/validity.hpp"

KISSM_DETAIL_BEGIN
namespace capi {

// The fields that kissm_result and the core's Registration share by name: copied as they are (-Wconversion
// refuses a narrowing copy).
#define KISSM_RESULT_SAME_FIELDS(X)                                                                                    \
  X(num_source_points)                                                                                                 \
  X(voxel_size_used)                                                                                                   \
  X(num_target_points)                                                                                                 \
  X(num_source_nonfinite)                                                                                              \
  X(num_target_nonfinite)                                                                                              \
  X(num_source_voxels)                                                                                                 \
  X(num_target_voxels)                                                                                                 \
  X(num_source_keypoints)                                                                                              \
  X(num_target_keypoints)                                                                                              \
  X(num_initial_correspondences)                                                                                       \
  X(num_pruned_correspondences)                                                                                        \
  X(num_rotation_inliers)                                                                                              \
  X(num_final_inliers)                                                                                                 \
  X(max_core_number)                                                                                                   \
  X(inlier_ratio)                                                                                                      \
  X(residual_rms)                                                                                                      \
  X(noise_bound)                                                                                                       \
  X(time_voxelize_ms)                                                                                                  \
  X(time_features_ms)                                                                                                  \
  X(time_matching_ms)                                                                                                  \
  X(time_pruning_ms)                                                                                                   \
  X(time_solver_ms)                                                                                                    \
  X(time_refine_ms)                                                                                                    \
  X(num_source_suppressed)                                                                                             \
  X(num_target_suppressed)                                                                                             \
  X(time_suppression_ms)                                                                                               \
  X(tilt)

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
    case Reason::LooseAlignment: return KISSM_REASON_LOOSE_ALIGNMENT;
    case Reason::Ambiguous: return KISSM_REASON_AMBIGUOUS;
    case Reason::LooseAndWeak: return KISSM_REASON_LOOSE_AND_WEAK;
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
    for (double &v : r->weak_directions) v = nan;
    r->ambiguity = nan;
    r->confidence = nan;
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
        r->ambiguity = g.ambiguity;
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
        r->degenerate = g.degenerate ? 1 : 0;
        r->num_weak_directions = static_cast<int32_t>(g.weak_directions.size());
        for (std::size_t i = 0; i < g.weak_directions.size(); ++i)
            for (int j = 0; j < 6; ++j)
                r->weak_directions[6 * i + static_cast<std::size_t>(j)] = g.weak_directions[i][j];
    }
    r->confidence = g.confidence;
#define KISSM_COPY_FIELD(name) r->name = g.name;
    KISSM_RESULT_SAME_FIELDS(KISSM_COPY_FIELD)
#undef KISSM_COPY_FIELD
    for (int i = 0; i < 3; ++i) r->inlier_extent[i] = g.inlier_extent[i];
    r->time_total_ms = g.time_voxelize_ms + g.time_features_ms + g.time_matching_ms + g.time_pruning_ms +
                       g.time_solver_ms + g.time_refine_ms;
    store_struct(caller, caller->struct_size, &full, sizeof full);
}

#undef KISSM_RESULT_SAME_FIELDS

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
