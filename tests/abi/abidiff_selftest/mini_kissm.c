/* SPDX-License-Identifier: MIT */
/* Definitions for mini_kissm.h (abidiff_selftest.sh). Nothing here is ever called. */
#include "mini_kissm.h"

#include <string.h>

struct kissm_matcher {
    kissm_config config;
    int32_t flags;
};

static struct kissm_matcher g_matcher;

int32_t kissm_config_init(kissm_config *config, uint32_t struct_size) {
    memset(config, 0, struct_size);
    config->struct_size = struct_size;
    return 0;
}

#ifdef MINI_PARAM_TYPE
int32_t kissm_create(const kissm_config *config, int64_t flags, kissm_matcher **out_matcher) {
#else
int32_t kissm_create(const kissm_config *config, int32_t flags, kissm_matcher **out_matcher) {
#endif
    g_matcher.config = *config;
    g_matcher.flags = (int32_t)flags;
    *out_matcher = &g_matcher;
    return 0;
}

int32_t kissm_register(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                       kissm_result *result) {
    result->valid = matcher != NULL && source->count > 0 && target->count > 0;
    return 0;
}

#ifdef MINI_RETURN_TYPE
uint32_t kissm_count(const kissm_points *points) { return (uint32_t)points->count; }
#else
uint64_t kissm_count(const kissm_points *points) { return points->count; }
#endif

#ifndef MINI_REMOVE_FUNCTION
void kissm_cancel(kissm_matcher *matcher) { matcher->flags = -1; }
#endif

#ifdef MINI_ADD_FUNCTION
uint32_t kissm_new_function(const kissm_config *config) { return config->struct_size; }
#endif
