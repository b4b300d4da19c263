/* SPDX-License-Identifier: MIT */
/* Versions, ABI sizes, config defaults, create/destroy, get_config, status and reason strings, the
 * thread-local last error message and kissm_result_init. C99. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

static void test_versions(void) {
    CHECK_EQ_INT(kissm_version_number(), KISSM_VERSION_NUMBER);
    CHECK_EQ_INT(kissm_abi_version(), KISSM_ABI_VERSION);
    REQUIRE(kissm_version_string() != NULL);
    CHECK(strcmp(kissm_version_string(), KISSM_VERSION_STRING) == 0);
    CHECK_EQ_INT(KISSM_VERSION_NUMBER, KISSM_VERSION_MAJOR * 10000 + KISSM_VERSION_MINOR * 100 + KISSM_VERSION_PATCH);
    {
        char expect[64];
        sprintf(expect, "%d.%d.%d", KISSM_VERSION_MAJOR, KISSM_VERSION_MINOR, KISSM_VERSION_PATCH);
        CHECK(strcmp(kissm_version_string(), expect) == 0);
    }
}

static void test_abi_sizeof(void) {
    CHECK_EQ_INT(kissm_abi_sizeof(KISSM_STRUCT_CONFIG), sizeof(kissm_config));
    CHECK_EQ_INT(kissm_abi_sizeof(KISSM_STRUCT_POINTS), sizeof(kissm_points));
    CHECK_EQ_INT(kissm_abi_sizeof(KISSM_STRUCT_RESULT), sizeof(kissm_result));
    CHECK_EQ_INT(kissm_abi_sizeof(KISSM_STRUCT_ALIGN_OPTIONS), sizeof(kissm_align_options));
    CHECK_EQ_INT(kissm_abi_sizeof(0), 0);
    CHECK_EQ_INT(kissm_abi_sizeof(5), 0);
    CHECK_EQ_INT(kissm_abi_sizeof(-1), 0);
    CHECK_EQ_INT(kissm_abi_sizeof(INT32_MAX), 0);
    CHECK_EQ_INT(kissm_abi_sizeof(INT32_MIN), 0);
    /* The layout a C compiler sees: struct_size first, fields in declaration order. */
    CHECK_EQ_INT(offsetof(kissm_config, struct_size), 0);
    CHECK_EQ_INT(offsetof(kissm_result, struct_size), 0);
    CHECK_EQ_INT(offsetof(kissm_points, data), 0);
}

static void check_defaults(const kissm_config *c, uint32_t expected_size) {
    CHECK_EQ_INT(c->struct_size, expected_size);
    CHECK_EQ_INT(c->num_threads, 0);
    CHECK(c->voxel_size == 0.3);
    CHECK(c->normal_radius_gain == 3.5);
    CHECK(c->fpfh_radius_gain == 5.0);
    CHECK(c->max_linearity == 0.99);
    CHECK(c->ratio_test == 0.9);
    CHECK(c->prune_noise_bound_gain == 1.0);
    CHECK(c->solver_noise_bound_gain == 0.75);
    CHECK(c->noise_bound_max == 0.0);
    CHECK(c->viewpoint[0] == 0.0 && c->viewpoint[1] == 0.0 && c->viewpoint[2] == 0.0);
    CHECK_EQ_INT(c->min_normal_neighbors, 3);
    CHECK_EQ_INT(c->max_correspondences, 0);
    CHECK_EQ_INT(c->min_inliers, 15);
    CHECK_EQ_INT(c->nonfinite_policy, KISSM_NONFINITE_REJECT);
    CHECK_EQ_INT(c->viewpoint_mode, KISSM_VIEWPOINT_LOCAL);
    CHECK_EQ_INT(c->log_level, KISSM_LOG_WARN);
    CHECK(c->log_fn == NULL);
    CHECK(c->log_user_data == NULL);
    CHECK(c->progress_fn == NULL);
    CHECK(c->progress_user_data == NULL);
    /* Refinement is off by default (the solver's pose as before); its settings are the library's to tune, so
     * only their documented ranges are checked here. */
    CHECK_EQ_INT(c->refine_mode, KISSM_REFINE_NONE);
    CHECK(c->refine_max_iterations >= 1 && c->refine_max_iterations <= 1000);
    CHECK(c->refine_max_distance_gain > 0.0 && c->refine_max_distance_gain <= 100.0);
    CHECK(c->refine_kernel_gain > 0.0 && c->refine_kernel_gain <= 100.0);
    CHECK(c->refine_rotation_epsilon >= 0.0 && c->refine_rotation_epsilon <= 1.0);
    CHECK(c->refine_translation_epsilon_gain >= 0.0 && c->refine_translation_epsilon_gain <= 1.0);
    CHECK(c->min_overlap >= 0.0 && c->min_overlap <= 1.0);
}

/* A caller compiled against a newer header: kissm_config followed by fields this kissm does not know. */
typedef struct newer_config {
    kissm_config base;
    double future[4];
} newer_config;

static void test_config_init(void) {
    kissm_config c;
    newer_config big;
    unsigned char buf[sizeof(kissm_config)], before[sizeof(kissm_config)];
    int i;

    memset(&c, 0x77, sizeof(c));
    CHECK_EQ_INT(kissm_config_init(&c, (uint32_t)sizeof(c)), KISSM_OK);
    check_defaults(&c, (uint32_t)sizeof(c));
    CHECK_EQ_INT(kissm_config_validate(&c), KISSM_OK);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);

    /* NULL config */
    CHECK_EQ_INT(kissm_config_init(NULL, (uint32_t)sizeof(c)), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "config") != NULL);

    /* Too small: nothing written. */
    {
        const uint32_t small_sizes[] = {0u, 4u, (uint32_t)sizeof(kissm_config) - 8u,
                                        (uint32_t)sizeof(kissm_config) - 1u};
        for (i = 0; i < (int)(sizeof(small_sizes) / sizeof(small_sizes[0])); ++i) {
            memset(buf, 0x33, sizeof(buf));
            memcpy(before, buf, sizeof(buf));
            CHECK_EQ_INT(kissm_config_init((kissm_config *)(void *)buf, small_sizes[i]), KISSM_ERR_STRUCT_SIZE);
            CHECK(memcmp(buf, before, sizeof(buf)) == 0);
            CHECK(strstr(kissm_last_error_message(), "struct_size") != NULL);
        }
    }

    /* Larger (a newer caller): defaults in the known part, the unknown tail zeroed, struct_size as given. */
    memset(&big, 0x66, sizeof(big));
    CHECK_EQ_INT(kissm_config_init(&big.base, (uint32_t)sizeof(big)), KISSM_OK);
    check_defaults(&big.base, (uint32_t)sizeof(big));
    for (i = 0; i < 4; ++i) CHECK(big.future[i] == 0.0);
    CHECK_EQ_INT(kissm_config_validate(&big.base), KISSM_OK);
}

static int32_t dummy_progress(void *user, int32_t stage, double fraction) {
    (void)user;
    (void)stage;
    (void)fraction;
    return 0;
}

static void dummy_log(void *user, int32_t level, const char *message) {
    (void)user;
    (void)level;
    (void)message;
}

static void test_create_destroy(void) {
    kissm_matcher *m = NULL;
    kissm_config c, got;
    int user_a = 1, user_b = 2;

    /* NULL config = defaults */
    CHECK_EQ_INT(kissm_create(NULL, &m), KISSM_OK);
    REQUIRE(m != NULL);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
    memset(&got, 0x44, sizeof(got));
    got.struct_size = (uint32_t)sizeof(got);
    CHECK_EQ_INT(kissm_get_config(m, &got), KISSM_OK);
    check_defaults(&got, (uint32_t)sizeof(got));
    kissm_destroy(m);

    /* Every field round-trips through create / get_config, non-default values throughout. */
    CHECK_EQ_INT(kissm_config_init(&c, (uint32_t)sizeof(c)), KISSM_OK);
    c.num_threads = 3;
    c.voxel_size = 0.125;
    c.normal_radius_gain = 2.75;
    c.fpfh_radius_gain = 6.5;
    c.max_linearity = 0.95;
    c.ratio_test = 0.8;
    c.prune_noise_bound_gain = 1.25;
    c.solver_noise_bound_gain = 0.5;
    c.noise_bound_max = 0.7;
    c.viewpoint[0] = 1.5;
    c.viewpoint[1] = -2.5;
    c.viewpoint[2] = 3.25;
    c.min_normal_neighbors = 5;
    c.max_correspondences = 1234;
    c.min_inliers = 17;
    c.nonfinite_policy = KISSM_NONFINITE_DROP;
    c.viewpoint_mode = KISSM_VIEWPOINT_CLOUD_CENTER;
    c.log_level = KISSM_LOG_DEBUG;
    c.log_fn = dummy_log;
    c.log_user_data = &user_a;
    c.progress_fn = dummy_progress;
    c.progress_user_data = &user_b;
    m = NULL;
    CHECK_EQ_INT(kissm_create(&c, &m), KISSM_OK);
    REQUIRE(m != NULL);
    /* The config is copied: changing the caller's struct afterwards changes nothing. */
    c.voxel_size = 99.0;
    c.log_fn = NULL;
    memset(&got, 0, sizeof(got));
    got.struct_size = (uint32_t)sizeof(got);
    CHECK_EQ_INT(kissm_get_config(m, &got), KISSM_OK);
    CHECK_EQ_INT(got.struct_size, sizeof(got));
    CHECK_EQ_INT(got.num_threads, 3);
    CHECK(got.voxel_size == 0.125);
    CHECK(got.normal_radius_gain == 2.75);
    CHECK(got.fpfh_radius_gain == 6.5);
    CHECK(got.max_linearity == 0.95);
    CHECK(got.ratio_test == 0.8);
    CHECK(got.prune_noise_bound_gain == 1.25);
    CHECK(got.solver_noise_bound_gain == 0.5);
    CHECK(got.noise_bound_max == 0.7);
    CHECK(got.viewpoint[0] == 1.5 && got.viewpoint[1] == -2.5 && got.viewpoint[2] == 3.25);
    CHECK_EQ_INT(got.min_normal_neighbors, 5);
    CHECK_EQ_INT(got.max_correspondences, 1234);
    CHECK_EQ_INT(got.min_inliers, 17);
    CHECK_EQ_INT(got.nonfinite_policy, KISSM_NONFINITE_DROP);
    CHECK_EQ_INT(got.viewpoint_mode, KISSM_VIEWPOINT_CLOUD_CENTER);
    CHECK_EQ_INT(got.log_level, KISSM_LOG_DEBUG);
    CHECK(got.log_fn == dummy_log);
    CHECK(got.log_user_data == &user_a);
    CHECK(got.progress_fn == dummy_progress);
    CHECK(got.progress_user_data == &user_b);

    /* get_config into a larger (newer) struct: known part copied, tail zeroed, struct_size kept. */
    {
        newer_config big;
        int i;
        memset(&big, 0x5A, sizeof(big));
        big.base.struct_size = (uint32_t)sizeof(big);
        CHECK_EQ_INT(kissm_get_config(m, &big.base), KISSM_OK);
        CHECK_EQ_INT(big.base.struct_size, sizeof(big));
        CHECK(big.base.voxel_size == 0.125);
        CHECK_EQ_INT(big.base.min_inliers, 17);
        for (i = 0; i < 4; ++i) CHECK(big.future[i] == 0.0);
    }
    /* get_config into a too small struct: STRUCT_SIZE and nothing written. */
    {
        kissm_config small, before;
        memset(&small, 0x21, sizeof(small));
        small.struct_size = (uint32_t)sizeof(small) - 8u;
        before = small;
        CHECK_EQ_INT(kissm_get_config(m, &small), KISSM_ERR_STRUCT_SIZE);
        CHECK(memcmp(&small, &before, sizeof(small)) == 0);
        CHECK(strstr(kissm_last_error_message(), "struct_size") != NULL);
    }
    CHECK_EQ_INT(kissm_get_config(NULL, &got), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "matcher") != NULL);
    CHECK_EQ_INT(kissm_get_config(m, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "out_config") != NULL);
    kissm_destroy(m);

    /* Two matchers are independent. */
    {
        kissm_matcher *a = NULL, *b = NULL;
        kissm_config ca = scn_config(0.5), cb = scn_config(0.25);
        CHECK_EQ_INT(kissm_create(&ca, &a), KISSM_OK);
        CHECK_EQ_INT(kissm_create(&cb, &b), KISSM_OK);
        REQUIRE(a != NULL && b != NULL && a != b);
        got.struct_size = (uint32_t)sizeof(got);
        CHECK_EQ_INT(kissm_get_config(a, &got), KISSM_OK);
        CHECK(got.voxel_size == 0.5);
        CHECK_EQ_INT(kissm_get_config(b, &got), KISSM_OK);
        CHECK(got.voxel_size == 0.25);
        kissm_destroy(b);
        kissm_destroy(a);
    }

    /* create with NULL out: NULL_ARGUMENT. */
    CHECK_EQ_INT(kissm_create(NULL, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "out_matcher") != NULL);

    /* Destroy functions accept NULL. */
    kissm_destroy(NULL);
    kissm_features_destroy(NULL);
    kissm_cloud_destroy(NULL);
    kissm_cancel(NULL);
    CHECK_EQ_INT(kissm_features_num_points(NULL), 0);
    CHECK_EQ_INT(kissm_features_num_voxels(NULL), 0);
    CHECK_EQ_INT(kissm_features_num_keypoints(NULL), 0);
    CHECK_EQ_INT(kissm_features_memory_bytes(NULL), 0);
    CHECK_EQ_INT(kissm_cloud_count(NULL), 0);
    CHECK(kissm_cloud_data(NULL) == NULL);
}

static const int32_t k_statuses[] = {KISSM_OK,
                                     KISSM_ERR_INVALID_ARGUMENT,
                                     KISSM_ERR_NULL_ARGUMENT,
                                     KISSM_ERR_EMPTY_INPUT,
                                     KISSM_ERR_TOO_FEW_POINTS,
                                     KISSM_ERR_NONFINITE,
                                     KISSM_ERR_VOXEL_RANGE,
                                     KISSM_ERR_STRUCT_SIZE,
                                     KISSM_ERR_OUT_OF_MEMORY,
                                     KISSM_ERR_CANCELLED,
                                     KISSM_ERR_FEATURES_MISMATCH,
                                     KISSM_ERR_IO,
                                     KISSM_ERR_PARSE,
                                     KISSM_ERR_UNSUPPORTED_FORMAT,
                                     KISSM_ERR_INTERNAL};
#define NUM_STATUSES ((int)(sizeof(k_statuses) / sizeof(k_statuses[0])))

static void test_status_strings(void) {
    int i, j;
    /* The codes are pinned forever. */
    for (i = 0; i < NUM_STATUSES; ++i) CHECK_EQ_INT(k_statuses[i], -i);
    for (i = 0; i < NUM_STATUSES; ++i) {
        const char *s = kissm_status_string(k_statuses[i]);
        CHECK_MSG(s != NULL && s[0] != '\0', "status %d", (int)k_statuses[i]);
        if (s == NULL) continue;
        CHECK_MSG(strcmp(s, "unknown status") != 0, "status %d", (int)k_statuses[i]);
        CHECK(kissm_status_string(k_statuses[i]) == s); /* static */
        for (j = 0; j < i; ++j) {
            const char *t = kissm_status_string(k_statuses[j]);
            CHECK_MSG(t != NULL && strcmp(s, t) != 0, "statuses %d and %d share \"%s\"", (int)k_statuses[i],
                      (int)k_statuses[j], s);
        }
    }
    {
        const int32_t unknown[] = {12345, 1, -15, -100, INT32_MIN, INT32_MAX};
        for (i = 0; i < 6; ++i) {
            const char *s = kissm_status_string(unknown[i]);
            CHECK(s != NULL && strcmp(s, "unknown status") == 0);
        }
    }
}

static void test_reason_strings(void) {
    const int32_t reasons[] = {KISSM_REASON_NONE,
                               KISSM_REASON_TOO_FEW_VOXELS,
                               KISSM_REASON_TOO_FEW_FEATURES,
                               KISSM_REASON_TOO_FEW_CORRESPONDENCES,
                               KISSM_REASON_SOLVER_FAILED,
                               KISSM_REASON_TOO_FEW_INLIERS,
                               KISSM_REASON_DEGENERATE,
                               KISSM_REASON_LOW_OVERLAP,
                               KISSM_REASON_UNCONSTRAINED,
                               KISSM_REASON_UNCERTAIN_ROTATION,
                               KISSM_REASON_CLUSTERED_INLIERS,
                               KISSM_REASON_NOT_CONVERGED,
                               KISSM_REASON_TILTED,
                               KISSM_REASON_LOOSE_ALIGNMENT,
                               KISSM_REASON_AMBIGUOUS,
                               KISSM_REASON_LOOSE_AND_WEAK};
    const int count = (int)(sizeof reasons / sizeof reasons[0]);
    const char *unknown = kissm_reason_string(12345);
    int i, j;
    REQUIRE(unknown != NULL && unknown[0] != '\0');
    CHECK(strstr(unknown, "unknown") != NULL);
    CHECK(kissm_reason_string(-1) != NULL && strcmp(kissm_reason_string(-1), unknown) == 0);
    CHECK(kissm_reason_string(count) != NULL && strcmp(kissm_reason_string(count), unknown) == 0);
    CHECK(kissm_reason_string(INT32_MIN) != NULL && strcmp(kissm_reason_string(INT32_MIN), unknown) == 0);
    for (i = 0; i < count; ++i) {
        const char *s = kissm_reason_string(reasons[i]);
        CHECK_EQ_INT(reasons[i], i);
        CHECK_MSG(s != NULL && s[0] != '\0', "reason %d", i);
        if (s == NULL) continue;
        CHECK_MSG(strcmp(s, unknown) != 0, "reason %d is \"%s\"", i, s);
        for (j = 0; j < i; ++j) CHECK_MSG(strcmp(s, kissm_reason_string(reasons[j])) != 0, "reasons %d and %d", i, j);
    }
}

static void test_last_error_message(void) {
    kissm_config c;
    kissm_matcher *m = NULL;
    const char *msg;

    CHECK_EQ_INT(kissm_config_init(&c, (uint32_t)sizeof(c)), KISSM_OK);
    c.voxel_size = -1.0;
    CHECK_EQ_INT(kissm_create(&c, &m), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(m == NULL);
    msg = kissm_last_error_message();
    REQUIRE(msg != NULL);
    CHECK(msg[0] != '\0');
    CHECK_MSG(strstr(msg, "voxel_size") != NULL, "message: %s", msg);

    /* A success clears it. */
    c.voxel_size = 0.5;
    CHECK_EQ_INT(kissm_config_validate(&c), KISSM_OK);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);

    c.min_inliers = 1;
    CHECK_EQ_INT(kissm_config_validate(&c), KISSM_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(kissm_last_error_message(), "min_inliers") != NULL, "message: %s", kissm_last_error_message());
    c.min_inliers = 10;
    CHECK_EQ_INT(kissm_create(&c, &m), KISSM_OK);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
    REQUIRE(m != NULL);

    /* A failing register names its argument, the next good call clears it. */
    {
        kissm_result r;
        kissm_points p;
        double xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
        memset(&p, 0, sizeof(p));
        p.data = xyz;
        p.count = 4;
        p.scalar_type = 7;
        r.struct_size = (uint32_t)sizeof(r);
        CHECK_EQ_INT(kissm_register(m, &p, &p, &r), KISSM_ERR_INVALID_ARGUMENT);
        CHECK_MSG(strstr(kissm_last_error_message(), "scalar_type") != NULL, "message: %s", kissm_last_error_message());
        CHECK(strstr(kissm_last_error_message(), "source") != NULL);
        p.scalar_type = KISSM_SCALAR_FLOAT64;
        CHECK_EQ_INT(kissm_register(m, &p, &p, &r), KISSM_OK);
        CHECK(strcmp(kissm_last_error_message(), "") == 0);
    }
    kissm_destroy(m);

    /* The message of a failure is stable across calls that do not touch it (reading it twice). */
    CHECK_EQ_INT(kissm_create(NULL, NULL), KISSM_ERR_NULL_ARGUMENT);
    msg = kissm_last_error_message();
    CHECK(msg != NULL && strstr(msg, "out_matcher") != NULL);
    CHECK(strcmp(msg, kissm_last_error_message()) == 0);
}

/* kissm_result_init: struct_size as given, everything else as a failed call leaves it; bad sizes write nothing. */
static void test_result_init(void) {
    unsigned char buf[sizeof(kissm_result) + 64], before[sizeof(buf)];
    kissm_result *r = (kissm_result *)(void *)buf;
    size_t i;
    const uint32_t bad_sizes[] = {0u, 4u, (uint32_t)sizeof(kissm_result) - 8u, 65537u, 0xFFFFFFFFu};

    memset(buf, 0x5a, sizeof(buf));
    CHECK_EQ_INT(kissm_result_init(r, (uint32_t)sizeof(kissm_result)), KISSM_OK);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
    CHECK_EQ_INT((int)r->struct_size, (int)sizeof(kissm_result));
    CHECK_EQ_INT(r->valid, 0);
    CHECK_EQ_INT(r->reason, KISSM_REASON_NONE);
    for (i = 0; i < 16; ++i) CHECK(isnan(r->transform[i]));
    for (i = 0; i < 9; ++i) CHECK(isnan(r->rotation[i]));
    for (i = 0; i < 3; ++i) CHECK(isnan(r->translation[i]));
    CHECK(isnan(r->residual_rms));
    CHECK(r->num_source_points == 0 && r->num_final_inliers == 0 && r->max_core_number == 0);
    CHECK(r->inlier_ratio == 0.0 && r->time_total_ms == 0.0);
    CHECK(scn_result_is_reset(r));            /* the refinement's fields too: NaN, 0 */
    CHECK(buf[sizeof(kissm_result)] == 0x5a); /* nothing written past the size given */

    /* A newer caller's larger struct: its unknown tail is zeroed. */
    memset(buf, 0x5a, sizeof(buf));
    CHECK_EQ_INT(kissm_result_init(r, (uint32_t)sizeof(buf)), KISSM_OK);
    CHECK_EQ_INT((int)r->struct_size, (int)sizeof(buf));
    for (i = sizeof(kissm_result); i < sizeof(buf); ++i) CHECK(buf[i] == 0);

    CHECK_EQ_INT(kissm_result_init(NULL, (uint32_t)sizeof(kissm_result)), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "kissm_result_init: result is NULL") != NULL);
    for (i = 0; i < sizeof(bad_sizes) / sizeof(bad_sizes[0]); ++i) {
        memset(buf, 0x33, sizeof(buf));
        memcpy(before, buf, sizeof(buf));
        CHECK_EQ_INT(kissm_result_init(r, bad_sizes[i]), KISSM_ERR_STRUCT_SIZE);
        CHECK(memcmp(buf, before, sizeof(buf)) == 0);
        CHECK(strstr(kissm_last_error_message(), "kissm_result_init: struct_size is ") != NULL);
    }
}

int main(void) {
    RUN_TEST(test_versions);
    RUN_TEST(test_abi_sizeof);
    RUN_TEST(test_config_init);
    RUN_TEST(test_create_destroy);
    RUN_TEST(test_status_strings);
    RUN_TEST(test_reason_strings);
    RUN_TEST(test_last_error_message);
    RUN_TEST(test_result_init);
    return TEST_SUMMARY();
}
