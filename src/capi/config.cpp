// SPDX-License-Identifier: MIT
// kissm_config: defaults (from the core's Params, stated once), validation with messages naming the field,
// and the conversion to the core's Params and Hooks.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "core/setting_codes.hpp"
#include "core/setting_limits.hpp"

KISSM_DETAIL_BEGIN
namespace capi {

namespace {

// The fields with one name and one meaning in kissm_config and Params: copied by name both ways.
// (viewpoint, nonfinite_policy, viewpoint_mode and refine_mode have other types in the core and are converted by
// hand.)
#define KISSM_SAME_FIELDS(X)                                                                                           \
  X(num_threads)                                                                                                       \
  X(voxel_size)                                                                                                        \
  X(normal_radius_gain)                                                                                                \
  X(fpfh_radius_gain)                                                                                                  \
  X(max_linearity)                                                                                                     \
  X(ratio_test)                                                                                                        \
  X(prune_noise_bound_gain)                                                                                            \
  X(solver_noise_bound_gain)                                                                                           \
  X(noise_bound_max)                                                                                                   \
  X(min_normal_neighbors)                                                                                              \
  X(max_correspondences)                                                                                               \
  X(min_inliers)                                                                                                       \
  X(refine_max_iterations)                                                                                             \
  X(refine_max_distance_gain)                                                                                          \
  X(refine_kernel_gain)                                                                                                \
  X(refine_rotation_epsilon)                                                                                           \
  X(refine_translation_epsilon_gain)                                                                                   \
  X(min_overlap)                                                                                                       \
  X(max_rotation_uncertainty)                                                                                          \
  X(min_inlier_coverage)                                                                                               \
  X(refine_min_inliers)                                                                                                \
  X(min_refine_condition)                                                                                              \
  X(refine_normal_radius_gain)                                                                                         \
  X(rotation_dof)                                                                                                      \
  X(sensor_height)                                                                                                     \
  X(max_refine_rmse_gain)                                                                                              \
  X(allow_degenerate)                                                                                                  \
  X(max_ambiguity)

// Log levels of the core and of kissm.h; no default, so a new LogLevel without a code fails the build.
constexpr int32_t log_code(LogLevel level) {
    switch (level) {
    case LogLevel::Error: return KISSM_LOG_ERROR;
    case LogLevel::Warn: return KISSM_LOG_WARN;
    case LogLevel::Info: return KISSM_LOG_INFO;
    case LogLevel::Debug: return KISSM_LOG_DEBUG;
    }
    return KISSM_LOG_WARN;
}

LogLevel log_level_of(int32_t code) {
    switch (code) {
    case KISSM_LOG_ERROR: return LogLevel::Error;
    case KISSM_LOG_INFO: return LogLevel::Info;
    case KISSM_LOG_DEBUG: return LogLevel::Debug;
    default: return LogLevel::Warn;
    }
}

// Stages of the core and of kissm.h, as the progress callback sees them.
constexpr int32_t stage_code(Stage stage) {
    switch (stage) {
    case Stage::Voxelize: return KISSM_STAGE_VOXELIZE;
    case Stage::Features: return KISSM_STAGE_FEATURES;
    case Stage::Matching: return KISSM_STAGE_MATCHING;
    case Stage::Pruning: return KISSM_STAGE_PRUNING;
    case Stage::Solver: return KISSM_STAGE_SOLVER;
    case Stage::Refine: return KISSM_STAGE_REFINE;
    }
    return KISSM_STAGE_SOLVER;
}
static_assert(stage_code(Stage::Voxelize) == 1 && stage_code(Stage::Solver) == 5 && stage_code(Stage::Refine) == 6,
              "stage codes are pinned");

// The settings' codes are the core's tables (core/setting_codes.hpp); kissm.h's constants must be the same numbers.
static_assert(setting_code(NonFinitePolicy::Reject) == KISSM_NONFINITE_REJECT &&
                  setting_code(NonFinitePolicy::Drop) == KISSM_NONFINITE_DROP &&
                  max_setting_code<NonFinitePolicy>() == KISSM_NONFINITE_DROP,
              "nonfinite_policy codes");
static_assert(setting_code(ViewpointMode::Fixed) == KISSM_VIEWPOINT_FIXED &&
                  setting_code(ViewpointMode::CloudCenter) == KISSM_VIEWPOINT_CLOUD_CENTER &&
                  setting_code(ViewpointMode::SignFree) == KISSM_VIEWPOINT_SIGN_FREE &&
                  setting_code(ViewpointMode::Local) == KISSM_VIEWPOINT_LOCAL &&
                  max_setting_code<ViewpointMode>() == KISSM_VIEWPOINT_LOCAL,
              "viewpoint_mode codes");
static_assert(setting_code(RefineMode::None) == KISSM_REFINE_NONE &&
                  setting_code(RefineMode::Gicp) == KISSM_REFINE_GICP &&
                  setting_code(RefineMode::PointToPlane) == KISSM_REFINE_POINT_TO_PLANE &&
                  max_setting_code<RefineMode>() == KISSM_REFINE_POINT_TO_PLANE,
              "refine_mode codes");
static_assert(setting_code(Suppression::None) == KISSM_SUPPRESS_NONE &&
                  setting_code(Suppression::Ground) == KISSM_SUPPRESS_GROUND &&
                  max_setting_code<Suppression>() == KISSM_SUPPRESS_GROUND,
              "suppression codes");
static_assert(log_code(LogLevel::Error) == 1 && log_code(LogLevel::Debug) == 4, "log levels are pinned");

// hypot: no overflow for huge finite components (which normalise fine), no underflow for tiny ones.
double up_length(const double up[3]) { return std::hypot(std::hypot(up[0], up[1]), up[2]); }

void require_int(int64_t v, int64_t lo, int64_t hi, const char *field) {
    if (!IntLimits{lo, hi}.contains(v))
        fail(ErrorKind::InvalidArgument, std::string("config.") + field + " is " + std::to_string(v) +
                                             "; it must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                                             "]");
}

// config.FIELD within core/setting_limits.hpp's limits, the message naming the field.
void require_in(int64_t v, const IntLimits &range, const char *field) { require_int(v, range.lo, range.hi, field); }
void require_in(double v, const RealLimits &range, const char *field) {
    if (!range.contains(v))
        fail(ErrorKind::InvalidArgument, std::string("config.") + field + " is " + number(v) + "; it must be in " +
                                             (range.lo_open ? "(" : "[") + number(range.lo) + ", " + number(range.hi) +
                                             "]");
}
#define KISSM_REQUIRE_IN_LIMITS(field) require_in(c.field, limits::field, #field)

} // namespace

kissm_config default_config() {
    const Params p;
    const Hooks h;
    kissm_config c;
    std::memset(&c, 0, sizeof(c)); // callbacks and user data NULL, reserved bytes zero
    c.struct_size = sizeof(kissm_config);
#define KISSM_FROM_PARAMS(field) c.field = p.field;
    KISSM_SAME_FIELDS(KISSM_FROM_PARAMS)
#undef KISSM_FROM_PARAMS
    for (int i = 0; i < 3; ++i) c.viewpoint[i] = p.viewpoint[static_cast<std::size_t>(i)];
    c.nonfinite_policy = setting_code(p.nonfinite);
    c.viewpoint_mode = setting_code(p.viewpoint_mode);
    c.log_level = log_code(h.log_level);
    c.refine_mode = setting_code(p.refine_mode);
    c.suppression = setting_code(p.suppression);
    for (int i = 0; i < 3; ++i) c.up[i] = p.up[static_cast<std::size_t>(i)];
    return c;
}

kissm_config validated_config(const kissm_config *given) {
    kissm_config c = default_config();
    if (given == nullptr) return c;
    check_struct_size("config->struct_size", given->struct_size, kConfigSizes, given);
    // An older caller's smaller struct: the fields it lacks keep their defaults.
    std::memcpy(&c, given, std::min<std::size_t>(given->struct_size, sizeof(kissm_config)));
    c.struct_size = sizeof(kissm_config);

    KISSM_REQUIRE_IN_LIMITS(num_threads);
    // 0 asks for the voxel suggested from each call's clouds (core/voxel_suggest.hpp).
    if (c.voxel_size != 0.0 && !limits::voxel_size.contains(c.voxel_size))
        fail(ErrorKind::InvalidArgument, "config.voxel_size is " + number(c.voxel_size) +
                                             "; it must be a finite length > 0, or 0 for a voxel suggested from the "
                                             "points (automatic)");
    KISSM_REQUIRE_IN_LIMITS(fpfh_radius_gain);
    require_in(c.normal_radius_gain, limits::normal_radius_gain_below(c.fpfh_radius_gain), "normal_radius_gain");
    KISSM_REQUIRE_IN_LIMITS(max_linearity);
    KISSM_REQUIRE_IN_LIMITS(ratio_test);
    KISSM_REQUIRE_IN_LIMITS(prune_noise_bound_gain);
    KISSM_REQUIRE_IN_LIMITS(solver_noise_bound_gain);
    KISSM_REQUIRE_IN_LIMITS(noise_bound_max);
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(c.viewpoint[i]))
            fail(ErrorKind::InvalidArgument, "config.viewpoint[" + std::to_string(i) + "] is not finite");
    KISSM_REQUIRE_IN_LIMITS(min_normal_neighbors);
    if (c.max_correspondences != 0 && !limits::max_correspondences.contains(c.max_correspondences))
        fail(ErrorKind::InvalidArgument, "config.max_correspondences is " + std::to_string(c.max_correspondences) +
                                             "; it must be in [" + std::to_string(limits::max_correspondences.lo) +
                                             ", " + std::to_string(limits::max_correspondences.hi) +
                                             "], or 0 for a cap that grows with the keypoints (automatic)");
    KISSM_REQUIRE_IN_LIMITS(min_inliers);
    require_int(c.nonfinite_policy, 0, max_setting_code<NonFinitePolicy>(), "nonfinite_policy");
    require_int(c.viewpoint_mode, 0, max_setting_code<ViewpointMode>(), "viewpoint_mode");
    require_int(c.log_level, 0, KISSM_LOG_DEBUG, "log_level");
    require_int(c.refine_mode, 0, max_setting_code<RefineMode>(), "refine_mode");
    KISSM_REQUIRE_IN_LIMITS(refine_max_iterations);
    KISSM_REQUIRE_IN_LIMITS(refine_max_distance_gain);
    KISSM_REQUIRE_IN_LIMITS(refine_kernel_gain);
    KISSM_REQUIRE_IN_LIMITS(refine_rotation_epsilon);
    KISSM_REQUIRE_IN_LIMITS(refine_translation_epsilon_gain);
    KISSM_REQUIRE_IN_LIMITS(min_overlap);
    KISSM_REQUIRE_IN_LIMITS(max_rotation_uncertainty);
    KISSM_REQUIRE_IN_LIMITS(min_inlier_coverage);
    KISSM_REQUIRE_IN_LIMITS(refine_min_inliers);
    require_int(c.reserved1, 0, 0, "reserved1");
    KISSM_REQUIRE_IN_LIMITS(min_refine_condition);
    KISSM_REQUIRE_IN_LIMITS(refine_normal_radius_gain);
    require_int(c.suppression, 0, max_setting_code<Suppression>(), "suppression");
    if (c.rotation_dof != 1 && c.rotation_dof != 3)
        fail(ErrorKind::InvalidArgument,
             "config.rotation_dof is " + std::to_string(c.rotation_dof) + "; it must be 3 or 1 (yaw only)");
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(c.up[i]))
            fail(ErrorKind::InvalidArgument, "config.up[" + std::to_string(i) + "] is not finite");
    if (!(up_length(c.up) > 1e-9))
        fail(ErrorKind::InvalidArgument, "config.up is (" + number(c.up[0]) + ", " + number(c.up[1]) + ", " +
                                             number(c.up[2]) + "); it must have a length above 1e-9");
    KISSM_REQUIRE_IN_LIMITS(sensor_height);
    KISSM_REQUIRE_IN_LIMITS(max_refine_rmse_gain);
    KISSM_REQUIRE_IN_LIMITS(allow_degenerate);
    KISSM_REQUIRE_IN_LIMITS(max_ambiguity);
    require_int(c.reserved2, 0, 0, "reserved2");
    return c;
}

Params to_params(const kissm_config &c) {
    Params p;
#define KISSM_TO_PARAMS(field) p.field = c.field;
    KISSM_SAME_FIELDS(KISSM_TO_PARAMS)
#undef KISSM_TO_PARAMS
    p.viewpoint = {{c.viewpoint[0], c.viewpoint[1], c.viewpoint[2]}};
    p.nonfinite = setting_of<NonFinitePolicy>(c.nonfinite_policy);
    p.viewpoint_mode = setting_of<ViewpointMode>(c.viewpoint_mode);
    p.refine_mode = setting_of<RefineMode>(c.refine_mode);
    p.suppression = setting_of<Suppression>(c.suppression);
    const double up_norm = up_length(c.up);
    p.up = {{c.up[0] / up_norm, c.up[1] / up_norm, c.up[2] / up_norm}};
    return p;
}

// The values docs/parameters.md ("Presets") gives the evidence for; anything else is the caller's.
void apply_preset(int32_t preset, kissm_config &c) {
    switch (preset) {
    case KISSM_PRESET_LIDAR_VEHICLE:
        c.voxel_size = 0.3;
        c.suppression = KISSM_SUPPRESS_GROUND;
        c.up[0] = 0.0, c.up[1] = 0.0, c.up[2] = 1.0;
        c.viewpoint_mode = KISSM_VIEWPOINT_FIXED;
        return;
    case KISSM_PRESET_LIDAR_HANDHELD:
        c.voxel_size = 0.3;
        c.suppression = KISSM_SUPPRESS_NONE;
        c.rotation_dof = 3;
        c.viewpoint_mode = KISSM_VIEWPOINT_LOCAL; // no one sensor frame: maps, drones, handheld trajectories
        return;
    case KISSM_PRESET_INDOOR_RGBD:
        c.voxel_size = 0.05;
        c.suppression = KISSM_SUPPRESS_NONE;
        c.rotation_dof = 3;
        return;
    case KISSM_PRESET_OBJECT:
        c.voxel_size = 0.006;
        c.suppression = KISSM_SUPPRESS_NONE;
        c.rotation_dof = 3;
        return;
    default:
        fail(ErrorKind::InvalidArgument,
             "preset is " + std::to_string(preset) + "; it must be a KISSM_PRESET_* value (" +
                 std::to_string(KISSM_PRESET_LIDAR_VEHICLE) + " to " + std::to_string(KISSM_PRESET_OBJECT) + ")");
    }
}

Hooks hooks_of(const kissm_config &c) {
    Hooks h;
    if (c.log_fn != nullptr && c.log_level > 0) {
        kissm_log_fn fn = c.log_fn;
        void *user = c.log_user_data;
        h.log = [fn, user](LogLevel level, const std::string &message) { fn(user, log_code(level), message.c_str()); };
        h.log_level = log_level_of(c.log_level);
    }
    if (c.progress_fn != nullptr) {
        kissm_progress_fn fn = c.progress_fn;
        void *user = c.progress_user_data;
        h.progress = [fn, user](Stage stage, double fraction) { return fn(user, stage_code(stage), fraction) != 0; };
    }
    return h;
}

#undef KISSM_SAME_FIELDS
#undef KISSM_REQUIRE_IN_LIMITS

} // namespace capi
KISSM_DETAIL_END

using namespace kissm::detail::capi;

extern "C" {

int32_t kissm_config_init(kissm_config *config, uint32_t struct_size) {
    return guarded("kissm_config_init", [&] {
        require_non_null(config, "config");
        check_struct_size("struct_size", struct_size, kConfigSizes);
        const kissm_config c = default_config();
        store_struct(config, struct_size, &c, sizeof c); // a newer caller's unknown tail: zero = default
        return ok();
    });
}

int32_t kissm_config_preset(kissm_config *config, int32_t preset) {
    return guarded("kissm_config_preset", [&] {
        require_non_null(config, "config");
        check_struct_size("config->struct_size", config->struct_size, kConfigSizes);
        const std::size_t known = std::min<std::size_t>(config->struct_size, sizeof(kissm_config));
        kissm_config c = default_config();
        std::memcpy(&c, config, known);
        apply_preset(preset, c);
        std::memcpy(config, &c, known); // a newer caller's fields this library does not know stay as they are
        return ok();
    });
}

int32_t kissm_config_validate(const kissm_config *config) {
    return guarded("kissm_config_validate", [&] {
        require_non_null(config, "config");
        (void)validated_config(config);
        return ok();
    });
}

} // extern "C"
