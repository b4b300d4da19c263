// SPDX-License-Identifier: MIT
// The C boundary: argument checks, the catch-all, status mapping and the thread-local error message.
// Every exported function is noexcept so that no C++ exception can unwind into a C, Python or Rust frame.
#include <cmath>
#include <cstring>
#include <new>
#include <sstream>
#include <string>

#include "capi/handles.hpp"
#include "core/failure.hpp"
#include "core/pipeline.hpp"
#include "core/run_context.hpp"
#include "io/read_points.hpp"
#include "kissm.h"

using kissm::detail::ErrorKind;
using kissm::detail::Failure;

namespace {

thread_local std::string t_last_error;

// Argument problems found at the boundary, before any work.
struct ArgError {
    int32_t status;
    std::string message;
};

int32_t status_of(ErrorKind kind) {
    switch (kind) {
    case ErrorKind::InvalidArgument: return KISSM_ERR_INVALID_ARGUMENT;
    case ErrorKind::NullArgument: return KISSM_ERR_NULL_ARGUMENT;
    case ErrorKind::EmptyInput: return KISSM_ERR_EMPTY_INPUT;
    case ErrorKind::TooFewPoints: return KISSM_ERR_TOO_FEW_POINTS;
    case ErrorKind::NonFinite: return KISSM_ERR_NONFINITE;
    case ErrorKind::VoxelRange: return KISSM_ERR_VOXEL_RANGE;
    case ErrorKind::StructSize: return KISSM_ERR_STRUCT_SIZE;
    case ErrorKind::Cancelled: return KISSM_ERR_CANCELLED;
    case ErrorKind::FeaturesMismatch: return KISSM_ERR_FEATURES_MISMATCH;
    case ErrorKind::Io: return KISSM_ERR_IO;
    case ErrorKind::Parse: return KISSM_ERR_PARSE;
    case ErrorKind::UnsupportedFormat: return KISSM_ERR_UNSUPPORTED_FORMAT;
    case ErrorKind::Internal: return KISSM_ERR_INTERNAL;
    }
    return KISSM_ERR_INTERNAL;
}

// The message is built inside the try: when memory has run out, composing it may fail too, and the status
// must still get through.
int32_t set_error(int32_t status, const char *function, const char *what, const char *detail = nullptr) noexcept {
    try {
        t_last_error = function;
        t_last_error += ": ";
        t_last_error += what;
        if (detail != nullptr) t_last_error += detail;
    } catch (...) {
        t_last_error.clear(); // clear() never allocates
    }
    return status;
}

int32_t ok() noexcept {
    t_last_error.clear();
    return KISSM_OK;
}

// Runs body() and maps every way it can fail to a status. body returns a status itself.
template <class Body>
int32_t guarded(const char *function, Body &&body) noexcept {
    try {
        return body();
    } catch (const Failure &f) {
        return set_error(status_of(f.kind()), function, f.what());
    } catch (const std::bad_alloc &) {
        return set_error(KISSM_ERR_OUT_OF_MEMORY, function, "out of memory");
    } catch (const std::length_error &) {
        return set_error(KISSM_ERR_OUT_OF_MEMORY, function, "out of memory (allocation too large)");
    } catch (const std::exception &e) {
        return set_error(KISSM_ERR_INTERNAL, function, "internal error: ", e.what());
    } catch (...) {
        return set_error(KISSM_ERR_INTERNAL, function, "internal error (unknown exception)");
    }
}

[[noreturn]] void arg_fail(ErrorKind kind, const std::string &message) { throw Failure(kind, message); }

std::string num(double v) {
    std::ostringstream s;
    s.precision(6);
    s << v;
    return s.str();
}

// ------------------------------------------------------------------------------------------------
// Config
// ------------------------------------------------------------------------------------------------

// Bytes of a caller's struct beyond the part this library knows must be zero: they are fields of a newer
// kissm that this one would silently ignore.
bool tail_is_zero(const void *p, std::size_t known, std::size_t given) {
    const auto *bytes = static_cast<const unsigned char *>(p);
    for (std::size_t i = known; i < given; ++i)
        if (bytes[i] != 0) return false;
    return true;
}

// An uninitialised struct_size is a common C mistake; a size no kissm struct will ever reach is refused
// before any byte beyond the known layout is read or written.
constexpr uint32_t kMaxStructSize = 65536;

void check_struct_size(const void *p, uint32_t given, std::size_t known, const char *what) {
    if (given > kMaxStructSize)
        arg_fail(ErrorKind::StructSize, std::string(what) + "->struct_size is " + std::to_string(given) +
                                            ", larger than any kissm struct (was it initialised? set it to sizeof(" +
                                            what + "))");
    if (given < known)
        arg_fail(ErrorKind::StructSize, std::string(what) + "->struct_size is " + std::to_string(given) +
                                            "; this kissm needs at least " + std::to_string(known) +
                                            " (set it to sizeof(" + what + "))");
    if (given > known && !tail_is_zero(p, known, given))
        arg_fail(ErrorKind::StructSize, std::string(what) + "->struct_size is " + std::to_string(given) +
                                            " with non-zero fields beyond the " + std::to_string(known) +
                                            " bytes this kissm " KISSM_VERSION_STRING " knows; upgrade kissm");
}

void fill_defaults(kissm_config &c) {
    std::memset(&c, 0, sizeof(c));
    c.struct_size = sizeof(kissm_config);
    c.num_threads = 0;
    c.voxel_size = 0.3;
    c.normal_radius_gain = 3.5;
    c.fpfh_radius_gain = 5.0;
    c.max_linearity = 0.99;
    c.ratio_test = 0.9;
    c.prune_noise_bound_gain = 1.0;
    c.solver_noise_bound_gain = 0.75;
    c.noise_bound_max = 0.0;
    c.viewpoint[0] = c.viewpoint[1] = c.viewpoint[2] = 0.0;
    c.min_normal_neighbors = 3;
    c.max_correspondences = 5000;
    c.min_inliers = 15;
    c.nonfinite_policy = KISSM_NONFINITE_REJECT;
    c.viewpoint_mode = KISSM_VIEWPOINT_FIXED;
    c.log_level = KISSM_LOG_WARN;
}

constexpr int32_t kMaxThreads = 1024;
constexpr int32_t kMaxCorrespondences = 100000;

void require_range(double v, double lo, double hi, bool lo_open, const char *field) {
    const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
    if (!ok)
        arg_fail(ErrorKind::InvalidArgument, std::string("config.") + field + " is " + num(v) + "; it must be in " +
                                                 (lo_open ? "(" : "[") + num(lo) + ", " + num(hi) + "]");
}

void require_int(int64_t v, int64_t lo, int64_t hi, const char *field) {
    if (v < lo || v > hi)
        arg_fail(ErrorKind::InvalidArgument, std::string("config.") + field + " is " + std::to_string(v) +
                                                 "; it must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                                                 "]");
}

// Copies a validated config (of whatever size the caller has) into a full-size one.
kissm_config validated_config(const kissm_config *given) {
    kissm_config c;
    fill_defaults(c);
    if (given == nullptr) return c;
    check_struct_size(given, given->struct_size, sizeof(kissm_config), "config");
    std::memcpy(&c, given, sizeof(kissm_config));
    c.struct_size = sizeof(kissm_config);

    require_int(c.num_threads, 0, kMaxThreads, "num_threads");
    if (!(std::isfinite(c.voxel_size) && c.voxel_size > 0.0))
        arg_fail(ErrorKind::InvalidArgument,
                 "config.voxel_size is " + num(c.voxel_size) + "; it must be a finite length > 0");
    require_range(c.fpfh_radius_gain, 1.5, 50.0, false, "fpfh_radius_gain");
    require_range(c.normal_radius_gain, 0.0, c.fpfh_radius_gain, true, "normal_radius_gain");
    require_range(c.max_linearity, 0.0, 1.0, true, "max_linearity");
    require_range(c.ratio_test, 0.0, 1.0, true, "ratio_test");
    require_range(c.prune_noise_bound_gain, 0.0, 1e6, true, "prune_noise_bound_gain");
    require_range(c.solver_noise_bound_gain, 0.0, 1e6, true, "solver_noise_bound_gain");
    require_range(c.noise_bound_max, 0.0, 1e300, false, "noise_bound_max");
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(c.viewpoint[i]))
            arg_fail(ErrorKind::InvalidArgument, "config.viewpoint[" + std::to_string(i) + "] is not finite");
    require_int(c.min_normal_neighbors, 3, 100000, "min_normal_neighbors");
    require_int(c.max_correspondences, 3, kMaxCorrespondences, "max_correspondences");
    require_int(c.min_inliers, 3, kMaxCorrespondences, "min_inliers");
    require_int(c.nonfinite_policy, KISSM_NONFINITE_REJECT, KISSM_NONFINITE_DROP, "nonfinite_policy");
    require_int(c.viewpoint_mode, KISSM_VIEWPOINT_FIXED, KISSM_VIEWPOINT_CLOUD_CENTER, "viewpoint_mode");
    require_int(c.log_level, 0, KISSM_LOG_DEBUG, "log_level");
    return c;
}

kissm::detail::Params to_params(const kissm_config &c) {
    kissm::detail::Params p;
    p.num_threads = c.num_threads;
    p.voxel_size = c.voxel_size;
    p.normal_radius_gain = c.normal_radius_gain;
    p.fpfh_radius_gain = c.fpfh_radius_gain;
    p.max_linearity = c.max_linearity;
    p.ratio_test = c.ratio_test;
    p.prune_noise_bound_gain = c.prune_noise_bound_gain;
    p.solver_noise_bound_gain = c.solver_noise_bound_gain;
    p.noise_bound_max = c.noise_bound_max;
    p.viewpoint = {{c.viewpoint[0], c.viewpoint[1], c.viewpoint[2]}};
    p.min_normal_neighbors = c.min_normal_neighbors;
    p.max_correspondences = c.max_correspondences;
    p.min_inliers = c.min_inliers;
    p.nonfinite = c.nonfinite_policy == KISSM_NONFINITE_DROP ? kissm::detail::NonFinitePolicy::Drop
                                                             : kissm::detail::NonFinitePolicy::Reject;
    p.viewpoint_mode = c.viewpoint_mode == KISSM_VIEWPOINT_CLOUD_CENTER ? kissm::detail::ViewpointMode::CloudCenter
                                                                        : kissm::detail::ViewpointMode::Fixed;
    return p;
}

kissm::detail::Hooks hooks_of(const kissm_config &c) {
    kissm::detail::Hooks h;
    if (c.log_fn != nullptr && c.log_level > 0) {
        kissm_log_fn fn = c.log_fn;
        void *user = c.log_user_data;
        h.log = [fn, user](kissm::detail::LogLevel level, const std::string &message) {
            fn(user, static_cast<int32_t>(level), message.c_str());
        };
        h.log_level = static_cast<kissm::detail::LogLevel>(c.log_level);
    }
    if (c.progress_fn != nullptr) {
        kissm_progress_fn fn = c.progress_fn;
        void *user = c.progress_user_data;
        h.progress = [fn, user](int stage, double fraction) { return fn(user, stage, fraction) != 0; };
    }
    return h;
}

// ------------------------------------------------------------------------------------------------
// Points and results
// ------------------------------------------------------------------------------------------------

kissm::detail::PointsView points_view(const kissm_points *p, const char *name) {
    if (p == nullptr) arg_fail(ErrorKind::NullArgument, std::string(name) + " is NULL");
    if (p->scalar_type != KISSM_SCALAR_FLOAT32 && p->scalar_type != KISSM_SCALAR_FLOAT64)
        arg_fail(ErrorKind::InvalidArgument, std::string(name) + "->scalar_type is " + std::to_string(p->scalar_type) +
                                                 "; use KISSM_SCALAR_FLOAT32 or KISSM_SCALAR_FLOAT64");
    if (p->reserved != 0) arg_fail(ErrorKind::InvalidArgument, std::string(name) + "->reserved must be 0");
    if (p->count == 0) arg_fail(ErrorKind::EmptyInput, std::string(name) + " has no points (count is 0)");
    if (p->data == nullptr) arg_fail(ErrorKind::NullArgument, std::string(name) + "->data is NULL");
    if (p->count < KISSM_MIN_POINTS)
        arg_fail(ErrorKind::TooFewPoints, std::string(name) + " has " + std::to_string(p->count) +
                                              " points; at least " + std::to_string(KISSM_MIN_POINTS) + " are needed");
    if (p->count > 0xFFFFFFFFull)
        arg_fail(ErrorKind::InvalidArgument, std::string(name) + "->count is " + std::to_string(p->count) +
                                                 "; at most 4294967295 points per cloud are supported");
    const uint64_t scalar = p->scalar_type == KISSM_SCALAR_FLOAT64 ? 8 : 4;
    const uint64_t stride = p->stride_bytes == 0 ? 3 * scalar : p->stride_bytes;
    if (stride < 3 * scalar)
        arg_fail(ErrorKind::InvalidArgument, std::string(name) + "->stride_bytes is " +
                                                 std::to_string(p->stride_bytes) +
                                                 "; it must be 0 (packed) or at least " + std::to_string(3 * scalar));
    if (stride > (UINT64_MAX / p->count))
        arg_fail(ErrorKind::InvalidArgument, std::string(name) + ": count * stride_bytes overflows");
    kissm::detail::PointsView v;
    v.data = p->data;
    v.count = p->count;
    v.stride_bytes = stride;
    v.is_double = p->scalar_type == KISSM_SCALAR_FLOAT64;
    return v;
}

void check_result(kissm_result *r) {
    if (r == nullptr) arg_fail(ErrorKind::NullArgument, "result is NULL");
    if (r->struct_size > kMaxStructSize)
        arg_fail(ErrorKind::StructSize,
                 "result->struct_size is " + std::to_string(r->struct_size) +
                     ", larger than any kissm struct (was it initialised? set it to sizeof(kissm_result))");
    if (r->struct_size < sizeof(kissm_result))
        arg_fail(ErrorKind::StructSize, "result->struct_size is " + std::to_string(r->struct_size) +
                                            "; this kissm needs at least " + std::to_string(sizeof(kissm_result)) +
                                            " (set it to sizeof(kissm_result))");
}

// A result with no pose: what every failing or degenerate call leaves behind.
void reset_result(kissm_result *r) noexcept {
    const uint32_t size = r->struct_size;
    std::memset(r, 0, size);
    r->struct_size = size;
    const double nan = std::nan("");
    for (double &v : r->transform) v = nan;
    for (double &v : r->rotation) v = nan;
    for (double &v : r->translation) v = nan;
    r->residual_rms = nan;
}

int32_t reason_code(kissm::detail::Reason reason) { return static_cast<int32_t>(reason); }

void fill_result(const kissm::detail::Registration &g, kissm_result *r) {
    reset_result(r);
    r->valid = g.solved && g.reason == kissm::detail::Reason::None;
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

// Validates the result pointer first (so that it can be reset whatever else is wrong), then runs body.
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

kissm_matcher *require_matcher(kissm_matcher *m) {
    if (m == nullptr) arg_fail(ErrorKind::NullArgument, "matcher is NULL");
    return m;
}

} // namespace

extern "C" {

uint32_t kissm_version_number(void) { return KISSM_VERSION_NUMBER; }
const char *kissm_version_string(void) { return KISSM_VERSION_STRING; }
uint32_t kissm_abi_version(void) { return KISSM_ABI_VERSION; }

const char *kissm_status_string(int32_t status) {
    switch (status) {
    case KISSM_OK: return "success";
    case KISSM_ERR_INVALID_ARGUMENT: return "invalid argument";
    case KISSM_ERR_NULL_ARGUMENT: return "required pointer is NULL";
    case KISSM_ERR_EMPTY_INPUT: return "point cloud is empty";
    case KISSM_ERR_TOO_FEW_POINTS: return "point cloud has too few points";
    case KISSM_ERR_NONFINITE: return "point cloud has a NaN or infinite coordinate";
    case KISSM_ERR_VOXEL_RANGE: return "voxel size too small for the cloud's extent";
    case KISSM_ERR_STRUCT_SIZE: return "unsupported struct size";
    case KISSM_ERR_OUT_OF_MEMORY: return "out of memory";
    case KISSM_ERR_CANCELLED: return "cancelled";
    case KISSM_ERR_FEATURES_MISMATCH: return "features were computed with different settings";
    case KISSM_ERR_IO: return "file could not be read";
    case KISSM_ERR_PARSE: return "file is malformed";
    case KISSM_ERR_UNSUPPORTED_FORMAT: return "file format not supported";
    case KISSM_ERR_INTERNAL: return "internal error";
    default: return "unknown status";
    }
}

const char *kissm_reason_string(int32_t reason) {
    switch (reason) {
    case KISSM_REASON_NONE: return "none";
    case KISSM_REASON_TOO_FEW_VOXELS: return "too few voxels";
    case KISSM_REASON_TOO_FEW_FEATURES: return "too few points with a reliable descriptor";
    case KISSM_REASON_TOO_FEW_CORRESPONDENCES: return "too few correspondences";
    case KISSM_REASON_SOLVER_FAILED: return "no consistent rotation found";
    case KISSM_REASON_TOO_FEW_INLIERS: return "too few inliers";
    case KISSM_REASON_DEGENERATE: return "inliers are collinear or planar";
    default: return "unknown reason";
    }
}

const char *kissm_last_error_message(void) { return t_last_error.c_str(); }

int32_t kissm_config_init(kissm_config *config, uint32_t struct_size) {
    return guarded("kissm_config_init", [&] {
        if (config == nullptr) arg_fail(ErrorKind::NullArgument, "config is NULL");
        if (struct_size < sizeof(kissm_config) || struct_size > kMaxStructSize)
            arg_fail(ErrorKind::StructSize, "struct_size is " + std::to_string(struct_size) +
                                                "; this kissm needs at least " + std::to_string(sizeof(kissm_config)) +
                                                " (and at most " + std::to_string(kMaxStructSize) + ")");
        kissm_config c;
        fill_defaults(c);
        std::memset(static_cast<void *>(config), 0, struct_size); // a newer caller's unknown tail: zero = default
        std::memcpy(static_cast<void *>(config), &c, sizeof(c));
        config->struct_size = struct_size;
        return ok();
    });
}

int32_t kissm_config_validate(const kissm_config *config) {
    return guarded("kissm_config_validate", [&] {
        if (config == nullptr) arg_fail(ErrorKind::NullArgument, "config is NULL");
        (void)validated_config(config);
        return ok();
    });
}

int32_t kissm_create(const kissm_config *config, kissm_matcher **out_matcher) {
    return guarded("kissm_create", [&] {
        if (out_matcher == nullptr) arg_fail(ErrorKind::NullArgument, "out_matcher is NULL");
        const kissm_config c = validated_config(config);
        auto *m = new kissm_matcher();
        m->config = c;
        m->params = to_params(c);
        *out_matcher = m;
        return ok();
    });
}

void kissm_destroy(kissm_matcher *matcher) { delete matcher; }

int32_t kissm_get_config(const kissm_matcher *matcher, kissm_config *out_config) {
    return guarded("kissm_get_config", [&] {
        if (matcher == nullptr) arg_fail(ErrorKind::NullArgument, "matcher is NULL");
        if (out_config == nullptr) arg_fail(ErrorKind::NullArgument, "out_config is NULL");
        const uint32_t size = out_config->struct_size;
        if (size > kMaxStructSize)
            arg_fail(ErrorKind::StructSize, "out_config->struct_size is " + std::to_string(size) +
                                                ", larger than any kissm struct (was it initialised?)");
        if (size < sizeof(kissm_config))
            arg_fail(ErrorKind::StructSize, "out_config->struct_size is " + std::to_string(size) +
                                                "; this kissm needs at least " + std::to_string(sizeof(kissm_config)));
        std::memset(static_cast<void *>(out_config), 0, size);
        std::memcpy(static_cast<void *>(out_config), &matcher->config, sizeof(kissm_config));
        out_config->struct_size = size;
        return ok();
    });
}

void kissm_cancel(kissm_matcher *matcher) {
    if (matcher != nullptr) matcher->cancel_requested.store(1);
}

int32_t kissm_register(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                       kissm_result *result) {
    return with_result("kissm_register", result, [&] {
        kissm_matcher *m = require_matcher(matcher);
        const kissm::detail::PointsView sv = points_view(source, "source");
        const kissm::detail::PointsView tv = points_view(target, "target");
        m->cancel_requested.store(0);
        kissm::detail::RunContext ctx(m->params.num_threads, &m->cancel_requested, hooks_of(m->config));
        const auto clouds = kissm::detail::describe_pair(sv, tv, m->params, ctx);
        kissm::detail::Registration g = kissm::detail::register_described(clouds.first, clouds.second, m->params, ctx);
        g.time_voxelize_ms = clouds.first.time_voxelize_ms + clouds.second.time_voxelize_ms;
        g.time_features_ms = clouds.first.time_features_ms + clouds.second.time_features_ms;
        fill_result(g, result);
        return ok();
    });
}

int32_t kissm_features_compute(kissm_matcher *matcher, const kissm_points *cloud, kissm_features **out_features) {
    return guarded("kissm_features_compute", [&] {
        kissm_matcher *m = require_matcher(matcher);
        if (out_features == nullptr) arg_fail(ErrorKind::NullArgument, "out_features is NULL");
        const kissm::detail::PointsView v = points_view(cloud, "cloud");
        m->cancel_requested.store(0);
        kissm::detail::RunContext ctx(m->params.num_threads, &m->cancel_requested, hooks_of(m->config));
        auto *f = new kissm_features();
        try {
            f->data = kissm::detail::describe_cloud(v, m->params, "cloud", ctx);
        } catch (...) {
            delete f;
            throw;
        }
        *out_features = f;
        return ok();
    });
}

void kissm_features_destroy(kissm_features *features) { delete features; }

uint64_t kissm_features_num_points(const kissm_features *f) { return f ? f->data.num_points : 0; }
uint64_t kissm_features_num_voxels(const kissm_features *f) { return f ? f->data.voxels.points.size() : 0; }
uint64_t kissm_features_num_keypoints(const kissm_features *f) { return f ? f->data.descriptors.keypoint.size() : 0; }

int32_t kissm_register_features(kissm_matcher *matcher, const kissm_features *source, const kissm_features *target,
                                kissm_result *result) {
    return with_result("kissm_register_features", result, [&] {
        kissm_matcher *m = require_matcher(matcher);
        if (source == nullptr) arg_fail(ErrorKind::NullArgument, "source is NULL");
        if (target == nullptr) arg_fail(ErrorKind::NullArgument, "target is NULL");
        if (!kissm::detail::same_descriptor_settings(source->data.params, m->params))
            arg_fail(ErrorKind::FeaturesMismatch, "source features were computed with descriptor settings (voxel size, "
                                                  "radii, tau, viewpoint) that differ from the matcher's");
        if (!kissm::detail::same_descriptor_settings(target->data.params, m->params))
            arg_fail(ErrorKind::FeaturesMismatch, "target features were computed with descriptor settings (voxel size, "
                                                  "radii, tau, viewpoint) that differ from the matcher's");
        m->cancel_requested.store(0);
        kissm::detail::RunContext ctx(m->params.num_threads, &m->cancel_requested, hooks_of(m->config));
        const kissm::detail::Registration g =
            kissm::detail::register_described(source->data, target->data, m->params, ctx);
        fill_result(g, result);
        return ok();
    });
}

int32_t kissm_read_points(const char *path, int32_t format, kissm_cloud **out_cloud) {
    return guarded("kissm_read_points", [&] {
        if (path == nullptr) arg_fail(ErrorKind::NullArgument, "path is NULL");
        if (out_cloud == nullptr) arg_fail(ErrorKind::NullArgument, "out_cloud is NULL");
        if (format < KISSM_FORMAT_AUTO || format > KISSM_FORMAT_BIN_XYZ)
            arg_fail(ErrorKind::InvalidArgument,
                     "format is " + std::to_string(format) + "; use a KISSM_FORMAT_* value");
        auto *c = new kissm_cloud();
        try {
            c->xyz = kissm::detail::read_points_file(path, static_cast<kissm::detail::FileFormat>(format));
        } catch (...) {
            delete c;
            throw;
        }
        *out_cloud = c;
        return ok();
    });
}

void kissm_cloud_destroy(kissm_cloud *cloud) { delete cloud; }
uint64_t kissm_cloud_count(const kissm_cloud *cloud) { return cloud ? cloud->xyz.size() / 3 : 0; }
const double *kissm_cloud_data(const kissm_cloud *cloud) {
    return (cloud && !cloud->xyz.empty()) ? cloud->xyz.data() : nullptr;
}

int32_t kissm_cloud_points(const kissm_cloud *cloud, kissm_points *out_points) {
    return guarded("kissm_cloud_points", [&] {
        if (cloud == nullptr) arg_fail(ErrorKind::NullArgument, "cloud is NULL");
        if (out_points == nullptr) arg_fail(ErrorKind::NullArgument, "out_points is NULL");
        out_points->data = cloud->xyz.empty() ? nullptr : cloud->xyz.data();
        out_points->count = cloud->xyz.size() / 3;
        out_points->stride_bytes = 3 * sizeof(double);
        out_points->scalar_type = KISSM_SCALAR_FLOAT64;
        out_points->reserved = 0;
        return ok();
    });
}

uint32_t kissm_abi_sizeof(int32_t which) {
    switch (which) {
    case KISSM_STRUCT_CONFIG: return sizeof(kissm_config);
    case KISSM_STRUCT_POINTS: return sizeof(kissm_points);
    case KISSM_STRUCT_RESULT: return sizeof(kissm_result);
    default: return 0;
    }
}

} // extern "C"
