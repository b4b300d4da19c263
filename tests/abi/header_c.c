/* SPDX-License-Identifier: MIT */
/* Compile-only test of the public header from C. The abi_header_c99 and abi_header_c11 tests compile this
 * file with -std=c99 / -std=c11 -Wall -Wextra -pedantic -Werror -Wstrict-prototypes -Wpadded (and a few
 * more): kissm.h must be warning-free, self-contained (it is included first) and padding-free.
 *
 * It also pins the API: every constant's value (codes are never renumbered) and every function's exact
 * signature. A change here is an API or ABI change; docs/abi-policy.md says which ones are allowed. */
#include "kissm.h"
#include "kissm.h" /* the include guard works */

/* C99 has no _Static_assert: a negative array size fails the compilation. */
#define PIN(name, value) typedef char pinned_##name[(name) == (value) ? 1 : -1];

PIN(KISSM_ABI_VERSION, 0)
PIN(KISSM_VERSION_NUMBER, KISSM_VERSION_MAJOR * 10000 + KISSM_VERSION_MINOR * 100 + KISSM_VERSION_PATCH)

PIN(KISSM_OK, 0)
PIN(KISSM_ERR_INVALID_ARGUMENT, -1)
PIN(KISSM_ERR_NULL_ARGUMENT, -2)
PIN(KISSM_ERR_EMPTY_INPUT, -3)
PIN(KISSM_ERR_TOO_FEW_POINTS, -4)
PIN(KISSM_ERR_NONFINITE, -5)
PIN(KISSM_ERR_VOXEL_RANGE, -6)
PIN(KISSM_ERR_STRUCT_SIZE, -7)
PIN(KISSM_ERR_OUT_OF_MEMORY, -8)
PIN(KISSM_ERR_CANCELLED, -9)
PIN(KISSM_ERR_FEATURES_MISMATCH, -10)
PIN(KISSM_ERR_IO, -11)
PIN(KISSM_ERR_PARSE, -12)
PIN(KISSM_ERR_UNSUPPORTED_FORMAT, -13)
PIN(KISSM_ERR_INTERNAL, -14)

PIN(KISSM_MIN_POINTS, 4)

PIN(KISSM_REASON_NONE, 0)
PIN(KISSM_REASON_TOO_FEW_VOXELS, 1)
PIN(KISSM_REASON_TOO_FEW_FEATURES, 2)
PIN(KISSM_REASON_TOO_FEW_CORRESPONDENCES, 3)
PIN(KISSM_REASON_SOLVER_FAILED, 4)
PIN(KISSM_REASON_TOO_FEW_INLIERS, 5)
PIN(KISSM_REASON_DEGENERATE, 6)

PIN(KISSM_NONFINITE_REJECT, 0)
PIN(KISSM_NONFINITE_DROP, 1)
PIN(KISSM_VIEWPOINT_FIXED, 0)
PIN(KISSM_VIEWPOINT_CLOUD_CENTER, 1)
PIN(KISSM_VIEWPOINT_SIGN_FREE, 2)
PIN(KISSM_VIEWPOINT_LOCAL, 3)

PIN(KISSM_LOG_ERROR, 1)
PIN(KISSM_LOG_WARN, 2)
PIN(KISSM_LOG_INFO, 3)
PIN(KISSM_LOG_DEBUG, 4)

PIN(KISSM_STAGE_VOXELIZE, 1)
PIN(KISSM_STAGE_FEATURES, 2)
PIN(KISSM_STAGE_MATCHING, 3)
PIN(KISSM_STAGE_PRUNING, 4)
PIN(KISSM_STAGE_SOLVER, 5)

PIN(KISSM_SCALAR_FLOAT32, 1)
PIN(KISSM_SCALAR_FLOAT64, 2)

PIN(KISSM_FORMAT_AUTO, 0)
PIN(KISSM_FORMAT_PLY, 1)
PIN(KISSM_FORMAT_PCD, 2)
PIN(KISSM_FORMAT_KITTI_BIN, 3)
PIN(KISSM_FORMAT_NPY, 4)
PIN(KISSM_FORMAT_XYZ, 5)
PIN(KISSM_FORMAT_BIN_XYZ, 6)
PIN(KISSM_FORMAT_LAS, 7)

PIN(KISSM_STRUCT_CONFIG, 1)
PIN(KISSM_STRUCT_POINTS, 2)
PIN(KISSM_STRUCT_RESULT, 3)
PIN(KISSM_STRUCT_ALIGN_OPTIONS, 4)

PIN(KISSM_PAIRS_ALL, 0)
PIN(KISSM_PAIRS_SEQUENCE, 1)
PIN(KISSM_PAIRS_LIST, 2)
PIN(KISSM_PAIRS_SESSIONS, 3)

PIN(KISSM_SIGNATURE_SIZE, 82)

/* The version string is a string literal. */
const char kissm_header_test_version[] = KISSM_VERSION_STRING;

/* Every function, with its exact type: a changed parameter or return type fails the compilation. */
struct kissm_header_test_api {
    uint32_t (*version_number)(void);
    const char *(*version_string)(void);
    uint32_t (*abi_version)(void);
    const char *(*status_string)(int32_t);
    const char *(*last_error_message)(void);
    const char *(*reason_string)(int32_t);
    int32_t (*config_init)(kissm_config *, uint32_t);
    int32_t (*config_validate)(const kissm_config *);
    int32_t (*create)(const kissm_config *, kissm_matcher **);
    void (*destroy)(kissm_matcher *);
    int32_t (*get_config)(const kissm_matcher *, kissm_config *);
    int32_t (*register_points)(kissm_matcher *, const kissm_points *, const kissm_points *, kissm_result *);
    void (*cancel)(kissm_matcher *);
    int32_t (*features_compute)(kissm_matcher *, const kissm_points *, kissm_features **);
    void (*features_destroy)(kissm_features *);
    uint64_t (*features_num_points)(const kissm_features *);
    uint64_t (*features_num_voxels)(const kissm_features *);
    uint64_t (*features_num_keypoints)(const kissm_features *);
    uint64_t (*features_memory_bytes)(const kissm_features *);
    int32_t (*register_features)(kissm_matcher *, const kissm_features *, const kissm_features *, kissm_result *);
    int32_t (*features_serialize)(const kissm_features *, void *, uint64_t, uint64_t *);
    int32_t (*features_deserialize)(const void *, uint64_t, kissm_features **);
    int32_t (*features_signature)(const kissm_features *, double *);
    int32_t (*read_points)(const char *, int32_t, kissm_cloud **);
    void (*cloud_destroy)(kissm_cloud *);
    uint64_t (*cloud_count)(const kissm_cloud *);
    uint64_t (*cloud_num_withheld)(const kissm_cloud *);
    const double *(*cloud_data)(const kissm_cloud *);
    int32_t (*cloud_points)(const kissm_cloud *, kissm_points *);
    int32_t (*align_options_init)(kissm_align_options *, uint32_t);
    int32_t (*align_features)(kissm_matcher *, const kissm_features *const *, uint64_t, const kissm_align_options *,
                              kissm_alignment **);
    void (*alignment_destroy)(kissm_alignment *);
    uint64_t (*alignment_num_scans)(const kissm_alignment *);
    uint64_t (*alignment_num_registrations)(const kissm_alignment *);
    int32_t (*alignment_poses)(const kissm_alignment *, double *, uint8_t *, uint64_t *);
    int32_t (*alignment_registration)(const kissm_alignment *, uint64_t, uint64_t *, uint64_t *, kissm_result *,
                                      int32_t *, double *, double *);
    int32_t (*sequence_loops)(uint64_t, const double *, const uint8_t *, const double *, double, uint64_t, uint64_t,
                              uint64_t *, uint64_t, uint64_t *);
    int32_t (*sequence_similar)(uint64_t, const uint8_t *, const double *, uint64_t, uint64_t, uint64_t *, uint64_t,
                                uint64_t *);
    int32_t (*sequence_corroborated)(uint64_t, const double *, const uint8_t *, double, uint64_t, const uint64_t *,
                                     const double *, uint8_t *);
    uint32_t (*abi_sizeof)(int32_t);
};

const struct kissm_header_test_api kissm_header_test_api = {
    .version_number = kissm_version_number,
    .version_string = kissm_version_string,
    .abi_version = kissm_abi_version,
    .status_string = kissm_status_string,
    .last_error_message = kissm_last_error_message,
    .reason_string = kissm_reason_string,
    .config_init = kissm_config_init,
    .config_validate = kissm_config_validate,
    .create = kissm_create,
    .destroy = kissm_destroy,
    .get_config = kissm_get_config,
    .register_points = kissm_register,
    .cancel = kissm_cancel,
    .features_compute = kissm_features_compute,
    .features_destroy = kissm_features_destroy,
    .features_num_points = kissm_features_num_points,
    .features_num_voxels = kissm_features_num_voxels,
    .features_num_keypoints = kissm_features_num_keypoints,
    .features_memory_bytes = kissm_features_memory_bytes,
    .register_features = kissm_register_features,
    .features_serialize = kissm_features_serialize,
    .features_deserialize = kissm_features_deserialize,
    .features_signature = kissm_features_signature,
    .read_points = kissm_read_points,
    .cloud_destroy = kissm_cloud_destroy,
    .cloud_count = kissm_cloud_count,
    .cloud_num_withheld = kissm_cloud_num_withheld,
    .cloud_data = kissm_cloud_data,
    .cloud_points = kissm_cloud_points,
    .align_options_init = kissm_align_options_init,
    .align_features = kissm_align_features,
    .alignment_destroy = kissm_alignment_destroy,
    .alignment_num_scans = kissm_alignment_num_scans,
    .alignment_num_registrations = kissm_alignment_num_registrations,
    .alignment_poses = kissm_alignment_poses,
    .alignment_registration = kissm_alignment_registration,
    .sequence_loops = kissm_sequence_loops,
    .sequence_similar = kissm_sequence_similar,
    .sequence_corroborated = kissm_sequence_corroborated,
    .abi_sizeof = kissm_abi_sizeof,
};

/* The callback typedefs accept plain C functions with these exact types. */
static void log_to_nowhere(void *user_data, int32_t level, const char *message) {
    (void)user_data;
    (void)level;
    (void)message;
}
static int32_t never_cancel(void *user_data, int32_t stage, double fraction) {
    (void)user_data;
    (void)stage;
    (void)fraction;
    return 0;
}
const kissm_log_fn kissm_header_test_log_fn = log_to_nowhere;
const kissm_progress_fn kissm_header_test_progress_fn = never_cancel;

/* The structs are complete types usable in C declarations and initialisers. */
kissm_config kissm_header_test_config;
kissm_result kissm_header_test_result;
kissm_align_options kissm_header_test_align_options;
const kissm_points kissm_header_test_points = {NULL, 0, 0, KISSM_SCALAR_FLOAT64, 0};
