// SPDX-License-Identifier: MIT
// Between the C structs of kissm.h and the core's types: configs (config.cpp), point views (points.cpp) and
// results (result.cpp). Each conversion validates what it reads and throws Failure naming the argument.
#pragma once

#include "capi/boundary.hpp"
#include "core/detail_namespace.hpp"
#include "core/params.hpp"
#include "core/pipeline.hpp"
#include "core/run_context.hpp"
#include "core/stage_types.hpp"
#include "kissm.h"

KISSM_DETAIL_BEGIN
namespace capi {

// The documented defaults: core/params.hpp's Params{} and Hooks{}, as a kissm_config.
kissm_config default_config();
// A full-size copy of a caller's config (of whatever struct_size), every field checked; NULL gives defaults.
kissm_config validated_config(const kissm_config *given);
Params to_params(const kissm_config &config);
Hooks hooks_of(const kissm_config &config);
// Writes the fields KISSM_PRESET_* `preset` sets into c; fails (InvalidArgument) for an unknown preset.
void apply_preset(int32_t preset, kissm_config &c);

// The caller's points, checked (scalar type, count, stride); `name` is the argument's name for messages.
PointsView points_view(const kissm_points *points, const char *name);

// A caller's 4x4 row-major rigid transform: finite, last row (0, 0, 0, 1), rotation block orthonormal to 1e-3
// with det > 0, translation within 1e9. Throws Failure(NullArgument or InvalidArgument) naming `name`; R is
// the nearest rotation to the block.
void rigid_transform(const double *m, const char *name, Eigen::Matrix3d &R, Eigen::Vector3d &t);

// A result pointer the library may write: non-null, with a struct_size it can hold.
void check_result(const kissm_result *result);
// No pose: zero counts, NaN transform. What every failing or degenerate call leaves behind.
void reset_result(kissm_result *result) noexcept;
void fill_result(const Registration &registration, kissm_result *result);

// For the calls that write a result: checks and resets it first (so that it holds no pose whatever else is
// wrong), then runs body under guarded(), and resets it again if body fails.
template <class Body>
int32_t with_result(const char *function, kissm_result *result, Body &&body) noexcept {
    int32_t status = guarded(function, [&] {
        check_result(result);
        reset_result(result);
        return KISSM_OK;
    });
    if (status != KISSM_OK) return status;
    status = guarded(function, body);
    if (status != KISSM_OK) reset_result(result);
    return status;
}

} // namespace capi
KISSM_DETAIL_END
