/* SPDX-License-Identifier: MIT */
/* Every way a caller can misuse the C API: exact status, a message naming the argument, outputs left alone
 * (a registration result is fully overwritten instead), and a handle that stays usable afterwards. Also
 * degenerate but well-formed inputs, which succeed with valid = 0 and a reason. C99. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define GOOD_VOXEL 0.6

/* A small, fast, registrable pair shared by every test. */
static scn_pair g_pair;
static kissm_matcher *g_m = NULL; /* default config, voxel GOOD_VOXEL */

/* A sentinel that no allocation returns: outputs must keep it when a call fails. */
#define SENTINEL_MATCHER ((kissm_matcher *)(uintptr_t)0x1234)
#define SENTINEL_FEATURES ((kissm_features *)(uintptr_t)0x5678)
#define SENTINEL_POSE_GRAPH ((kissm_pose_graph *)(uintptr_t)0x9abc)

static int msg_has(const char *word) {
    const char *msg = kissm_last_error_message();
    if (msg != NULL && strstr(msg, word) != NULL) return 1;
    fprintf(stderr, "  message \"%s\" does not name \"%s\"\n", msg ? msg : "(null)", word);
    return 0;
}

/* The matcher registers the good pair successfully (a failure before left it usable). */
static void check_usable(kissm_matcher *m, const char *after) {
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_result r;
    scn_result_poison(&r);
    CHECK_MSG(kissm_register(m, &s, &t, &r) == KISSM_OK, "after %s: %s", after, kissm_last_error_message());
    CHECK_MSG(r.valid == 1 && scn_rotation_error_deg(r.rotation, g_pair.truth.R) < 3.0, "after %s", after);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
}

/* ---------------------------------------------------------------------------------------------- */
/* NULL pointers                                                                                    */
/* ---------------------------------------------------------------------------------------------- */

static void test_null_pointers(void) {
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_features *fs = NULL, *ft = NULL, *out_f;
    kissm_matcher *out_m;
    kissm_config c = scn_config(GOOD_VOXEL);
    kissm_result r;

    CHECK_EQ_INT(kissm_config_init(NULL, (uint32_t)sizeof(kissm_config)), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_config_validate(NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("config"));
    CHECK_EQ_INT(kissm_create(&c, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("out_matcher"));
    CHECK_EQ_INT(kissm_get_config(NULL, &c), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("matcher"));
    CHECK_EQ_INT(kissm_get_config(g_m, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("out_config"));
    CHECK_EQ_INT(kissm_result_init(NULL, (uint32_t)sizeof(kissm_result)), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("result"));

    /* kissm_register: the result is overwritten whenever it is usable. */
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register(NULL, &s, &t, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("matcher"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register(g_m, NULL, &t, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("source"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register(g_m, &s, NULL, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("target"));
    CHECK(scn_result_is_reset(&r));
    CHECK_EQ_INT(kissm_register(g_m, &s, &t, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("result"));
    CHECK_EQ_INT(kissm_register(NULL, NULL, NULL, NULL), KISSM_ERR_NULL_ARGUMENT);
    check_usable(g_m, "kissm_register NULLs");

    /* kissm_features_compute: *out untouched. */
    out_f = SENTINEL_FEATURES;
    CHECK_EQ_INT(kissm_features_compute(NULL, &s, &out_f), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("matcher"));
    CHECK(out_f == SENTINEL_FEATURES);
    CHECK_EQ_INT(kissm_features_compute(g_m, NULL, &out_f), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("cloud"));
    CHECK(out_f == SENTINEL_FEATURES);
    CHECK_EQ_INT(kissm_features_compute(g_m, &s, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("out_features"));

    /* kissm_register_features */
    REQUIRE(kissm_features_compute(g_m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(g_m, &t, &ft) == KISSM_OK);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register_features(NULL, fs, ft, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("matcher"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register_features(g_m, NULL, ft, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("source"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register_features(g_m, fs, NULL, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("target"));
    CHECK(scn_result_is_reset(&r));
    CHECK_EQ_INT(kissm_register_features(g_m, fs, ft, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("result"));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register_features(g_m, fs, ft, &r), KISSM_OK);

    /* kissm_features_signature: nothing written */
    {
        double sig[KISSM_SIGNATURE_SIZE];
        int k, untouched = 1;
        for (k = 0; k < KISSM_SIGNATURE_SIZE; ++k) sig[k] = -7.0;
        CHECK_EQ_INT(kissm_features_signature(NULL, sig), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("features"));
        for (k = 0; k < KISSM_SIGNATURE_SIZE; ++k) untouched &= sig[k] == -7.0;
        CHECK(untouched);
        CHECK_EQ_INT(kissm_features_signature(fs, NULL), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("out_signature"));
        CHECK_EQ_INT(kissm_features_signature(fs, sig), KISSM_OK);
        CHECK(strcmp(kissm_last_error_message(), "") == 0);
    }
    CHECK(r.valid == 1);
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);

    /* Files */
    {
        kissm_cloud *cloud = (kissm_cloud *)(uintptr_t)0x9abc;
        kissm_points view;
        CHECK_EQ_INT(kissm_read_points(NULL, KISSM_FORMAT_AUTO, &cloud), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("path"));
        CHECK(cloud == (kissm_cloud *)(uintptr_t)0x9abc);
        CHECK_EQ_INT(kissm_read_points("/nonexistent/x.xyz", KISSM_FORMAT_AUTO, NULL), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("out_cloud"));
        memset(&view, 0x11, sizeof(view));
        CHECK_EQ_INT(kissm_cloud_points(NULL, &view), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("cloud"));
        /* The getters of a NULL cloud answer 0, as documented, and set no error. */
        CHECK_EQ_INT(kissm_cloud_count(NULL), 0);
        CHECK_EQ_INT(kissm_cloud_num_withheld(NULL), 0);
    }
    out_m = SENTINEL_MATCHER;
    CHECK_EQ_INT(kissm_create(NULL, &out_m), KISSM_OK); /* NULL config is not an error: defaults */
    CHECK(out_m != SENTINEL_MATCHER && out_m != NULL);
    if (out_m != SENTINEL_MATCHER) kissm_destroy(out_m);
}

/* ---------------------------------------------------------------------------------------------- */
/* Malformed kissm_points                                                                           */
/* ---------------------------------------------------------------------------------------------- */

#define DATA_GOOD 0
#define DATA_NULL 1

typedef struct points_case {
    const char *name;
    int data;
    uint64_t count;
    uint64_t stride_bytes;
    int32_t scalar_type;
    int32_t reserved;
    int32_t status;
    const char *word; /* the message names this (besides "source"/"target"/"cloud") */
} points_case;

static const points_case k_points_cases[] = {
    {"count 0", DATA_GOOD, 0, 0, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_EMPTY_INPUT, "count"},
    {"count 0, data NULL", DATA_NULL, 0, 0, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_EMPTY_INPUT, "count"},
    {"1 point", DATA_GOOD, 1, 0, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_TOO_FEW_POINTS, "1"},
    {"2 points", DATA_GOOD, 2, 0, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_TOO_FEW_POINTS, "2"},
    {"3 points", DATA_GOOD, 3, 0, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_TOO_FEW_POINTS, "3"},
    {"3 points f32", DATA_GOOD, 3, 0, KISSM_SCALAR_FLOAT32, 0, KISSM_ERR_TOO_FEW_POINTS, "3"},
    {"data NULL", DATA_NULL, 100, 0, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_NULL_ARGUMENT, "data"},
    {"data NULL f32", DATA_NULL, 4, 0, KISSM_SCALAR_FLOAT32, 0, KISSM_ERR_NULL_ARGUMENT, "data"},
    {"scalar_type 0", DATA_GOOD, 100, 0, 0, 0, KISSM_ERR_INVALID_ARGUMENT, "scalar_type"},
    {"scalar_type 3", DATA_GOOD, 100, 0, 3, 0, KISSM_ERR_INVALID_ARGUMENT, "scalar_type"},
    {"scalar_type -1", DATA_GOOD, 100, 0, -1, 0, KISSM_ERR_INVALID_ARGUMENT, "scalar_type"},
    {"reserved 1", DATA_GOOD, 100, 0, KISSM_SCALAR_FLOAT64, 1, KISSM_ERR_INVALID_ARGUMENT, "reserved"},
    {"reserved -1", DATA_GOOD, 100, 0, KISSM_SCALAR_FLOAT64, -1, KISSM_ERR_INVALID_ARGUMENT, "reserved"},
    {"stride 8 f64", DATA_GOOD, 100, 8, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_INVALID_ARGUMENT, "stride_bytes"},
    {"stride 16 f64", DATA_GOOD, 100, 16, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_INVALID_ARGUMENT, "stride_bytes"},
    {"stride 23 f64", DATA_GOOD, 100, 23, KISSM_SCALAR_FLOAT64, 0, KISSM_ERR_INVALID_ARGUMENT, "stride_bytes"},
    {"stride 1 f32", DATA_GOOD, 100, 1, KISSM_SCALAR_FLOAT32, 0, KISSM_ERR_INVALID_ARGUMENT, "stride_bytes"},
    {"stride 11 f32", DATA_GOOD, 100, 11, KISSM_SCALAR_FLOAT32, 0, KISSM_ERR_INVALID_ARGUMENT, "stride_bytes"},
};

static kissm_points make_case_points(const points_case *pc, const double *xyz64, const float *xyz32) {
    kissm_points p;
    memset(&p, 0, sizeof(p));
    p.data = pc->data == DATA_NULL
                 ? NULL
                 : (pc->scalar_type == KISSM_SCALAR_FLOAT32 ? (const void *)xyz32 : (const void *)xyz64);
    p.count = pc->count;
    p.stride_bytes = pc->stride_bytes;
    p.scalar_type = pc->scalar_type;
    p.reserved = pc->reserved;
    return p;
}

static void test_bad_points(void) {
    const kissm_points good_s = scn_points(&g_pair.source), good_t = scn_points(&g_pair.target);
    float *src32 = scn_cloud_to_float(&g_pair.source);
    size_t i;
    for (i = 0; i < sizeof(k_points_cases) / sizeof(k_points_cases[0]); ++i) {
        const points_case *pc = &k_points_cases[i];
        const kissm_points bad = make_case_points(pc, g_pair.source.xyz, src32);
        kissm_result r;
        kissm_features *f = SENTINEL_FEATURES;
        int32_t st;

        /* as the source */
        scn_result_poison(&r);
        st = kissm_register(g_m, &bad, &good_t, &r);
        CHECK_MSG(st == pc->status, "%s as source: %d (%s)", pc->name, (int)st, kissm_last_error_message());
        CHECK_MSG(msg_has("source") && msg_has(pc->word), "%s as source", pc->name);
        CHECK_MSG(scn_result_is_reset(&r), "%s as source", pc->name);
        /* as the target */
        scn_result_poison(&r);
        st = kissm_register(g_m, &good_s, &bad, &r);
        CHECK_MSG(st == pc->status, "%s as target: %d (%s)", pc->name, (int)st, kissm_last_error_message());
        CHECK_MSG(msg_has("target") && msg_has(pc->word), "%s as target", pc->name);
        CHECK_MSG(scn_result_is_reset(&r), "%s as target", pc->name);
        /* to kissm_features_compute */
        st = kissm_features_compute(g_m, &bad, &f);
        CHECK_MSG(st == pc->status, "%s to features_compute: %d (%s)", pc->name, (int)st, kissm_last_error_message());
        CHECK_MSG(msg_has(pc->word), "%s to features_compute", pc->name);
        CHECK(f == SENTINEL_FEATURES);
        check_usable(g_m, pc->name);
    }
    free(src32);
}

/* Strides that are fine: exactly 3 scalars, and a padded point (a float32 xyz + intensity). */
static void test_valid_strides(void) {
    const size_t n = g_pair.source.count;
    float *xyzi = (float *)malloc(n * 4 * sizeof(float));
    kissm_points s, t = scn_points(&g_pair.target), packed = scn_points(&g_pair.source);
    kissm_result a, b;
    size_t i;
    REQUIRE(xyzi != NULL);
    for (i = 0; i < n; ++i) {
        xyzi[4 * i + 0] = (float)g_pair.source.xyz[3 * i + 0];
        xyzi[4 * i + 1] = (float)g_pair.source.xyz[3 * i + 1];
        xyzi[4 * i + 2] = (float)g_pair.source.xyz[3 * i + 2];
        xyzi[4 * i + 3] = NAN; /* an intensity the library must never read as a coordinate */
    }
    s = scn_points_f32(xyzi, n);
    s.stride_bytes = 16;
    scn_result_poison(&a);
    CHECK_EQ_INT(kissm_register(g_m, &s, &t, &a), KISSM_OK);
    CHECK_EQ_INT(a.valid, 1);
    CHECK_EQ_INT(a.num_source_nonfinite, 0);
    packed.stride_bytes = 24; /* explicit packed float64 stride equals stride 0 */
    scn_result_poison(&a);
    scn_result_poison(&b);
    CHECK_EQ_INT(kissm_register(g_m, &packed, &t, &a), KISSM_OK);
    packed.stride_bytes = 0;
    CHECK_EQ_INT(kissm_register(g_m, &packed, &t, &b), KISSM_OK);
    CHECK(scn_result_equal(&a, &b));
    free(xyzi);
}

/* ---------------------------------------------------------------------------------------------- */
/* Non-finite coordinates                                                                           */
/* ---------------------------------------------------------------------------------------------- */

static void test_nonfinite(void) {
    const double bad_values[3] = {NAN, INFINITY, -INFINITY};
    const char *bad_names[3] = {"NaN", "+Inf", "-Inf"};
    const size_t n = g_pair.source.count;
    const size_t where[3] = {0, n / 2, n - 1};
    kissm_config drop_cfg = scn_config(GOOD_VOXEL);
    kissm_matcher *drop = NULL;
    kissm_points good_t = scn_points(&g_pair.target);
    kissm_result r, ref;
    scn_cloud cloud, removed;
    int v, w;

    drop_cfg.nonfinite_policy = KISSM_NONFINITE_DROP;
    REQUIRE(kissm_create(&drop_cfg, &drop) == KISSM_OK);
    scn_cloud_init(&cloud);
    scn_cloud_init(&removed);

    for (v = 0; v < 3; ++v) {
        for (w = 0; w < 3; ++w) {
            const int axis = w; /* first point: x, middle: y, last: z */
            kissm_points s;
            float *f32;
            kissm_features *f = SENTINEL_FEATURES;
            scn_cloud_copy(&cloud, &g_pair.source);
            cloud.xyz[3 * where[w] + (size_t)axis] = bad_values[v];
            s = scn_points(&cloud);

            /* REJECT (the default): NONFINITE, as source, as target, as float32, to features_compute */
            scn_result_poison(&r);
            CHECK_MSG(kissm_register(g_m, &s, &good_t, &r) == KISSM_ERR_NONFINITE, "%s at %lu", bad_names[v],
                      (unsigned long)where[w]);
            CHECK(msg_has("source"));
            CHECK(scn_result_is_reset(&r));
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register(g_m, &good_t, &s, &r), KISSM_ERR_NONFINITE);
            CHECK(msg_has("target"));
            CHECK(scn_result_is_reset(&r));
            f32 = scn_cloud_to_float(&cloud);
            {
                const kissm_points s32 = scn_points_f32(f32, cloud.count);
                scn_result_poison(&r);
                CHECK_EQ_INT(kissm_register(g_m, &s32, &good_t, &r), KISSM_ERR_NONFINITE);
                CHECK(scn_result_is_reset(&r));
            }
            CHECK_EQ_INT(kissm_features_compute(g_m, &s, &f), KISSM_ERR_NONFINITE);
            CHECK(f == SENTINEL_FEATURES);

            /* DROP: succeeds, counts the point, and equals the call without that point. */
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register(drop, &s, &good_t, &r), KISSM_OK);
            CHECK_EQ_INT(r.num_source_points, n);
            CHECK_EQ_INT(r.num_source_nonfinite, 1);
            CHECK_EQ_INT(r.num_target_nonfinite, 0);
            CHECK_EQ_INT(r.valid, 1);
            scn_cloud_copy(&removed, &g_pair.source);
            memmove(removed.xyz + 3 * where[w], removed.xyz + 3 * (where[w] + 1),
                    3 * (n - where[w] - 1) * sizeof(double));
            removed.count--;
            {
                const kissm_points sr = scn_points(&removed);
                scn_result_poison(&ref);
                CHECK_EQ_INT(kissm_register(drop, &sr, &good_t, &ref), KISSM_OK);
                CHECK_EQ_INT(ref.num_source_points, n - 1);
                ref.num_source_points = n;
                ref.num_source_nonfinite = 1;
                CHECK_MSG(scn_result_equal(&r, &ref), "DROP of %s at %lu differs from removing the point", bad_names[v],
                          (unsigned long)where[w]);
            }
            /* DROP as the target, float32 */
            {
                const kissm_points s32 = scn_points_f32(f32, cloud.count);
                kissm_points gs = scn_points(&g_pair.source);
                scn_result_poison(&r);
                CHECK_EQ_INT(kissm_register(drop, &gs, &s32, &r), KISSM_OK);
                CHECK_EQ_INT(r.num_target_nonfinite, 1);
                CHECK_EQ_INT(r.num_source_nonfinite, 0);
                CHECK_EQ_INT(r.num_target_points, n);
            }
            free(f32);
        }
    }
    check_usable(g_m, "non-finite (REJECT)");

    /* Several bad points, all in one cloud */
    {
        size_t i, k = 0;
        kissm_points s;
        scn_cloud_copy(&cloud, &g_pair.source);
        for (i = 0; i < n; i += 97, ++k) cloud.xyz[3 * i + (i % 3)] = bad_values[i % 3];
        s = scn_points(&cloud);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(drop, &s, &good_t, &r), KISSM_OK);
        CHECK_EQ_INT(r.num_source_nonfinite, k);
        CHECK_EQ_INT(r.valid, 1);
    }

    /* DROP leaving nothing: EMPTY_INPUT; leaving 3 points: TOO_FEW_POINTS. */
    {
        size_t i;
        kissm_points s;
        kissm_features *f = SENTINEL_FEATURES;
        scn_cloud_copy(&cloud, &g_pair.source);
        for (i = 0; i < 3 * n; ++i) cloud.xyz[i] = (i % 2) ? NAN : INFINITY;
        s = scn_points(&cloud);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(drop, &s, &good_t, &r), KISSM_ERR_EMPTY_INPUT);
        CHECK(msg_has("source"));
        CHECK(scn_result_is_reset(&r));
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(drop, &good_t, &s, &r), KISSM_ERR_EMPTY_INPUT);
        CHECK(msg_has("target"));
        CHECK(scn_result_is_reset(&r));
        CHECK_EQ_INT(kissm_features_compute(drop, &s, &f), KISSM_ERR_EMPTY_INPUT);
        CHECK(f == SENTINEL_FEATURES);
        for (i = 0; i < 3; ++i) {
            cloud.xyz[3 * (10 * i) + 0] = (double)i;
            cloud.xyz[3 * (10 * i) + 1] = 1.0;
            cloud.xyz[3 * (10 * i) + 2] = 2.0 * (double)i;
        }
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(drop, &s, &good_t, &r), KISSM_ERR_TOO_FEW_POINTS);
        CHECK(msg_has("source"));
        CHECK(scn_result_is_reset(&r));
        /* A fourth finite point: acceptable input (far too little to register, but not an error). */
        cloud.xyz[3 * 40 + 0] = 5.0;
        cloud.xyz[3 * 40 + 1] = 5.0;
        cloud.xyz[3 * 40 + 2] = 5.0;
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(drop, &s, &good_t, &r), KISSM_OK);
        CHECK_EQ_INT(r.valid, 0);
        CHECK_MSG(r.reason == KISSM_REASON_TOO_FEW_VOXELS || r.reason == KISSM_REASON_TOO_FEW_FEATURES, "reason %d",
                  (int)r.reason);
        CHECK_EQ_INT(r.num_source_voxels, 4);
        CHECK_EQ_INT(r.num_source_keypoints, 0);
        CHECK_EQ_INT(r.num_source_nonfinite, n - 4);
        CHECK_EQ_INT(r.num_source_points, n);
        CHECK(scn_result_poison_left(&r) == 0);
    }
    check_usable(drop, "non-finite (DROP)");
    check_usable(g_m, "non-finite");
    scn_cloud_free(&cloud);
    scn_cloud_free(&removed);
    kissm_destroy(drop);
}

/* ---------------------------------------------------------------------------------------------- */
/* Voxel size                                                                                       */
/* ---------------------------------------------------------------------------------------------- */

static void test_voxel_size(void) {
    const double bad[] = {-0.3, -1e-9, -1e-300, NAN, INFINITY, -INFINITY};
    size_t i;
    /* 0 (and -0) is the automatic voxel size: valid. */
    for (i = 0; i < 2; ++i) {
        kissm_config c = scn_config(i == 0 ? 0.0 : -0.0);
        kissm_matcher *m = NULL;
        CHECK_EQ_INT(kissm_config_validate(&c), KISSM_OK);
        CHECK_EQ_INT(kissm_create(&c, &m), KISSM_OK);
        check_usable(m, "voxel_size 0");
        kissm_destroy(m);
    }
    for (i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i) {
        kissm_config c = scn_config(bad[i]);
        kissm_matcher *m = SENTINEL_MATCHER;
        CHECK_MSG(kissm_config_validate(&c) == KISSM_ERR_INVALID_ARGUMENT, "voxel_size %g", bad[i]);
        CHECK(msg_has("voxel_size"));
        CHECK_MSG(kissm_create(&c, &m) == KISSM_ERR_INVALID_ARGUMENT, "voxel_size %g", bad[i]);
        CHECK(msg_has("voxel_size"));
        CHECK(m == SENTINEL_MATCHER);
    }

    /* Too small for the extent (a ~24 m cloud): VOXEL_RANGE at registration time. The same matcher then
     * registers a cloud small enough for that voxel size (1e-9 m voxels on a ~10 micrometre cloud are only
     * ~1e4 per axis). */
    {
        kissm_config c = scn_config(1e-9);
        kissm_matcher *m = NULL;
        kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target), p;
        kissm_features *f = SENTINEL_FEATURES;
        kissm_result r;
        scn_cloud tiny;
        CHECK_EQ_INT(kissm_config_validate(&c), KISSM_OK);
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_ERR_VOXEL_RANGE);
        CHECK(msg_has("voxel_size"));
        CHECK(scn_result_is_reset(&r));
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &s, &s, &r), KISSM_ERR_VOXEL_RANGE);
        CHECK(msg_has("source"));
        CHECK(scn_result_is_reset(&r));
        CHECK_EQ_INT(kissm_features_compute(m, &s, &f), KISSM_ERR_VOXEL_RANGE);
        CHECK(f == SENTINEL_FEATURES);

        scn_cloud_init(&tiny);
        scn_cloud_copy(&tiny, &g_pair.source);
        for (i = 0; i < 3 * tiny.count; ++i) tiny.xyz[i] *= 4e-7;
        p = scn_points(&tiny);
        scn_result_poison(&r);
        CHECK_MSG(kissm_register(m, &p, &p, &r) == KISSM_OK, "%s", kissm_last_error_message());
        CHECK(scn_result_poison_left(&r) == 0);
        /* a tiny source against the big target: the target is out of range */
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &p, &t, &r), KISSM_ERR_VOXEL_RANGE);
        CHECK(msg_has("target"));
        CHECK(scn_result_is_reset(&r));
        kissm_destroy(m);
        scn_cloud_free(&tiny);
    }
    /* Far too large: every point in one voxel, a success with valid = 0. */
    {
        kissm_config c = scn_config(1e9);
        kissm_matcher *m = NULL;
        kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
        kissm_result r;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
        CHECK_EQ_INT(r.valid, 0);
        CHECK_EQ_INT(r.reason, KISSM_REASON_TOO_FEW_VOXELS);
        CHECK_EQ_INT(r.num_source_voxels, 1);
        CHECK_EQ_INT(r.num_target_voxels, 1);
        CHECK_EQ_INT(r.num_source_points, g_pair.source.count);
        CHECK(isnan(r.transform[0]) && isnan(r.rotation[0]) && isnan(r.translation[0]));
        CHECK(scn_result_poison_left(&r) == 0);
        kissm_destroy(m);
    }
}

/* ---------------------------------------------------------------------------------------------- */
/* Every config field                                                                               */
/* ---------------------------------------------------------------------------------------------- */

enum {
    F_NUM_THREADS,
    F_NORMAL_GAIN,
    F_FPFH_GAIN,
    F_MAX_LINEARITY,
    F_RATIO_TEST,
    F_PRUNE_GAIN,
    F_SOLVER_GAIN,
    F_NOISE_BOUND_MAX,
    F_VIEWPOINT0,
    F_VIEWPOINT1,
    F_VIEWPOINT2,
    F_MIN_NORMAL_NEIGHBORS,
    F_MAX_CORRESPONDENCES,
    F_MIN_INLIERS,
    F_NONFINITE_POLICY,
    F_VIEWPOINT_MODE,
    F_LOG_LEVEL,
    F_REFINE_MODE,
    F_REFINE_MAX_ITERATIONS,
    F_REFINE_MAX_DISTANCE_GAIN,
    F_REFINE_KERNEL_GAIN,
    F_REFINE_ROTATION_EPSILON,
    F_REFINE_TRANSLATION_EPSILON_GAIN,
    F_MIN_OVERLAP,
    F_MAX_ROTATION_UNCERTAINTY,
    F_MIN_INLIER_COVERAGE,
    F_REFINE_MIN_INLIERS,
    F_RESERVED1,
    F_MIN_REFINE_CONDITION,
    F_SUPPRESSION,
    F_ROTATION_DOF,
    F_UP0,
    F_UP2,
    F_UP_ALL, /* all three components */
    F_SENSOR_HEIGHT,
    F_MAX_REFINE_RMSE_GAIN,
    F_ALLOW_DEGENERATE,
    F_RESERVED2,
    F_MAX_AMBIGUITY
};

typedef struct field_case {
    int field;
    double value;
    const char *word; /* the message must name this */
} field_case;

/* kissm_suggest_voxel_size: NULLs, counts, bad views and clouds without a length; the output keeps its value. */
static void test_suggest_voxel_size(void) {
    kissm_points p[2];
    double v = -7.0;
    scn_cloud dup, few;
    const double nan_xyz[12] = {NAN, 0, 0, NAN, 1, 1, NAN, 2, 2, NAN, 3, 3};
    p[0] = scn_points(&g_pair.source), p[1] = scn_points(&g_pair.target);
    CHECK_EQ_INT(kissm_suggest_voxel_size(NULL, 1, &v), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("clouds"));
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 1, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("out_voxel_size"));
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 0, &v), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("num_clouds"));
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 65537, &v), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("num_clouds"));
    p[1].scalar_type = 7;
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 2, &v), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("clouds[1]->scalar_type"));
    p[1] = scn_points(&g_pair.target);
    p[1].data = NULL;
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 2, &v), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("clouds[1]->data"));
    p[1] = scn_points(&g_pair.target);
    p[0].count = 0;
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 2, &v), KISSM_ERR_EMPTY_INPUT);
    CHECK(msg_has("clouds[0]"));
    /* every point non-finite: no length to measure */
    p[0].data = nan_xyz, p[0].count = 4, p[0].stride_bytes = 0, p[0].scalar_type = KISSM_SCALAR_FLOAT64;
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 2, &v), KISSM_ERR_EMPTY_INPUT);
    CHECK(msg_has("clouds[0]"));
    /* 3 finite points */
    scn_cloud_init(&few);
    scn_cloud_push(&few, 0, 0, 0), scn_cloud_push(&few, 1, 0, 0), scn_cloud_push(&few, 0, 1, 0);
    scn_cloud_push(&few, NAN, 0, 0), scn_cloud_push(&few, 0, INFINITY, 0);
    p[0] = scn_points(&few);
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 2, &v), KISSM_ERR_TOO_FEW_POINTS);
    CHECK(msg_has("clouds[0]"));
    /* all points on one spot */
    scn_cloud_init(&dup);
    scn_make_duplicates(&dup, 100, 1.0, 2.0, 3.0);
    p[0] = scn_points(&g_pair.source), p[1] = scn_points(&dup);
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 2, &v), KISSM_ERR_TOO_FEW_POINTS);
    CHECK(msg_has("clouds[1]") && msg_has("coincide"));
    CHECK(v == -7.0);
    /* and through a matcher at voxel_size 0: the same status, the result reset */
    {
        kissm_config c = scn_config(0.0);
        kissm_matcher *m = NULL;
        kissm_result r;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &p[0], &p[1], &r), KISSM_ERR_TOO_FEW_POINTS);
        CHECK(msg_has("target") && msg_has("coincide"));
        CHECK(scn_result_is_reset(&r));
        check_usable(m, "a cloud without extent at voxel_size 0");
        kissm_destroy(m);
    }
    /* non-finite points are ignored: the finite ones decide */
    p[0] = scn_points(&g_pair.source), p[1] = scn_points(&g_pair.target);
    CHECK_EQ_INT(kissm_suggest_voxel_size(p, 2, &v), KISSM_OK);
    CHECK(v > 0.0);
    scn_cloud_free(&dup);
    scn_cloud_free(&few);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
}

static void set_field(kissm_config *c, int field, double v) {
    switch (field) {
    case F_NUM_THREADS: c->num_threads = (int32_t)v; break;
    case F_NORMAL_GAIN: c->normal_radius_gain = v; break;
    case F_FPFH_GAIN: c->fpfh_radius_gain = v; break;
    case F_MAX_LINEARITY: c->max_linearity = v; break;
    case F_RATIO_TEST: c->ratio_test = v; break;
    case F_PRUNE_GAIN: c->prune_noise_bound_gain = v; break;
    case F_SOLVER_GAIN: c->solver_noise_bound_gain = v; break;
    case F_NOISE_BOUND_MAX: c->noise_bound_max = v; break;
    case F_VIEWPOINT0: c->viewpoint[0] = v; break;
    case F_VIEWPOINT1: c->viewpoint[1] = v; break;
    case F_VIEWPOINT2: c->viewpoint[2] = v; break;
    case F_MIN_NORMAL_NEIGHBORS: c->min_normal_neighbors = (int32_t)v; break;
    case F_MAX_CORRESPONDENCES: c->max_correspondences = (int32_t)v; break;
    case F_MIN_INLIERS: c->min_inliers = (int32_t)v; break;
    case F_NONFINITE_POLICY: c->nonfinite_policy = (int32_t)v; break;
    case F_VIEWPOINT_MODE: c->viewpoint_mode = (int32_t)v; break;
    case F_LOG_LEVEL: c->log_level = (int32_t)v; break;
    case F_REFINE_MODE: c->refine_mode = (int32_t)v; break;
    case F_REFINE_MAX_ITERATIONS: c->refine_max_iterations = (int32_t)v; break;
    case F_REFINE_MAX_DISTANCE_GAIN: c->refine_max_distance_gain = v; break;
    case F_REFINE_KERNEL_GAIN: c->refine_kernel_gain = v; break;
    case F_REFINE_ROTATION_EPSILON: c->refine_rotation_epsilon = v; break;
    case F_REFINE_TRANSLATION_EPSILON_GAIN: c->refine_translation_epsilon_gain = v; break;
    case F_MIN_OVERLAP: c->min_overlap = v; break;
    case F_MAX_ROTATION_UNCERTAINTY: c->max_rotation_uncertainty = v; break;
    case F_MIN_INLIER_COVERAGE: c->min_inlier_coverage = v; break;
    case F_REFINE_MIN_INLIERS: c->refine_min_inliers = (int32_t)v; break;
    case F_RESERVED1: c->reserved1 = (int32_t)v; break;
    case F_MIN_REFINE_CONDITION: c->min_refine_condition = v; break;
    case F_SUPPRESSION: c->suppression = (int32_t)v; break;
    case F_ROTATION_DOF: c->rotation_dof = (int32_t)v; break;
    case F_UP0: c->up[0] = v; break;
    case F_UP2: c->up[2] = v; break;
    case F_UP_ALL: c->up[0] = c->up[1] = c->up[2] = v; break;
    case F_SENSOR_HEIGHT: c->sensor_height = v; break;
    case F_MAX_REFINE_RMSE_GAIN: c->max_refine_rmse_gain = v; break;
    case F_ALLOW_DEGENERATE: c->allow_degenerate = (int32_t)v; break;
    case F_RESERVED2: c->reserved2 = (int32_t)v; break;
    case F_MAX_AMBIGUITY: c->max_ambiguity = v; break;
    default: break;
    }
}

static const field_case k_bad_fields[] = {
    {F_NUM_THREADS, -1, "num_threads"},
    {F_NUM_THREADS, -1000, "num_threads"},
    {F_NUM_THREADS, 1000000, "num_threads"},
    {F_NORMAL_GAIN, 0.0, "normal_radius_gain"},
    {F_NORMAL_GAIN, -1.0, "normal_radius_gain"},
    {F_NORMAL_GAIN, NAN, "normal_radius_gain"},
    {F_NORMAL_GAIN, INFINITY, "radius_gain"},
    {F_NORMAL_GAIN, 5.5, "radius_gain"}, /* above fpfh_radius_gain (5.0) */
    {F_FPFH_GAIN, 0.0, "fpfh_radius_gain"},
    {F_FPFH_GAIN, -5.0, "fpfh_radius_gain"},
    {F_FPFH_GAIN, NAN, "fpfh_radius_gain"},
    {F_FPFH_GAIN, INFINITY, "fpfh_radius_gain"},
    {F_FPFH_GAIN, 3.0, "radius_gain"}, /* below normal_radius_gain (3.5) */
    {F_MAX_LINEARITY, 0.0, "max_linearity"},
    {F_MAX_LINEARITY, -0.5, "max_linearity"},
    {F_MAX_LINEARITY, 1.0001, "max_linearity"},
    {F_MAX_LINEARITY, NAN, "max_linearity"},
    {F_RATIO_TEST, 0.0, "ratio_test"},
    {F_RATIO_TEST, -0.9, "ratio_test"},
    {F_RATIO_TEST, 1.5, "ratio_test"},
    {F_RATIO_TEST, NAN, "ratio_test"},
    {F_PRUNE_GAIN, 0.0, "prune_noise_bound_gain"},
    {F_PRUNE_GAIN, -1.0, "prune_noise_bound_gain"},
    {F_PRUNE_GAIN, NAN, "prune_noise_bound_gain"},
    {F_PRUNE_GAIN, INFINITY, "prune_noise_bound_gain"},
    {F_SOLVER_GAIN, 0.0, "solver_noise_bound_gain"},
    {F_SOLVER_GAIN, -0.75, "solver_noise_bound_gain"},
    {F_SOLVER_GAIN, NAN, "solver_noise_bound_gain"},
    {F_SOLVER_GAIN, INFINITY, "solver_noise_bound_gain"},
    {F_NOISE_BOUND_MAX, -0.1, "noise_bound_max"},
    {F_NOISE_BOUND_MAX, NAN, "noise_bound_max"},
    {F_NOISE_BOUND_MAX, -INFINITY, "noise_bound_max"},
    {F_VIEWPOINT0, NAN, "viewpoint"},
    {F_VIEWPOINT1, INFINITY, "viewpoint"},
    {F_VIEWPOINT2, -INFINITY, "viewpoint"},
    {F_MIN_NORMAL_NEIGHBORS, 2, "min_normal_neighbors"},
    {F_MIN_NORMAL_NEIGHBORS, 0, "min_normal_neighbors"},
    {F_MIN_NORMAL_NEIGHBORS, -3, "min_normal_neighbors"},
    {F_MAX_CORRESPONDENCES, 2, "max_correspondences"},
    {F_MAX_CORRESPONDENCES, 1, "max_correspondences"},
    {F_MAX_CORRESPONDENCES, -5000, "max_correspondences"},
    {F_MIN_INLIERS, 2, "min_inliers"},
    {F_MIN_INLIERS, 0, "min_inliers"},
    {F_MIN_INLIERS, -10, "min_inliers"},
    {F_NONFINITE_POLICY, -1, "nonfinite_policy"},
    {F_NONFINITE_POLICY, 2, "nonfinite_policy"},
    {F_NONFINITE_POLICY, 99, "nonfinite_policy"},
    {F_VIEWPOINT_MODE, -1, "viewpoint_mode"},
    {F_VIEWPOINT_MODE, 4, "viewpoint_mode"},
    {F_LOG_LEVEL, -1, "log_level"},
    {F_LOG_LEVEL, 5, "log_level"},
    {F_LOG_LEVEL, 99, "log_level"},
    /* refinement (the message names config.<field>) */
    {F_REFINE_MODE, -1, "config.refine_mode"},
    {F_REFINE_MODE, 3, "config.refine_mode"},
    {F_REFINE_MODE, 99, "config.refine_mode"},
    {F_REFINE_MAX_ITERATIONS, 0, "config.refine_max_iterations"},
    {F_REFINE_MAX_ITERATIONS, -1, "config.refine_max_iterations"},
    {F_REFINE_MAX_ITERATIONS, 1001, "config.refine_max_iterations"},
    {F_REFINE_MAX_DISTANCE_GAIN, 0.0, "config.refine_max_distance_gain"},
    {F_REFINE_MAX_DISTANCE_GAIN, -1.0, "config.refine_max_distance_gain"},
    {F_REFINE_MAX_DISTANCE_GAIN, 100.5, "config.refine_max_distance_gain"},
    {F_REFINE_MAX_DISTANCE_GAIN, NAN, "config.refine_max_distance_gain"},
    {F_REFINE_MAX_DISTANCE_GAIN, INFINITY, "config.refine_max_distance_gain"},
    {F_REFINE_KERNEL_GAIN, 0.0, "config.refine_kernel_gain"},
    {F_REFINE_KERNEL_GAIN, -0.1, "config.refine_kernel_gain"},
    {F_REFINE_KERNEL_GAIN, 101.0, "config.refine_kernel_gain"},
    {F_REFINE_KERNEL_GAIN, NAN, "config.refine_kernel_gain"},
    {F_REFINE_KERNEL_GAIN, INFINITY, "config.refine_kernel_gain"},
    {F_REFINE_ROTATION_EPSILON, -1e-9, "config.refine_rotation_epsilon"},
    {F_REFINE_ROTATION_EPSILON, 1.5, "config.refine_rotation_epsilon"},
    {F_REFINE_ROTATION_EPSILON, NAN, "config.refine_rotation_epsilon"},
    {F_REFINE_ROTATION_EPSILON, INFINITY, "config.refine_rotation_epsilon"},
    {F_REFINE_TRANSLATION_EPSILON_GAIN, -0.1, "config.refine_translation_epsilon_gain"},
    {F_REFINE_TRANSLATION_EPSILON_GAIN, 1.01, "config.refine_translation_epsilon_gain"},
    {F_REFINE_TRANSLATION_EPSILON_GAIN, NAN, "config.refine_translation_epsilon_gain"},
    {F_MIN_OVERLAP, -0.01, "config.min_overlap"},
    {F_MIN_OVERLAP, 1.01, "config.min_overlap"},
    {F_MIN_OVERLAP, NAN, "config.min_overlap"},
    {F_MIN_OVERLAP, -INFINITY, "config.min_overlap"},
    {F_MAX_ROTATION_UNCERTAINTY, 0.0, "config.max_rotation_uncertainty"},
    {F_MAX_ROTATION_UNCERTAINTY, -0.1, "config.max_rotation_uncertainty"},
    {F_MAX_ROTATION_UNCERTAINTY, 3.16, "config.max_rotation_uncertainty"},
    {F_MAX_ROTATION_UNCERTAINTY, NAN, "config.max_rotation_uncertainty"},
    {F_MAX_ROTATION_UNCERTAINTY, INFINITY, "config.max_rotation_uncertainty"},
    {F_MIN_INLIER_COVERAGE, -0.01, "config.min_inlier_coverage"},
    {F_MIN_INLIER_COVERAGE, 1.01, "config.min_inlier_coverage"},
    {F_MIN_INLIER_COVERAGE, NAN, "config.min_inlier_coverage"},
    {F_REFINE_MIN_INLIERS, 2, "config.refine_min_inliers"},
    {F_REFINE_MIN_INLIERS, -1, "config.refine_min_inliers"},
    {F_REFINE_MIN_INLIERS, 100001, "config.refine_min_inliers"},
    {F_RESERVED1, 1, "config.reserved1"},
    {F_RESERVED1, -1, "config.reserved1"},
    {F_MIN_REFINE_CONDITION, -1e-9, "config.min_refine_condition"},
    {F_MIN_REFINE_CONDITION, 1.5, "config.min_refine_condition"},
    {F_MIN_REFINE_CONDITION, NAN, "config.min_refine_condition"},
    /* ground-vehicle options */
    {F_SUPPRESSION, -1, "config.suppression"},
    {F_SUPPRESSION, 2, "config.suppression"},
    {F_ROTATION_DOF, 0, "config.rotation_dof"},
    {F_ROTATION_DOF, 2, "config.rotation_dof"},
    {F_ROTATION_DOF, 6, "config.rotation_dof"},
    {F_UP0, NAN, "config.up[0]"},
    {F_UP2, INFINITY, "config.up[2]"},
    {F_UP_ALL, 0.0, "config.up"},
    {F_UP_ALL, 1e-12, "config.up"},
    {F_SENSOR_HEIGHT, -0.1, "config.sensor_height"},
    {F_SENSOR_HEIGHT, 1000.5, "config.sensor_height"},
    {F_SENSOR_HEIGHT, NAN, "config.sensor_height"},
    {F_MAX_REFINE_RMSE_GAIN, 0.0, "config.max_refine_rmse_gain"},
    {F_MAX_REFINE_RMSE_GAIN, -1.0, "config.max_refine_rmse_gain"},
    {F_MAX_REFINE_RMSE_GAIN, 100.5, "config.max_refine_rmse_gain"},
    {F_MAX_REFINE_RMSE_GAIN, NAN, "config.max_refine_rmse_gain"},
    {F_ALLOW_DEGENERATE, -1, "config.allow_degenerate"},
    {F_ALLOW_DEGENERATE, 2, "config.allow_degenerate"},
    {F_RESERVED2, 1, "config.reserved2"},
    {F_RESERVED2, -1, "config.reserved2"},
    {F_MAX_AMBIGUITY, -0.01, "config.max_ambiguity"},
    {F_MAX_AMBIGUITY, 1.01, "config.max_ambiguity"},
    {F_MAX_AMBIGUITY, NAN, "config.max_ambiguity"},
    {F_MAX_AMBIGUITY, INFINITY, "config.max_ambiguity"},
};

/* Documented boundary values that must be accepted. */
static const field_case k_good_fields[] = {
    {F_NUM_THREADS, 0, ""},
    {F_NUM_THREADS, 1, ""},
    {F_NUM_THREADS, 64, ""},
    {F_NORMAL_GAIN, 5.0, ""},
    /* equal to fpfh_radius_gain */ {F_FPFH_GAIN, 3.5, ""},
    {F_FPFH_GAIN, 10.0, ""},
    {F_MAX_LINEARITY, 1.0, ""},
    {F_MAX_LINEARITY, 1e-6, ""},
    {F_RATIO_TEST, 1.0, ""},
    {F_RATIO_TEST, 1e-6, ""},
    {F_PRUNE_GAIN, 1e-3, ""},
    {F_PRUNE_GAIN, 100.0, ""},
    {F_SOLVER_GAIN, 1e-3, ""},
    {F_NOISE_BOUND_MAX, 0.0, ""},
    {F_NOISE_BOUND_MAX, 2.5, ""},
    {F_VIEWPOINT0, -1e7, ""},
    {F_VIEWPOINT2, 1e7, ""},
    {F_MIN_NORMAL_NEIGHBORS, 3, ""},
    {F_MIN_NORMAL_NEIGHBORS, 50, ""},
    {F_MAX_CORRESPONDENCES, 3, ""},
    {F_MAX_CORRESPONDENCES, 20000, ""},
    {F_MIN_INLIERS, 3, ""},
    {F_MIN_INLIERS, 1000, ""},
    {F_NONFINITE_POLICY, KISSM_NONFINITE_REJECT, ""},
    {F_NONFINITE_POLICY, KISSM_NONFINITE_DROP, ""},
    {F_VIEWPOINT_MODE, KISSM_VIEWPOINT_FIXED, ""},
    {F_VIEWPOINT_MODE, KISSM_VIEWPOINT_CLOUD_CENTER, ""},
    {F_VIEWPOINT_MODE, KISSM_VIEWPOINT_SIGN_FREE, ""},
    {F_VIEWPOINT_MODE, KISSM_VIEWPOINT_LOCAL, ""},
    {F_LOG_LEVEL, 0, ""},
    {F_LOG_LEVEL, KISSM_LOG_ERROR, ""},
    {F_LOG_LEVEL, KISSM_LOG_DEBUG, ""},
    {F_REFINE_MODE, KISSM_REFINE_NONE, ""},
    {F_REFINE_MODE, KISSM_REFINE_GICP, ""},
    {F_REFINE_MODE, KISSM_REFINE_POINT_TO_PLANE, ""},
    {F_REFINE_MAX_ITERATIONS, 1, ""},
    {F_REFINE_MAX_ITERATIONS, 1000, ""},
    {F_REFINE_MAX_DISTANCE_GAIN, 1e-3, ""},
    {F_REFINE_MAX_DISTANCE_GAIN, 100.0, ""},
    {F_REFINE_KERNEL_GAIN, 1e-3, ""},
    {F_REFINE_KERNEL_GAIN, 100.0, ""},
    {F_REFINE_ROTATION_EPSILON, 0.0, ""},
    {F_REFINE_ROTATION_EPSILON, 1.0, ""},
    {F_REFINE_TRANSLATION_EPSILON_GAIN, 0.0, ""},
    {F_REFINE_TRANSLATION_EPSILON_GAIN, 1.0, ""},
    {F_MIN_OVERLAP, 0.0, ""},
    {F_MIN_OVERLAP, 1.0, ""},
    {F_MAX_ROTATION_UNCERTAINTY, 1e-6, ""},
    {F_MAX_ROTATION_UNCERTAINTY, 3.15, ""},
    {F_MIN_INLIER_COVERAGE, 0.0, ""},
    {F_MIN_INLIER_COVERAGE, 1.0, ""},
    {F_REFINE_MIN_INLIERS, 3, ""},
    {F_REFINE_MIN_INLIERS, 100000, ""},
    {F_RESERVED1, 0, ""},
    {F_MIN_REFINE_CONDITION, 0.0, ""},
    {F_MIN_REFINE_CONDITION, 1.0, ""},
    {F_SUPPRESSION, KISSM_SUPPRESS_NONE, ""},
    {F_SUPPRESSION, KISSM_SUPPRESS_GROUND, ""},
    {F_ROTATION_DOF, 1, ""},
    {F_ROTATION_DOF, 3, ""},
    {F_UP0, -1e300, ""}, /* normalised without overflow */
    {F_UP_ALL, 1e-9 / 1.5, ""},
    {F_SENSOR_HEIGHT, 0.0, ""},
    {F_SENSOR_HEIGHT, 1000.0, ""},
    {F_MAX_REFINE_RMSE_GAIN, 1e-300, ""},
    {F_MAX_REFINE_RMSE_GAIN, 100.0, ""},
    {F_ALLOW_DEGENERATE, 0, ""},
    {F_ALLOW_DEGENERATE, 1, ""},
};

static void test_config_fields(void) {
    size_t i;
    for (i = 0; i < sizeof(k_bad_fields) / sizeof(k_bad_fields[0]); ++i) {
        const field_case *fc = &k_bad_fields[i];
        kissm_config c = scn_config(0.3);
        kissm_matcher *m = SENTINEL_MATCHER;
        int32_t st;
        set_field(&c, fc->field, fc->value);
        st = kissm_config_validate(&c);
        CHECK_MSG(st == KISSM_ERR_INVALID_ARGUMENT, "validate: %s = %g gave %d", fc->word, fc->value, (int)st);
        CHECK_MSG(msg_has(fc->word), "validate: %s = %g", fc->word, fc->value);
        st = kissm_create(&c, &m);
        CHECK_MSG(st == KISSM_ERR_INVALID_ARGUMENT, "create: %s = %g gave %d", fc->word, fc->value, (int)st);
        CHECK_MSG(msg_has(fc->word), "create: %s = %g", fc->word, fc->value);
        CHECK(m == SENTINEL_MATCHER);
        if (m != SENTINEL_MATCHER && m != NULL) kissm_destroy(m);
    }
    for (i = 0; i < sizeof(k_good_fields) / sizeof(k_good_fields[0]); ++i) {
        const field_case *fc = &k_good_fields[i];
        kissm_config c = scn_config(0.3);
        kissm_matcher *m = NULL;
        set_field(&c, fc->field, fc->value);
        CHECK_MSG(kissm_config_validate(&c) == KISSM_OK, "field %d = %g: %s", fc->field, fc->value,
                  kissm_last_error_message());
        CHECK_MSG(kissm_create(&c, &m) == KISSM_OK, "field %d = %g", fc->field, fc->value);
        CHECK(m != NULL);
        kissm_destroy(m);
    }
}

/* ---------------------------------------------------------------------------------------------- */
/* struct_size                                                                                      */
/* ---------------------------------------------------------------------------------------------- */

typedef struct newer_config {
    kissm_config base;
    unsigned char future[24];
} newer_config;

typedef struct newer_result {
    kissm_result base;
    double future[3];
} newer_result;

static void test_struct_sizes(void) {
    const uint32_t small_sizes[] = {0u, 4u, 8u, (uint32_t)sizeof(kissm_config) - 8u,
                                    (uint32_t)sizeof(kissm_config) - 1u};
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    size_t i;

    /* config too small */
    for (i = 0; i < sizeof(small_sizes) / sizeof(small_sizes[0]); ++i) {
        kissm_config c = scn_config(GOOD_VOXEL);
        kissm_matcher *m = SENTINEL_MATCHER;
        c.struct_size = small_sizes[i];
        CHECK_EQ_INT(kissm_config_validate(&c), KISSM_ERR_STRUCT_SIZE);
        CHECK(msg_has("struct_size"));
        CHECK_EQ_INT(kissm_create(&c, &m), KISSM_ERR_STRUCT_SIZE);
        CHECK(msg_has("struct_size"));
        CHECK(m == SENTINEL_MATCHER);
    }
    /* config larger with a zero tail: accepted, same behaviour */
    {
        newer_config big;
        kissm_matcher *m = NULL;
        kissm_config got;
        REQUIRE(kissm_config_init(&big.base, (uint32_t)sizeof(big)) == KISSM_OK);
        for (i = 0; i < sizeof(big.future); ++i) CHECK(big.future[i] == 0);
        big.base.voxel_size = GOOD_VOXEL;
        CHECK_EQ_INT(kissm_config_validate(&big.base), KISSM_OK);
        CHECK_EQ_INT(kissm_create(&big.base, &m), KISSM_OK);
        REQUIRE(m != NULL);
        got.struct_size = (uint32_t)sizeof(got);
        CHECK_EQ_INT(kissm_get_config(m, &got), KISSM_OK);
        CHECK(got.voxel_size == GOOD_VOXEL);
        CHECK_EQ_INT(got.struct_size, sizeof(got));
        check_usable(m, "larger config");
        kissm_destroy(m);
        /* ... and a non-zero tail (a newer field this kissm would ignore): STRUCT_SIZE */
        for (i = 0; i < sizeof(big.future); i += sizeof(big.future) - 1) {
            kissm_matcher *m2 = SENTINEL_MATCHER;
            memset(big.future, 0, sizeof(big.future));
            big.future[i] = 1;
            CHECK_EQ_INT(kissm_config_validate(&big.base), KISSM_ERR_STRUCT_SIZE);
            CHECK(msg_has("struct_size"));
            CHECK_EQ_INT(kissm_create(&big.base, &m2), KISSM_ERR_STRUCT_SIZE);
            CHECK(m2 == SENTINEL_MATCHER);
        }
    }

    /* absurd sizes (an uninitialised field): refused before any byte past the known layout is touched */
    {
        const uint32_t huge[] = {65537u, 0x5A5A5A5Au, 0xFFFFFFFFu};
        for (i = 0; i < sizeof(huge) / sizeof(huge[0]); ++i) {
            kissm_config c = scn_config(GOOD_VOXEL);
            kissm_matcher *m = SENTINEL_MATCHER;
            kissm_result r;
            unsigned char before[sizeof(kissm_result)];
            c.struct_size = huge[i];
            CHECK_EQ_INT(kissm_config_validate(&c), KISSM_ERR_STRUCT_SIZE);
            CHECK_EQ_INT(kissm_create(&c, &m), KISSM_ERR_STRUCT_SIZE);
            CHECK(m == SENTINEL_MATCHER);
            CHECK_EQ_INT(kissm_config_init(&c, huge[i]), KISSM_ERR_STRUCT_SIZE);
            c.struct_size = huge[i];
            CHECK_EQ_INT(kissm_get_config(g_m, &c), KISSM_ERR_STRUCT_SIZE);
            CHECK_EQ_INT(c.struct_size, huge[i]);
            memset(&r, 0x5A, sizeof(r));
            memcpy(before, &r, sizeof(r));
            CHECK_EQ_INT(kissm_result_init(&r, huge[i]), KISSM_ERR_STRUCT_SIZE);
            CHECK(memcmp(&r, before, sizeof(r)) == 0);
            memset(&r, 0x5A, sizeof(r));
            r.struct_size = huge[i];
            memcpy(before, &r, sizeof(r));
            CHECK_EQ_INT(kissm_register(g_m, &s, &t, &r), KISSM_ERR_STRUCT_SIZE);
            CHECK(msg_has("struct_size"));
            CHECK(memcmp(&r, before, sizeof(r)) == 0);
        }
    }

    /* result too small: STRUCT_SIZE, and nothing written at or beyond the size the caller claims. */
    {
        const uint32_t rsizes[] = {0u, 4u, 16u, (uint32_t)sizeof(kissm_result) - 8u};
        kissm_features *fs = NULL, *ft = NULL;
        REQUIRE(kissm_features_compute(g_m, &s, &fs) == KISSM_OK);
        REQUIRE(kissm_features_compute(g_m, &t, &ft) == KISSM_OK);
        for (i = 0; i < sizeof(rsizes) / sizeof(rsizes[0]); ++i) {
            int pass;
            for (pass = 0; pass < 2; ++pass) {
                unsigned char before[sizeof(kissm_result)];
                kissm_result r;
                int32_t st;
                memset(&r, 0x5A, sizeof(r));
                r.struct_size = rsizes[i];
                memcpy(before, &r, sizeof(r));
                st = pass == 0 ? kissm_register(g_m, &s, &t, &r) : kissm_register_features(g_m, fs, ft, &r);
                CHECK_MSG(st == KISSM_ERR_STRUCT_SIZE, "result struct_size %u pass %d: %d", (unsigned)rsizes[i], pass,
                          (int)st);
                CHECK(msg_has("struct_size"));
                CHECK_EQ_INT(r.struct_size, rsizes[i]);
                CHECK(memcmp((unsigned char *)&r + (rsizes[i] < 4 ? 4 : rsizes[i]),
                             before + (rsizes[i] < 4 ? 4 : rsizes[i]),
                             sizeof(r) - (rsizes[i] < 4 ? 4 : rsizes[i])) == 0);
            }
        }
        /* result larger (a newer caller): accepted; the unknown tail is overwritten too (zero). */
        {
            newer_result big;
            int pass;
            for (pass = 0; pass < 2; ++pass) {
                memset(&big, 0x5A, sizeof(big));
                big.base.struct_size = (uint32_t)sizeof(big);
                CHECK_EQ_INT(pass == 0 ? kissm_register(g_m, &s, &t, &big.base)
                                       : kissm_register_features(g_m, fs, ft, &big.base),
                             KISSM_OK);
                CHECK_EQ_INT(big.base.struct_size, sizeof(big));
                CHECK_EQ_INT(big.base.valid, 1);
                CHECK(scn_result_poison_left(&big.base) == 0);
                CHECK(big.future[0] == 0.0 && big.future[1] == 0.0 && big.future[2] == 0.0);
            }
            /* a failing call with a larger result: reset including the tail */
            {
                kissm_points empty = s;
                empty.count = 0;
                memset(&big, 0x5A, sizeof(big));
                big.base.struct_size = (uint32_t)sizeof(big);
                CHECK_EQ_INT(kissm_register(g_m, &empty, &t, &big.base), KISSM_ERR_EMPTY_INPUT);
                CHECK_EQ_INT(big.base.struct_size, sizeof(big));
                CHECK_EQ_INT(big.base.valid, 0);
                CHECK(isnan(big.base.transform[3]));
                CHECK(scn_result_poison_left(&big.base) == 0);
                CHECK(big.future[0] == 0.0 && big.future[2] == 0.0);
            }
        }
        kissm_features_destroy(fs);
        kissm_features_destroy(ft);
    }
    check_usable(g_m, "struct sizes");
}

/* ---------------------------------------------------------------------------------------------- */
/* Degenerate but well-formed input: KISSM_OK, valid = 0, a reason                                 */
/* ---------------------------------------------------------------------------------------------- */

static void check_invalid_result(const char *what, kissm_matcher *m, const scn_cloud *a, const scn_cloud *b,
                                 int32_t expected_reason) {
    kissm_points s = scn_points(a), t = scn_points(b);
    kissm_result r;
    int32_t st;
    scn_result_poison(&r);
    st = kissm_register(m, &s, &t, &r);
    CHECK_MSG(st == KISSM_OK, "%s: status %d (%s)", what, (int)st, kissm_last_error_message());
    CHECK_MSG(r.valid == 0, "%s: valid", what);
    CHECK_MSG(r.reason > KISSM_REASON_NONE && r.reason <= KISSM_REASON_NOT_CONVERGED, "%s: reason %d", what,
              (int)r.reason);
    if (expected_reason >= 0) CHECK_MSG(r.reason == expected_reason, "%s: reason %d", what, (int)r.reason);
    CHECK_MSG(scn_result_poison_left(&r) == 0, "%s: poison left", what);
    CHECK_EQ_INT(r.num_source_points, a->count);
    CHECK_EQ_INT(r.num_target_points, b->count);
    /* Either no pose at all (NaN) or an estimated one kept for inspection with a proper last row. */
    if (!isnan(r.transform[0])) {
        CHECK(r.transform[12] == 0.0 && r.transform[13] == 0.0 && r.transform[14] == 0.0 && r.transform[15] == 1.0);
    } else {
        CHECK(isnan(r.rotation[0]) && isnan(r.translation[0]));
    }
    if (r.valid != 0 || (expected_reason >= 0 && r.reason != expected_reason)) scn_result_print(what, &r);
}

static void test_degenerate(void) {
    kissm_config c = scn_config(0.3);
    kissm_matcher *m = NULL;
    scn_cloud a, b;
    const double axis[3] = {0.3, 1.0, -0.2}, shift[3] = {1.0, -2.0, 0.5};
    scn_pose pose;
    scn_cloud_init(&a);
    scn_cloud_init(&b);
    scn_pose_axis_angle(&pose, axis, 1.2, shift);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);

    /* collinear: a line and a moved, independently sampled copy */
    scn_make_line(&a, 11, 6000, 0.003);
    scn_make_line(&b, 12, 6000, 0.003);
    scn_cloud_apply(&b, &pose);
    check_invalid_result("collinear", m, &a, &b, -1);

    /* planar */
    scn_make_plane(&a, 21, 12000, 0.01);
    scn_make_plane(&b, 22, 12000, 0.01);
    scn_cloud_apply(&b, &pose);
    check_invalid_result("planar", m, &a, &b, -1);

    /* all duplicates: one voxel */
    scn_make_duplicates(&a, 4, 1.0, 2.0, 3.0);
    scn_make_duplicates(&b, 4, -1.0, 0.5, 7.0);
    check_invalid_result("4 duplicates", m, &a, &b, KISSM_REASON_TOO_FEW_VOXELS);
    scn_make_duplicates(&a, 5000, 1.0, 2.0, 3.0);
    check_invalid_result("5000 duplicates vs 4", m, &a, &b, KISSM_REASON_TOO_FEW_VOXELS);
    check_invalid_result("duplicates vs a scene", m, &a, &g_pair.target, KISSM_REASON_TOO_FEW_VOXELS);
    check_invalid_result("a scene vs duplicates", m, &g_pair.source, &a, KISSM_REASON_TOO_FEW_VOXELS);

    /* unrelated clouds far apart: a scene and a random volume 10 km away */
    {
        const double far[3] = {1e4, -1e4, 50.0};
        scn_make_blob(&b, 31, 12000, far, 6.0);
        check_invalid_result("scene vs far random blob", m, &g_pair.source, &b, -1);
        check_invalid_result("far random blob vs scene", m, &b, &g_pair.target, -1);
    }
    /* a line against a scene */
    scn_make_line(&a, 41, 6000, 0.003);
    check_invalid_result("line vs scene", m, &a, &g_pair.target, -1);
    check_usable(g_m, "degenerate inputs");

    kissm_destroy(m);
    scn_cloud_free(&a);
    scn_cloud_free(&b);
}

/* ---------------------------------------------------------------------------------------------- */
/* kissm_refine and kissm_refine_features                                                          */
/* ---------------------------------------------------------------------------------------------- */

/* Both entry points on g_pair, from the truth: status, and what the result and the transform hold after. */
static int32_t call_refine(int features, kissm_matcher *m, const double *initial, kissm_result *r) {
    static kissm_features *fs = NULL, *ft = NULL;
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    if (m == NULL && initial == NULL && r == NULL) { /* cleanup */
        kissm_features_destroy(fs);
        kissm_features_destroy(ft);
        fs = ft = NULL;
        return KISSM_OK;
    }
    if (!features) return kissm_refine(m, &s, &t, initial, r);
    if (fs == NULL &&
        (kissm_features_compute(g_m, &s, &fs) != KISSM_OK || kissm_features_compute(g_m, &t, &ft) != KISSM_OK))
        return -1000;
    return kissm_refine_features(m, fs, ft, initial, r);
}

static const char *const k_refine_names[2] = {"kissm_refine", "kissm_refine_features"};

static void test_refine_null_pointers(void) {
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_features *fs = NULL, *ft = NULL;
    double initial[16];
    kissm_result r;
    int pass;
    scn_pose_to_matrix(&g_pair.truth, initial);
    REQUIRE(kissm_features_compute(g_m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(g_m, &t, &ft) == KISSM_OK);

    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(NULL, &s, &t, initial, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("matcher"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(g_m, NULL, &t, initial, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("source"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(g_m, &s, NULL, initial, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("target"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(g_m, &s, &t, NULL, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("initial_transform"));
    CHECK(scn_result_is_reset(&r));
    CHECK_EQ_INT(kissm_refine(g_m, &s, &t, initial, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("result"));
    CHECK_EQ_INT(kissm_refine(NULL, NULL, NULL, NULL, NULL), KISSM_ERR_NULL_ARGUMENT);
    {
        kissm_points no_data = s;
        no_data.data = NULL;
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine(g_m, &no_data, &t, initial, &r), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("source") && msg_has("data"));
        CHECK(scn_result_is_reset(&r));
    }

    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine_features(NULL, fs, ft, initial, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("matcher"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine_features(g_m, NULL, ft, initial, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("source"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine_features(g_m, fs, NULL, initial, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("target"));
    CHECK(scn_result_is_reset(&r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine_features(g_m, fs, ft, NULL, &r), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("initial_transform"));
    CHECK(scn_result_is_reset(&r));
    CHECK_EQ_INT(kissm_refine_features(g_m, fs, ft, initial, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("result"));
    CHECK_EQ_INT(kissm_refine_features(NULL, NULL, NULL, NULL, NULL), KISSM_ERR_NULL_ARGUMENT);

    /* and both work afterwards */
    for (pass = 0; pass < 2; ++pass) {
        scn_result_poison(&r);
        CHECK_MSG((pass ? kissm_refine_features(g_m, fs, ft, initial, &r) : kissm_refine(g_m, &s, &t, initial, &r)) ==
                      KISSM_OK,
                  "%s: %s", k_refine_names[pass], kissm_last_error_message());
        CHECK_EQ_INT(r.valid, 1);
        CHECK(strcmp(kissm_last_error_message(), "") == 0);
    }
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    check_usable(g_m, "refine NULLs");
}

/* Initial transforms that are not a finite rigid motion: exactly KISSM_ERR_INVALID_ARGUMENT naming
 * initial_transform, the result reset, the transform itself untouched, the matcher usable. */
typedef struct transform_case {
    const char *name;
    int index;    /* entry changed (-1: see below) */
    double value; /* its new value */
    double scale; /* the rotation block times this (1 = unchanged) */
    int reflect;  /* negate the third column of the rotation block */
} transform_case;

static const transform_case k_bad_transforms[] = {
    {"NaN rotation entry", 0, NAN, 1.0, 0},
    {"NaN rotation entry", 5, NAN, 1.0, 0},
    {"NaN translation", 3, NAN, 1.0, 0},
    {"+Inf translation", 7, INFINITY, 1.0, 0},
    {"-Inf translation", 11, -INFINITY, 1.0, 0},
    {"+Inf rotation entry", 10, INFINITY, 1.0, 0},
    {"NaN in the last row", 15, NAN, 1.0, 0},
    {"-Inf in the last row", 12, -INFINITY, 1.0, 0},
    {"translation 2e9", 3, 2e9, 1.0, 0},
    {"translation -1e10", 7, -1e10, 1.0, 0},
    {"translation 1e300", 11, 1e300, 1.0, 0},
    {"scaled by 1.01", -1, 0.0, 1.01, 0},
    {"scaled by 0.5", -1, 0.0, 0.5, 0},
    {"scaled by 2", -1, 0.0, 2.0, 0},
    {"scaled by 0", -1, 0.0, 0.0, 0},
    {"scaled by -1 (a rotation by 180 deg and a reflection)", -1, 0.0, -1.0, 0},
    {"reflected (det -1)", -1, 0.0, 1.0, 1},
    {"sheared", 1, 0.05, 1.0, 0},
    {"sheared slightly beyond 1e-3", 2, 0.0015, 1.0, 0},
    {"last row (0, 0, 0, 2)", 15, 2.0, 1.0, 0},
    {"last row (0, 0, 0, 0)", 15, 0.0, 1.0, 0},
    {"last row (0.1, 0, 0, 1)", 12, 0.1, 1.0, 0},
    {"last row (0, 0, -1e-12, 1)", 14, -1e-12, 1.0, 0},
};

static void make_bad_transform(const transform_case *tc, double m[16]) {
    int i, j;
    /* identity rotation except where the case says: entries 1 and 2 are off-diagonal */
    for (i = 0; i < 16; ++i) m[i] = (i % 5 == 0) ? 1.0 : 0.0;
    m[3] = 0.5, m[7] = -0.25, m[11] = 0.125;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) m[4 * i + j] *= tc->scale;
    if (tc->reflect)
        for (i = 0; i < 3; ++i) m[4 * i + 2] = -m[4 * i + 2];
    if (tc->index >= 0) m[tc->index] = tc->value;
}

static void test_refine_bad_initial_transform(void) {
    size_t i;
    int pass;
    for (pass = 0; pass < 2; ++pass) {
        for (i = 0; i < sizeof(k_bad_transforms) / sizeof(k_bad_transforms[0]); ++i) {
            const transform_case *tc = &k_bad_transforms[i];
            double m[16], copy[16];
            kissm_result r;
            int32_t st;
            make_bad_transform(tc, m);
            memcpy(copy, m, sizeof(m));
            scn_result_poison(&r);
            st = call_refine(pass, g_m, m, &r);
            CHECK_MSG(st == KISSM_ERR_INVALID_ARGUMENT, "%s, %s: status %d (%s)", k_refine_names[pass], tc->name,
                      (int)st, kissm_last_error_message());
            CHECK_MSG(msg_has("initial_transform"), "%s, %s", k_refine_names[pass], tc->name);
            CHECK_MSG(scn_result_is_reset(&r), "%s, %s", k_refine_names[pass], tc->name);
            CHECK(memcmp(m, copy, sizeof(m)) == 0);
        }
        /* every entry in turn NaN: each refused */
        {
            int k, refused = 0;
            for (k = 0; k < 16; ++k) {
                double m[16];
                kissm_result r;
                scn_pose_to_matrix(&g_pair.truth, m);
                m[k] = NAN;
                scn_result_poison(&r);
                refused += call_refine(pass, g_m, m, &r) == KISSM_ERR_INVALID_ARGUMENT && scn_result_is_reset(&r) &&
                           strstr(kissm_last_error_message(), "initial_transform") != NULL;
            }
            CHECK_EQ_INT(refused, 16);
        }
        /* the boundaries: a translation of exactly 1e9 and a rotation off by less than 1e-3 are accepted (and
         * refine nothing: the clouds are 1e9 m apart) */
        {
            double m[16];
            kissm_result r;
            int32_t st;
            scn_pose_to_matrix(&g_pair.truth, m);
            m[3] = 1e9;
            m[7] = -1e9;
            scn_result_poison(&r);
            st = call_refine(pass, g_m, m, &r);
            CHECK_MSG(st == KISSM_OK, "%s, translation 1e9: %d (%s)", k_refine_names[pass], (int)st,
                      kissm_last_error_message());
            CHECK_EQ_INT(r.valid, 0);
            CHECK_EQ_INT(r.reason, KISSM_REASON_LOW_OVERLAP);
            CHECK(scn_result_poison_left(&r) == 0);
            scn_pose_to_matrix(&g_pair.truth, m);
            m[0] += 4e-4;
            scn_result_poison(&r);
            CHECK_EQ_INT(call_refine(pass, g_m, m, &r), KISSM_OK);
            CHECK_EQ_INT(r.valid, 1);
        }
        check_usable(g_m, k_refine_names[pass]);
    }
}

static void test_refine_struct_sizes_and_mismatch(void) {
    const uint32_t bad_sizes[] = {0u, 4u, 16u, 436u, 444u, (uint32_t)sizeof(kissm_result) - 8u, 65537u, 0x5A5A5A5Au};
    double initial[16];
    size_t i;
    int pass;
    scn_pose_to_matrix(&g_pair.truth, initial);
    for (pass = 0; pass < 2; ++pass) {
        for (i = 0; i < sizeof(bad_sizes) / sizeof(bad_sizes[0]); ++i) {
            unsigned char before[sizeof(kissm_result)];
            kissm_result r;
            int32_t st;
            memset(&r, 0x5A, sizeof(r));
            r.struct_size = bad_sizes[i];
            memcpy(before, &r, sizeof(r));
            st = call_refine(pass, g_m, initial, &r);
            CHECK_MSG(st == KISSM_ERR_STRUCT_SIZE, "%s, result struct_size %u: %d", k_refine_names[pass],
                      (unsigned)bad_sizes[i], (int)st);
            CHECK(msg_has("struct_size"));
            CHECK_EQ_INT(r.struct_size, bad_sizes[i]);
            /* nothing written at all (sizes the library refuses are never written into) */
            CHECK(memcmp(&r, before, sizeof(r)) == 0);
        }
        /* a bad result size wins over a bad transform: the result is never touched */
        {
            double nan_m[16];
            kissm_result r;
            memcpy(nan_m, initial, sizeof(nan_m));
            nan_m[0] = NAN;
            memset(&r, 0x5A, sizeof(r));
            r.struct_size = 8;
            CHECK_EQ_INT(call_refine(pass, g_m, nan_m, &r), KISSM_ERR_STRUCT_SIZE);
        }
    }
    /* features computed under other descriptor settings */
    {
        kissm_config c = scn_config(GOOD_VOXEL * 1.25);
        kissm_matcher *other = NULL;
        kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
        kissm_features *fs = NULL, *ft = NULL, *gs = NULL;
        kissm_result r;
        REQUIRE(kissm_create(&c, &other) == KISSM_OK);
        REQUIRE(kissm_features_compute(g_m, &s, &fs) == KISSM_OK);
        REQUIRE(kissm_features_compute(g_m, &t, &ft) == KISSM_OK);
        REQUIRE(kissm_features_compute(other, &s, &gs) == KISSM_OK);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine_features(g_m, gs, ft, initial, &r), KISSM_ERR_FEATURES_MISMATCH);
        CHECK(msg_has("source"));
        CHECK(scn_result_is_reset(&r));
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine_features(g_m, fs, gs, initial, &r), KISSM_ERR_FEATURES_MISMATCH);
        CHECK(msg_has("target"));
        CHECK(scn_result_is_reset(&r));
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine_features(other, fs, ft, initial, &r), KISSM_ERR_FEATURES_MISMATCH);
        CHECK(scn_result_is_reset(&r));
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine_features(g_m, fs, ft, initial, &r), KISSM_OK);
        CHECK_EQ_INT(r.valid, 1);
        kissm_features_destroy(fs);
        kissm_features_destroy(ft);
        kissm_features_destroy(gs);
        kissm_destroy(other);
    }
    /* the other argument checks of kissm_refine: the points tables, as kissm_register's */
    {
        size_t k;
        float *src32 = scn_cloud_to_float(&g_pair.source);
        const kissm_points good_t = scn_points(&g_pair.target);
        for (k = 0; k < sizeof(k_points_cases) / sizeof(k_points_cases[0]); ++k) {
            const points_case *pc = &k_points_cases[k];
            const kissm_points bad = make_case_points(pc, g_pair.source.xyz, src32);
            kissm_result r;
            int32_t st;
            scn_result_poison(&r);
            st = kissm_refine(g_m, &bad, &good_t, initial, &r);
            CHECK_MSG(st == pc->status, "kissm_refine, %s as source: %d (%s)", pc->name, (int)st,
                      kissm_last_error_message());
            CHECK_MSG(msg_has("source") && msg_has(pc->word), "kissm_refine, %s", pc->name);
            CHECK(scn_result_is_reset(&r));
            scn_result_poison(&r);
            st = kissm_refine(g_m, &good_t, &bad, initial, &r);
            CHECK_MSG(st == pc->status, "kissm_refine, %s as target: %d", pc->name, (int)st);
            CHECK(scn_result_is_reset(&r));
        }
        free(src32);
    }
    /* non-finite points: REJECT refuses them, as kissm_register does */
    {
        scn_cloud cloud;
        kissm_points p, good_t = scn_points(&g_pair.target);
        kissm_result r;
        scn_cloud_init(&cloud);
        scn_cloud_copy(&cloud, &g_pair.source);
        cloud.xyz[3 * 17 + 1] = NAN;
        p = scn_points(&cloud);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine(g_m, &p, &good_t, initial, &r), KISSM_ERR_NONFINITE);
        CHECK(msg_has("source"));
        CHECK(scn_result_is_reset(&r));
        scn_cloud_free(&cloud);
    }
    call_refine(0, NULL, NULL, NULL);
    check_usable(g_m, "refine sizes");
}

/* Degenerate clouds through the new entry points and with refinement on: KISSM_OK, valid = 0, a reason. */
static void check_invalid_refine(const char *what, kissm_matcher *m, const scn_cloud *a, const scn_cloud *b,
                                 const double initial[16], int32_t expected_reason) {
    kissm_points s = scn_points(a), t = scn_points(b);
    kissm_result r;
    int32_t st;
    scn_result_poison(&r);
    st = kissm_refine(m, &s, &t, initial, &r);
    CHECK_MSG(st == KISSM_OK, "%s: status %d (%s)", what, (int)st, kissm_last_error_message());
    CHECK_MSG(r.valid == 0 && r.reason > KISSM_REASON_NONE && r.reason <= KISSM_REASON_NOT_CONVERGED,
              "%s: valid %d reason %d", what, (int)r.valid, (int)r.reason);
    if (expected_reason >= 0) CHECK_MSG(r.reason == expected_reason, "%s: reason %d", what, (int)r.reason);
    CHECK_MSG(scn_result_poison_left(&r) == 0, "%s: poison left", what);
    CHECK(r.transform[15] == 1.0 && !isnan(r.overlap));
}

static void test_refine_degenerate(void) {
    kissm_config c = scn_config(0.3);
    kissm_matcher *m = NULL;
    scn_cloud a, b;
    const double axis[3] = {0.3, 1.0, -0.2}, shift[3] = {1.0, -2.0, 0.5};
    double initial[16];
    scn_pose pose;
    scn_cloud_init(&a);
    scn_cloud_init(&b);
    scn_pose_axis_angle(&pose, axis, 1.2, shift);
    scn_pose_to_matrix(&pose, initial);
    c.refine_mode = KISSM_REFINE_GICP;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);

    /* a line has no normals: nothing to match */
    scn_make_line(&a, 11, 6000, 0.003);
    scn_make_line(&b, 12, 6000, 0.003);
    scn_cloud_apply(&b, &pose);
    check_invalid_refine("collinear", m, &a, &b, initial, KISSM_REASON_LOW_OVERLAP);
    check_invalid_result("collinear, register + GICP", m, &a, &b, -1);
    /* a plane slides */
    scn_make_plane(&a, 21, 12000, 0.01);
    scn_make_plane(&b, 22, 12000, 0.01);
    scn_cloud_apply(&b, &pose);
    check_invalid_refine("planar", m, &a, &b, initial, KISSM_REASON_UNCONSTRAINED);
    check_invalid_result("planar, register + GICP", m, &a, &b, -1);
    /* duplicates: one voxel, no normal */
    scn_make_duplicates(&a, 4, 1.0, 2.0, 3.0);
    scn_make_duplicates(&b, 5000, -1.0, 0.5, 7.0);
    check_invalid_refine("duplicates", m, &a, &b, initial, KISSM_REASON_LOW_OVERLAP);
    check_invalid_refine("duplicates vs a scene", m, &a, &g_pair.target, initial, KISSM_REASON_LOW_OVERLAP);
    check_invalid_refine("a scene vs duplicates", m, &g_pair.source, &b, initial, KISSM_REASON_LOW_OVERLAP);
    check_invalid_result("duplicates, register + GICP", m, &a, &b, KISSM_REASON_TOO_FEW_VOXELS);
    /* unrelated: a scene and a random volume 10 km away, and the scene against that volume moved onto it */
    {
        const double far[3] = {1e4, -1e4, 50.0}, near[3] = {0.0, 0.0, 0.0};
        scn_make_blob(&b, 31, 12000, far, 6.0);
        check_invalid_refine("scene vs far random blob", m, &g_pair.source, &b, initial, KISSM_REASON_LOW_OVERLAP);
        check_invalid_result("scene vs far random blob, register + GICP", m, &g_pair.source, &b, -1);
        scn_make_blob(&b, 32, 12000, near, 6.0);
        check_invalid_refine("scene in a random blob", m, &g_pair.source, &b, initial, -1);
    }
    check_usable(g_m, "degenerate refinement");
    kissm_destroy(m);
    scn_cloud_free(&a);
    scn_cloud_free(&b);
}

/* ---------------------------------------------------------------------------------------------- */
/* Pose graphs                                                                                      */
/* ---------------------------------------------------------------------------------------------- */

/* An edge that add_edge refuses: the status, the argument its message names, and the graph unchanged (no edge,
 * out_edge untouched, the last solution kept). */
static void check_refused_edge(kissm_pose_graph *g, uint64_t s, uint64_t t, const double T[16], const double I[36],
                               int32_t robust, int32_t status, const char *word, const char *what) {
    uint64_t id = 777, before = kissm_pose_graph_num_edges(g);
    uint8_t placed[3] = {9, 9, 9}; /* the graph of test_pose_graph_bad_input: 3 nodes */
    int32_t st = kissm_pose_graph_add_edge(g, s, t, T, I, robust, &id);
    CHECK_MSG(st == status, "%s: status %d (%s)", what, (int)st, kissm_last_error_message());
    CHECK_MSG(msg_has(word), "%s", what);
    CHECK_MSG(id == 777 && kissm_pose_graph_num_edges(g) == before, "%s: the graph changed", what);
    CHECK_MSG(kissm_pose_graph_poses(g, NULL, placed, NULL) == KISSM_OK && placed[0] == 1 && placed[1] == 1,
              "%s: solution lost", what);
}

static void test_pose_graph_bad_input(void) {
    kissm_pose_graph *g = SENTINEL_POSE_GRAPH;
    double T[16], I[36], bad[36], out_pose[16 * 3];
    uint8_t flags[3];
    size_t i;
    int k;
    for (k = 0; k < 16; ++k) T[k] = (k % 5 == 0) ? 1.0 : 0.0;
    T[3] = 1.0;
    memset(I, 0, sizeof(I));
    for (k = 0; k < 6; ++k) I[7 * k] = 100.0;
    I[1] = I[6] = 10.0; /* symmetric, positive definite */

    /* create */
    CHECK_EQ_INT(kissm_pose_graph_create(3, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("out_graph"));
    CHECK_EQ_INT(kissm_pose_graph_create(0, &g), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("num_nodes") && g == SENTINEL_POSE_GRAPH);
    CHECK_EQ_INT(kissm_pose_graph_create((uint64_t)KISSM_POSE_GRAPH_MAX_NODES + 1u, &g), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("num_nodes") && g == SENTINEL_POSE_GRAPH);
    REQUIRE(kissm_pose_graph_create(3, &g) == KISSM_OK);

    /* NULLs */
    CHECK_EQ_INT(kissm_pose_graph_add_edge(NULL, 0, 1, T, I, 1, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("graph"));
    CHECK_EQ_INT(kissm_pose_graph_optimize(NULL, 0, 1.0), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_pose_graph_poses(NULL, out_pose, flags, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_pose_graph_edges(NULL, flags, NULL), KISSM_ERR_NULL_ARGUMENT);
    /* no solution yet: outputs untouched */
    memset(flags, 9, sizeof(flags));
    CHECK_EQ_INT(kissm_pose_graph_poses(g, NULL, flags, NULL), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("solution") && flags[0] == 9);
    CHECK_EQ_INT(kissm_pose_graph_edges(g, flags, NULL), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(flags[0] == 9);

    /* one good edge and a solution, which every refused edge below must leave in place */
    REQUIRE(kissm_pose_graph_add_edge(g, 1, 0, T, I, 1, NULL) == KISSM_OK);
    REQUIRE(kissm_pose_graph_optimize(g, 0, KISSM_POSE_GRAPH_DEFAULT_BOUND) == KISSM_OK);
    check_refused_edge(g, 0, 1, NULL, I, 1, KISSM_ERR_NULL_ARGUMENT, "transform", "NULL transform");
    check_refused_edge(g, 0, 1, T, NULL, 1, KISSM_ERR_NULL_ARGUMENT, "information", "NULL information");
    check_refused_edge(g, 3, 1, T, I, 1, KISSM_ERR_INVALID_ARGUMENT, "source", "source out of range");
    check_refused_edge(g, 0, UINT64_MAX, T, I, 1, KISSM_ERR_INVALID_ARGUMENT, "target", "target out of range");
    check_refused_edge(g, 2, 2, T, I, 1, KISSM_ERR_INVALID_ARGUMENT, "source and target", "self edge");
    check_refused_edge(g, 0, 1, T, I, 2, KISSM_ERR_INVALID_ARGUMENT, "robust", "robust 2");
    check_refused_edge(g, 0, 1, T, I, -1, KISSM_ERR_INVALID_ARGUMENT, "robust", "robust -1");
    for (i = 0; i < sizeof(k_bad_transforms) / sizeof(k_bad_transforms[0]); ++i) {
        double m[16];
        make_bad_transform(&k_bad_transforms[i], m);
        check_refused_edge(g, 0, 1, m, I, 1, KISSM_ERR_INVALID_ARGUMENT, "transform", k_bad_transforms[i].name);
    }
    for (k = 0; k < 16; ++k) {
        double m[16];
        memcpy(m, T, sizeof(m));
        m[k] = NAN;
        check_refused_edge(g, 0, 1, m, I, 1, KISSM_ERR_INVALID_ARGUMENT, "transform", "NaN in transform");
    }
    for (k = 0; k < 36; ++k) {
        memcpy(bad, I, sizeof(bad));
        bad[k] = k % 2 ? INFINITY : NAN;
        check_refused_edge(g, 0, 1, T, bad, 1, KISSM_ERR_INVALID_ARGUMENT, "information", "non-finite information");
    }
    memcpy(bad, I, sizeof(bad));
    bad[1] = 10.001; /* I[0][1] != I[1][0] */
    check_refused_edge(g, 0, 1, T, bad, 1, KISSM_ERR_INVALID_ARGUMENT, "symmetric", "asymmetric information");
    memcpy(bad, I, sizeof(bad));
    bad[35] = 0.0; /* singular */
    check_refused_edge(g, 0, 1, T, bad, 1, KISSM_ERR_INVALID_ARGUMENT, "positive definite", "singular information");
    memcpy(bad, I, sizeof(bad));
    bad[14] = -1.0; /* a negative eigenvalue */
    check_refused_edge(g, 0, 1, T, bad, 1, KISSM_ERR_INVALID_ARGUMENT, "positive definite", "indefinite information");
    memset(bad, 0, sizeof(bad));
    check_refused_edge(g, 0, 1, T, bad, 1, KISSM_ERR_INVALID_ARGUMENT, "positive definite", "zero information");
    /* symmetric to within 1e-9 of the largest entry: accepted */
    memcpy(bad, I, sizeof(bad));
    bad[1] += 1e-8;
    CHECK_EQ_INT(kissm_pose_graph_add_edge(g, 2, 1, T, bad, 1, NULL), KISSM_OK);

    /* optimize: the anchor and the bound; a refused call keeps the last solution */
    REQUIRE(kissm_pose_graph_optimize(g, 0, KISSM_POSE_GRAPH_DEFAULT_BOUND) == KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 3, 1.0), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("anchor"));
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, 0.0), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("bound"));
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, -1.0), KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, NAN), KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, INFINITY), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(msg_has("bound"));
    CHECK_EQ_INT(kissm_pose_graph_poses(g, out_pose, flags, NULL), KISSM_OK);
    CHECK(flags[0] == 1 && flags[1] == 1 && flags[2] == 1);
    kissm_pose_graph_destroy(g);
}

int main(void) {
    scn_make_pair(&g_pair, 7, 6.0, 0.01);
    {
        kissm_config c = scn_config(GOOD_VOXEL);
        if (kissm_create(&c, &g_m) != KISSM_OK) {
            fprintf(stderr, "cannot create the matcher: %s\n", kissm_last_error_message());
            return 1;
        }
    }
    RUN_TEST(test_null_pointers);
    RUN_TEST(test_bad_points);
    RUN_TEST(test_valid_strides);
    RUN_TEST(test_nonfinite);
    RUN_TEST(test_voxel_size);
    RUN_TEST(test_suggest_voxel_size);
    RUN_TEST(test_config_fields);
    RUN_TEST(test_struct_sizes);
    RUN_TEST(test_degenerate);
    RUN_TEST(test_refine_null_pointers);
    RUN_TEST(test_refine_bad_initial_transform);
    RUN_TEST(test_refine_struct_sizes_and_mismatch);
    RUN_TEST(test_refine_degenerate);
    RUN_TEST(test_pose_graph_bad_input);
    kissm_destroy(g_m);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
