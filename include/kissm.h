/* SPDX-License-Identifier: MIT */
/*
 * kissm: fast, robust, deterministic global 3D point cloud registration.
 *
 * The only public header of the library. C99 and C++ compatible; fixed-width types only; no enum types,
 * no bool and no compiler-specific types cross this boundary (constants are #defines on int32_t values).
 *
 * Conventions
 *  - Every fallible function returns an int32_t status: KISSM_OK (0) or a negative KISSM_ERR_* code.
 *    Codes are never renumbered. kissm_status_string() gives a static description of a code and
 *    kissm_last_error_message() the detailed message of the last failure on the calling thread.
 *  - Output parameters come last. On failure nothing is written to them, except that a kissm_result
 *    passed to a registration call is always fully overwritten (valid = 0, NaN pose) so that a failed or
 *    invalid call can never hand back an older pose.
 *  - The library never prints, never aborts, never keeps a caller's pointer after a call returns, and
 *    creates no thread outside a call.
 *  - Structs that may grow (kissm_config, kissm_result) start with struct_size; fields are only appended.
 */
#ifndef KISSM_H
#define KISSM_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#  if defined(KISSM_BUILDING_DLL)
#    define KISSM_API __declspec(dllexport)
#  elif defined(KISSM_DLL)
#    define KISSM_API __declspec(dllimport)
#  else
#    define KISSM_API
#  endif
#elif defined(__GNUC__) || defined(__clang__)
#  define KISSM_API __attribute__((visibility("default")))
#else
#  define KISSM_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------------ */
/* Version                                                                                          */
/* ------------------------------------------------------------------------------------------------ */

#define KISSM_VERSION_MAJOR 0
#define KISSM_VERSION_MINOR 1
#define KISSM_VERSION_PATCH 0
#define KISSM_VERSION_NUMBER (KISSM_VERSION_MAJOR * 10000 + KISSM_VERSION_MINOR * 100 + KISSM_VERSION_PATCH)
#define KISSM_VERSION_STRING "0.1.0"
/* Bumped only when the ABI breaks; equals the shared library's SOVERSION. */
#define KISSM_ABI_VERSION 0

/* Runtime twins of the macros above; bindings compare them with the header they were built from. */
KISSM_API uint32_t kissm_version_number(void);
KISSM_API const char *kissm_version_string(void);
KISSM_API uint32_t kissm_abi_version(void);

/* ------------------------------------------------------------------------------------------------ */
/* Status codes (values are pinned forever)                                                        */
/* ------------------------------------------------------------------------------------------------ */

#define KISSM_OK 0
#define KISSM_ERR_INVALID_ARGUMENT -1    /* a config value or argument is out of its documented range */
#define KISSM_ERR_NULL_ARGUMENT -2       /* a required pointer is NULL */
#define KISSM_ERR_EMPTY_INPUT -3         /* a cloud has no points (or none left after dropping non-finite ones) */
#define KISSM_ERR_TOO_FEW_POINTS -4      /* a cloud has fewer than KISSM_MIN_POINTS points */
#define KISSM_ERR_NONFINITE -5           /* a NaN or infinite coordinate under KISSM_NONFINITE_REJECT */
#define KISSM_ERR_VOXEL_RANGE -6         /* the voxel size is too small for the cloud's extent */
#define KISSM_ERR_STRUCT_SIZE -7         /* struct_size too small, above 65536, or with a non-zero unknown tail */
#define KISSM_ERR_OUT_OF_MEMORY -8       /* an allocation failed; nothing was changed */
#define KISSM_ERR_CANCELLED -9           /* kissm_cancel() or the progress callback stopped the call */
#define KISSM_ERR_FEATURES_MISMATCH -10  /* features computed under a different configuration */
#define KISSM_ERR_IO -11                 /* a file could not be opened or read */
#define KISSM_ERR_PARSE -12              /* a file is malformed, truncated or of an unsupported layout */
#define KISSM_ERR_UNSUPPORTED_FORMAT -13 /* a file's format is not recognised */
#define KISSM_ERR_INTERNAL -14           /* a bug in kissm: please report it with the message */

/* Static, never-NULL description of a status code ("unknown status" for unknown values). */
KISSM_API const char *kissm_status_string(int32_t status);
/* Detailed message of the last failing kissm_* call on this thread, naming the offending argument.
 * Library-owned; valid until the next kissm_* call on this thread; "" when the last call succeeded. */
KISSM_API const char *kissm_last_error_message(void);

/* Fewest points a cloud may have before kissm_register() refuses it with KISSM_ERR_TOO_FEW_POINTS. */
#define KISSM_MIN_POINTS 4

/* ------------------------------------------------------------------------------------------------ */
/* Reasons for valid = 0 (a well-formed input that gives no trustworthy pose is not an error)       */
/* ------------------------------------------------------------------------------------------------ */

#define KISSM_REASON_NONE 0                    /* valid = 1, or the call failed (see its status) */
#define KISSM_REASON_TOO_FEW_VOXELS 1          /* a cloud has too few occupied voxels to describe */
#define KISSM_REASON_TOO_FEW_FEATURES 2        /* a cloud has too few points with a reliable descriptor */
#define KISSM_REASON_TOO_FEW_CORRESPONDENCES 3 /* matching or pruning left too few correspondences */
#define KISSM_REASON_SOLVER_FAILED 4           /* the robust solver found no consistent rotation */
#define KISSM_REASON_TOO_FEW_INLIERS 5         /* final inliers below config.min_inliers */
#define KISSM_REASON_DEGENERATE 6              /* the inliers are collinear or planar: the pose is ambiguous */

KISSM_API const char *kissm_reason_string(int32_t reason);

/* ------------------------------------------------------------------------------------------------ */
/* Configuration                                                                                    */
/* ------------------------------------------------------------------------------------------------ */

/* Non-finite policy. */
#define KISSM_NONFINITE_REJECT 0 /* a NaN/Inf coordinate fails the call with KISSM_ERR_NONFINITE */
#define KISSM_NONFINITE_DROP 1   /* such points are skipped and counted in the result */

/* Where normals are oriented toward. */
#define KISSM_VIEWPOINT_FIXED 0        /* config.viewpoint, in each cloud's own input frame (the sensor) */
#define KISSM_VIEWPOINT_CLOUD_CENTER 1 /* each cloud's bounding-box centre (maps, no sensor) */

/* Log levels for kissm_log_fn. */
#define KISSM_LOG_ERROR 1
#define KISSM_LOG_WARN 2
#define KISSM_LOG_INFO 3
#define KISSM_LOG_DEBUG 4

/* Pipeline stages, as reported to kissm_progress_fn. */
#define KISSM_STAGE_VOXELIZE 1
#define KISSM_STAGE_FEATURES 2
#define KISSM_STAGE_MATCHING 3
#define KISSM_STAGE_PRUNING 4
#define KISSM_STAGE_SOLVER 5

/* Called on the calling thread only, never concurrently; must not call back into the same matcher. */
typedef void (*kissm_log_fn)(void *user_data, int32_t level, const char *message);
/* Called on the calling thread at stage boundaries and within long stages; return non-zero to cancel.
 * Stages never go back within a call and fractions never decrease within a stage; the last call of a
 * registration that ran to the end is (KISSM_STAGE_SOLVER, 1.0). */
typedef int32_t (*kissm_progress_fn)(void *user_data, int32_t stage, double fraction);

typedef struct kissm_config {
    uint32_t struct_size; /* sizeof(kissm_config) as the caller knows it; set by kissm_config_init */
    int32_t num_threads;  /* worker threads, 0..1024; 0 = all hardware threads. Results do not depend on it. */

    double voxel_size;              /* metres (or the cloud's unit); > 0. Every length below scales with it. 0.3 */
    double normal_radius_gain;      /* normal radius = gain * voxel_size; in (0, fpfh_radius_gain]; 3.5 (paper) */
    double fpfh_radius_gain;        /* FPFH radius = gain * voxel_size; in [1.5, 50] and >= normal gain; 5.0 */
    double max_linearity;           /* tau_lin: (l1 - l2) / l1 above this gets no normal; in (0, 1]; 0.99 */
    double ratio_test;              /* Lowe ratio on squared descriptor distances, in (0, 1]; 1 = off; 0.9 */
    double prune_noise_bound_gain;  /* graph edge when length mismatch <= gain * voxel_size; in (0, 1e6]; 1.0 */
    double solver_noise_bound_gain; /* solver inlier bound = gain * voxel_size; in (0, 1e6]; 0.75 */
    double noise_bound_max;         /* cap on both noise bounds in metres, finite; 0 = no cap; 0 */
    double viewpoint[3];            /* for KISSM_VIEWPOINT_FIXED: the sensor position, finite; (0, 0, 0) */

    int32_t min_normal_neighbors; /* tau_num: neighbours needed for a normal and a descriptor; 3..100000; 3 */
    int32_t max_correspondences;  /* cap on mutual matches kept (best ratio first); 3..100000; 5000 */
    int32_t min_inliers;          /* valid needs at least this many final inliers; 3..100000; 15 */
    int32_t nonfinite_policy;     /* KISSM_NONFINITE_*; KISSM_NONFINITE_REJECT */
    int32_t viewpoint_mode;       /* KISSM_VIEWPOINT_*; KISSM_VIEWPOINT_FIXED */
    int32_t log_level;            /* most verbose level passed to log_fn, 0 (none)..4; KISSM_LOG_WARN */

    kissm_log_fn log_fn; /* NULL = silent */
    void *log_user_data;
    kissm_progress_fn progress_fn; /* NULL = none */
    void *progress_user_data;
    /* New fields are only ever appended here. */
} kissm_config;

/* Writes the documented defaults into the first struct_size bytes of *config and sets
 * config->struct_size = struct_size. Pass sizeof(kissm_config). Fails with KISSM_ERR_STRUCT_SIZE when
 * struct_size is smaller than the first published layout. */
KISSM_API int32_t kissm_config_init(kissm_config *config, uint32_t struct_size);
/* Checks every field; KISSM_OK or KISSM_ERR_INVALID_ARGUMENT / KISSM_ERR_STRUCT_SIZE with a message
 * naming the field. kissm_create() performs the same checks. */
KISSM_API int32_t kissm_config_validate(const kissm_config *config);

/* ------------------------------------------------------------------------------------------------ */
/* Points: a borrowed, zero-copy view of the caller's xyz coordinates                               */
/* ------------------------------------------------------------------------------------------------ */

#define KISSM_SCALAR_FLOAT32 1
#define KISSM_SCALAR_FLOAT64 2

typedef struct kissm_points {
    const void *data;      /* first point's x; y and z follow contiguously. Read during the call only. */
    uint64_t count;        /* number of points, at most 4294967295 */
    uint64_t stride_bytes; /* bytes from one point to the next; 0 = packed (3 scalars) */
    int32_t scalar_type;   /* KISSM_SCALAR_FLOAT32 or KISSM_SCALAR_FLOAT64 */
    int32_t reserved;      /* must be 0 */
} kissm_points;

/* ------------------------------------------------------------------------------------------------ */
/* Result                                                                                           */
/* ------------------------------------------------------------------------------------------------ */

typedef struct kissm_result {
    uint32_t struct_size; /* set by the caller to sizeof(kissm_result) */
    int32_t valid;        /* 1 when the pose can be trusted (see reason and the counts) */
    int32_t reason;       /* KISSM_REASON_* when valid = 0 */
    int32_t reserved0;

    /* Maps source points into the target frame: p_t = R p_s + t. Row-major. NaN when no pose was
     * estimated; when valid = 0 but a pose was estimated it is kept here for inspection. */
    double transform[16];
    double rotation[9];
    double translation[3];

    uint64_t num_source_points; /* points given */
    uint64_t num_target_points;
    uint64_t num_source_nonfinite; /* points dropped under KISSM_NONFINITE_DROP */
    uint64_t num_target_nonfinite;
    uint64_t num_source_voxels; /* occupied voxels */
    uint64_t num_target_voxels;
    uint64_t num_source_keypoints; /* voxels with a descriptor */
    uint64_t num_target_keypoints;
    uint64_t num_initial_correspondences; /* mutual, ratio-tested, capped matches */
    uint64_t num_pruned_correspondences;  /* the maximum k-core */
    uint64_t num_rotation_inliers;        /* pruned correspondences the rotation solver kept */
    uint64_t num_final_inliers;           /* pruned correspondences within the solver bound after R, t */
    uint64_t max_core_number;             /* k of the maximum k-core */

    double inlier_ratio;     /* num_final_inliers / num_initial_correspondences (0 when none) */
    double residual_rms;     /* RMS of |R a + t - b| over final inliers, metres (NaN when none) */
    double noise_bound;      /* solver inlier bound used, metres */
    double inlier_extent[3]; /* sqrt of the eigenvalues (descending) of the inliers' source covariance */

    /* Wall-clock milliseconds per stage; time_total_ms is their sum. Stages not run are 0. Timings are
     * the only fields that differ between identical calls. */
    double time_voxelize_ms; /* input checks, recentring and voxelisation */
    double time_features_ms; /* neighbour search, normals, FPFH */
    double time_matching_ms; /* descriptor matching */
    double time_pruning_ms;  /* compatibility graph and max k-core */
    double time_solver_ms;   /* GNC-TLS rotation, translation, inliers, validity */
    double time_total_ms;
    /* New fields are only ever appended here. */
} kissm_result;

/* Prepares a result for a registration call: writes struct_size and leaves the rest as a failed call
 * does (valid = 0, counts 0, NaN pose). Pass sizeof(kissm_result). Optional (setting struct_size by hand
 * is enough); fails with KISSM_ERR_NULL_ARGUMENT or KISSM_ERR_STRUCT_SIZE (below the first published
 * layout, or above 65536) and then writes nothing. */
KISSM_API int32_t kissm_result_init(kissm_result *result, uint32_t struct_size);

/* ------------------------------------------------------------------------------------------------ */
/* Matcher                                                                                          */
/* ------------------------------------------------------------------------------------------------ */

/* Mutable; used by one thread at a time (kissm_cancel excepted). Distinct matchers run concurrently. */
typedef struct kissm_matcher kissm_matcher;

/* config NULL = defaults. The config is validated and copied. */
KISSM_API int32_t kissm_create(const kissm_config *config, kissm_matcher **out_matcher);
KISSM_API void kissm_destroy(kissm_matcher *matcher); /* NULL is fine */
/* Copies the matcher's config into *out (whose struct_size the caller sets). */
KISSM_API int32_t kissm_get_config(const kissm_matcher *matcher, kissm_config *out_config);

/* Global registration of source against target. The result is always fully overwritten. Returns KISSM_OK
 * whenever the inputs were acceptable, including when result->valid is 0. */
KISSM_API int32_t kissm_register(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                                 kissm_result *result);

/* Requests that the call running on matcher stop with KISSM_ERR_CANCELLED. Safe from any thread. A
 * request made while no call is running is cleared when the next call starts. */
KISSM_API void kissm_cancel(kissm_matcher *matcher);

/* ------------------------------------------------------------------------------------------------ */
/* Features: a cloud described once, matched against many                                           */
/* ------------------------------------------------------------------------------------------------ */

/* Immutable once created; may be used from several threads at once and outlive the matcher. */
typedef struct kissm_features kissm_features;

KISSM_API int32_t kissm_features_compute(kissm_matcher *matcher, const kissm_points *cloud,
                                         kissm_features **out_features);
KISSM_API void kissm_features_destroy(kissm_features *features);                 /* NULL is fine */
KISSM_API uint64_t kissm_features_num_points(const kissm_features *features);    /* 0 for NULL */
KISSM_API uint64_t kissm_features_num_voxels(const kissm_features *features);    /* 0 for NULL */
KISSM_API uint64_t kissm_features_num_keypoints(const kissm_features *features); /* 0 for NULL */
/* Same pose, counts and validity as kissm_register() on the clouds the features were computed from.
 * Fails with KISSM_ERR_FEATURES_MISMATCH when either was computed under a config whose descriptor
 * parameters differ from matcher's. Voxelisation and feature times are reported as 0. */
KISSM_API int32_t kissm_register_features(kissm_matcher *matcher, const kissm_features *source,
                                          const kissm_features *target, kissm_result *result);

/* ------------------------------------------------------------------------------------------------ */
/* Point files: PLY (ascii, binary), PCD (ascii, binary), KITTI .bin (float32 xyzi), .npy (float32 /  */
/* float64, shape (N, 3) or (N, >=3)), whitespace xyz text (.xyz, .txt, .pts, .asc)                   */
/* ------------------------------------------------------------------------------------------------ */

#define KISSM_FORMAT_AUTO 0 /* by extension, then by content */
#define KISSM_FORMAT_PLY 1
#define KISSM_FORMAT_PCD 2
#define KISSM_FORMAT_KITTI_BIN 3 /* float32 x y z intensity */
#define KISSM_FORMAT_NPY 4
#define KISSM_FORMAT_XYZ 5
#define KISSM_FORMAT_BIN_XYZ 6 /* float32 x y z, no intensity */

/* A cloud owned by the library, as read from a file: float64 xyz, packed. */
typedef struct kissm_cloud kissm_cloud;

/* path is UTF-8. Non-finite points are kept as they are (the registration policy decides). */
KISSM_API int32_t kissm_read_points(const char *path, int32_t format, kissm_cloud **out_cloud);
KISSM_API void kissm_cloud_destroy(kissm_cloud *cloud);         /* NULL is fine */
KISSM_API uint64_t kissm_cloud_count(const kissm_cloud *cloud); /* 0 for NULL */
/* Pointer to count * 3 doubles, valid until kissm_cloud_destroy(); NULL for NULL or an empty cloud. */
KISSM_API const double *kissm_cloud_data(const kissm_cloud *cloud);
/* Fills a kissm_points view of the cloud (float64, packed). */
KISSM_API int32_t kissm_cloud_points(const kissm_cloud *cloud, kissm_points *out_points);

/* ------------------------------------------------------------------------------------------------ */
/* ABI self-check for bindings                                                                      */
/* ------------------------------------------------------------------------------------------------ */

#define KISSM_STRUCT_CONFIG 1
#define KISSM_STRUCT_POINTS 2
#define KISSM_STRUCT_RESULT 3

/* sizeof() of the public struct as compiled into the library; 0 for an unknown id. */
KISSM_API uint32_t kissm_abi_sizeof(int32_t which);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* KISSM_H */
