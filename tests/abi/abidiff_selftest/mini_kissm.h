/* SPDX-License-Identifier: MIT */
/* A miniature kissm.h for abidiff_selftest.sh: each MINI_* macro makes one kind of change to it, so that
 * the self-test can check which changes check_abi.sh (abidiff + kissm.abignore) accepts and which it
 * rejects. Same struct names as kissm.h, because kissm.abignore matches them by name. */
#ifndef MINI_KISSM_H
#define MINI_KISSM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct kissm_config {
    uint32_t struct_size;
#ifdef MINI_FIELD_TYPE
    uint32_t num_threads; /* was int32_t */
#else
    int32_t num_threads;
#endif
#ifdef MINI_REORDER
    double ratio_test; /* swapped with voxel_size */
    double voxel_size;
#else
    double voxel_size;
    double ratio_test;
#endif
#ifdef MINI_APPEND_CONFIG
    double appended_gain;
    int32_t appended_mode;
    int32_t appended_reserved;
#endif
} kissm_config;

typedef struct kissm_points {
    const void *data;
    uint64_t count;
#ifdef MINI_APPEND_POINTS
    uint64_t appended_stride; /* kissm_points has no struct_size: frozen */
#endif
} kissm_points;

typedef struct kissm_result {
    uint32_t struct_size;
#ifdef MINI_RESULT_FIELD_TYPE
    uint32_t valid; /* was int32_t */
#else
    int32_t valid;
#endif
    double transform[16];
#ifdef MINI_APPEND_RESULT
    uint64_t appended_count;
#endif
} kissm_result;

typedef struct kissm_matcher kissm_matcher;

int32_t kissm_config_init(kissm_config *config, uint32_t struct_size);
#ifdef MINI_PARAM_TYPE
int32_t kissm_create(const kissm_config *config, int64_t flags, kissm_matcher **out_matcher);
#else
int32_t kissm_create(const kissm_config *config, int32_t flags, kissm_matcher **out_matcher);
#endif
int32_t kissm_register(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                       kissm_result *result);
#ifdef MINI_RETURN_TYPE
uint32_t kissm_count(const kissm_points *points);
#else
uint64_t kissm_count(const kissm_points *points);
#endif
#ifndef MINI_REMOVE_FUNCTION
void kissm_cancel(kissm_matcher *matcher);
#endif
#ifdef MINI_ADD_FUNCTION
uint32_t kissm_new_function(const kissm_config *config);
#endif

#ifdef __cplusplus
}
#endif

#endif
