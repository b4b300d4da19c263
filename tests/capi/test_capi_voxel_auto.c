/* SPDX-License-Identifier: MIT */
/* The automatic voxel size: kissm_suggest_voxel_size (one cloud, a pair, a set) and kissm_config.voxel_size = 0,
 * which registers with the pair's suggestion and reports it in kissm_result.voxel_size_used. The suggestion is
 * symmetric, order-free, scales exactly with the clouds and does not depend on the thread count; the registration
 * with it is the registration at that voxel, bit for bit. C99. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

static scn_pair g_pair;

static double suggest(const scn_cloud *a, const scn_cloud *b) {
    kissm_points p[2];
    double v = -1.0;
    int32_t st;
    p[0] = scn_points(a);
    if (b != NULL) p[1] = scn_points(b);
    st = kissm_suggest_voxel_size(p, b != NULL ? 2 : 1, &v);
    CHECK_MSG(st == KISSM_OK, "status %d: %s", (int)st, kissm_last_error_message());
    return v;
}

static void register_with(double voxel, int32_t threads, const scn_cloud *s, const scn_cloud *t, kissm_result *r) {
    kissm_config c = scn_config(voxel);
    kissm_matcher *m = NULL;
    kissm_points sp = scn_points(s), tp = scn_points(t);
    c.num_threads = threads;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(r);
    CHECK_MSG(kissm_register(m, &sp, &tp, r) == KISSM_OK, "%s", kissm_last_error_message());
    CHECK(scn_result_poison_left(r) == 0);
    kissm_destroy(m);
}

/* The pair's suggestion: a rung of the ladder 2^(k/8), the smaller of the clouds' own, the same either way round. */
static void test_suggestion_rule(void) {
    const double vs = suggest(&g_pair.source, NULL), vt = suggest(&g_pair.target, NULL);
    const double v = suggest(&g_pair.source, &g_pair.target), k = 8.0 * log2(v);
    CHECK(v > 0.0 && isfinite(v));
    CHECK(v == (vs < vt ? vs : vt));
    CHECK(v == suggest(&g_pair.target, &g_pair.source));
    CHECK_MSG(fabs(k - floor(k + 0.5)) < 1e-9, "voxel %.17g is not a rung 2^(k/8)", v);
    /* a set: the lower median of its clouds' own suggestions (clouds scaled by 1, 2, 4 and 8 suggest v, 2v, 4v
     * and 8v exactly: see the invariance test), in any order */
    {
        scn_cloud scaled[4];
        kissm_points p[4];
        double set = -1.0;
        size_t c, i;
        for (c = 0; c < 4; ++c) {
            scn_cloud_init(&scaled[c]);
            scn_cloud_copy(&scaled[c], &g_pair.source);
            for (i = 0; i < 3 * scaled[c].count; ++i) scaled[c].xyz[i] *= (double)(1u << c);
        }
        p[0] = scn_points(&scaled[2]), p[1] = scn_points(&scaled[0]), p[2] = scn_points(&scaled[1]);
        CHECK_EQ_INT(kissm_suggest_voxel_size(p, 3, &set), KISSM_OK);
        CHECK_MSG(set == 2.0 * vs, "%.17g vs 2 x %.17g", set, vs);
        p[3] = scn_points(&scaled[3]);
        CHECK_EQ_INT(kissm_suggest_voxel_size(p, 4, &set), KISSM_OK);
        CHECK(set == 2.0 * vs); /* four: the second smallest */
        CHECK_EQ_INT(kissm_suggest_voxel_size(&p[1], 2, &set), KISSM_OK);
        CHECK(set == vs); /* a pair: the smaller */
        for (c = 0; c < 4; ++c) scn_cloud_free(&scaled[c]);
    }
}

/* Occupied voxels of side v, anchored at the cloud's minimum, counted as the library counts them. */
static int cmp_u64(const void *a, const void *b) {
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static size_t occupied(const scn_cloud *c, double v) {
    double lo[3], hi[3];
    uint64_t cells[3], *keys = (uint64_t *)malloc(c->count * sizeof *keys);
    size_t i, n = 0;
    int a;
    CHECK(keys != NULL);
    if (keys == NULL) return 0;
    for (a = 0; a < 3; ++a) lo[a] = hi[a] = c->xyz[a];
    for (i = 0; i < c->count; ++i)
        for (a = 0; a < 3; ++a) {
            if (c->xyz[3 * i + a] < lo[a]) lo[a] = c->xyz[3 * i + a];
            if (c->xyz[3 * i + a] > hi[a]) hi[a] = c->xyz[3 * i + a];
        }
    for (a = 0; a < 3; ++a) cells[a] = (uint64_t)((hi[a] - lo[a]) * (1.0 / v)) + 1;
    for (i = 0; i < c->count; ++i) {
        uint64_t k[3];
        for (a = 0; a < 3; ++a) {
            k[a] = (uint64_t)((c->xyz[3 * i + a] - lo[a]) * (1.0 / v));
            if (k[a] > cells[a] - 1) k[a] = cells[a] - 1;
        }
        keys[i] = (k[0] * cells[1] + k[1]) * cells[2] + k[2];
    }
    qsort(keys, c->count, sizeof *keys, cmp_u64);
    for (i = 0; i < c->count; ++i) n += i == 0 || keys[i] != keys[i - 1];
    free(keys);
    return n;
}

/* The count each kind of cloud aims at: 2000 occupied voxels for a compact one (a closed surface, as an object
 * scan), 3000 for one sparse away from its centre (rings on the ground about a sensor, as a LiDAR scan). The
 * suggestion is the finest rung within the count: the next finer rung holds more. */
static void test_compact_and_wide_counts(void) {
    scn_cloud ball, rings;
    const double golden = 2.399963229728653; /* radians: points spread evenly over the sphere */
    const double finer = pow(2.0, -1.0 / 8.0);
    double v;
    size_t i;
    scn_cloud_init(&ball);
    for (i = 0; i < 60000; ++i) {
        const double z = 1.0 - 2.0 * ((double)i + 0.5) / 60000.0, r = sqrt(1.0 - z * z);
        scn_cloud_push(&ball, 0.2 * r * cos(golden * (double)i), 0.2 * r * sin(golden * (double)i), 0.2 * z);
    }
    v = suggest(&ball, NULL);
    CHECK_MSG(occupied(&ball, v) <= 2000 && occupied(&ball, v * finer) > 2000, "ball: %zu voxels at %.17g, %zu finer",
              occupied(&ball, v), v, occupied(&ball, v * finer));
    scn_cloud_init(&rings);
    for (i = 0; i < 64; ++i) { /* rings 2 to 65 m out, 1,500 points each, on the ground and a wall at 40 m */
        const double radius = 2.0 + (double)i;
        size_t j;
        for (j = 0; j < 1500; ++j) {
            const double t = 6.283185307179586 * (double)j / 1500.0;
            scn_cloud_push(&rings, radius * cos(t), radius * sin(t), -1.7);
            if (i % 8 == 0) scn_cloud_push(&rings, 40.0 * cos(t), 40.0 * sin(t), -1.7 + 0.05 * (double)i);
        }
    }
    v = suggest(&rings, NULL);
    CHECK_MSG(occupied(&rings, v) <= 3000 && occupied(&rings, v * finer) > 3000,
              "rings: %zu voxels at %.17g, %zu finer", occupied(&rings, v), v, occupied(&rings, v * finer));
    scn_cloud_free(&ball);
    scn_cloud_free(&rings);
}

/* Order-free, frame-free to the grid's anchor, and exactly scaled with the clouds (the ladder's rungs double with
 * every octave): shuffled points, float32 points and a cloud scaled by 4 give the same rung. */
static void test_suggestion_invariance(void) {
    const double v = suggest(&g_pair.source, NULL);
    scn_cloud shuffled, scaled;
    size_t i;
    scn_cloud_init(&shuffled);
    scn_cloud_copy(&shuffled, &g_pair.source);
    scn_cloud_shuffle(&shuffled, 7);
    CHECK(suggest(&shuffled, NULL) == v);
    scn_cloud_init(&scaled);
    scn_cloud_copy(&scaled, &g_pair.source);
    for (i = 0; i < 3 * scaled.count; ++i) scaled.xyz[i] *= 4.0;
    CHECK_MSG(suggest(&scaled, NULL) == 4.0 * v, "%.17g vs 4 x %.17g", suggest(&scaled, NULL), v);
    scn_cloud_translate(&scaled, 1e3, -2e3, 5.0); /* a shifted frame: the grid is anchored at the cloud */
    CHECK(suggest(&scaled, NULL) == 4.0 * v);
    scn_cloud_free(&shuffled);
    scn_cloud_free(&scaled);
}

/* voxel_size 0 registers as the suggested voxel does, bit for bit (but voxel_size_used, the same too, and the
 * times), at 1 and 4 threads; the pose is right. */
static void test_register_auto(void) {
    const double v = suggest(&g_pair.source, &g_pair.target);
    kissm_result a1, a4, fixed;
    register_with(0.0, 1, &g_pair.source, &g_pair.target, &a1);
    register_with(0.0, 4, &g_pair.source, &g_pair.target, &a4);
    register_with(v, 2, &g_pair.source, &g_pair.target, &fixed);
    CHECK(a1.voxel_size_used == v && a4.voxel_size_used == v && fixed.voxel_size_used == v);
    CHECK(scn_result_equal(&a1, &a4));
    CHECK(scn_result_equal(&a1, &fixed));
    CHECK_MSG(a1.valid == 1, "reason %d", (int)a1.reason);
    CHECK(scn_rotation_error_deg(a1.rotation, g_pair.truth.R) < 2.0);
    CHECK(scn_translation_error(a1.translation, g_pair.truth.t) < 2.0 * v);
    CHECK(a1.time_voxelize_ms > 0.0);
}

/* Features: a matcher at voxel_size 0 describes a cloud alone at its own suggestion; features of one voxel
 * register (and match the points' registration at that voxel); features of two voxels are refused by name. */
static void test_features_auto(void) {
    kissm_config c = scn_config(0.0), cv;
    kissm_matcher *m = NULL, *mv = NULL;
    kissm_features *fs = NULL, *ft = NULL, *fs_own = NULL, *ft_own = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_result r, points;
    const double v = suggest(&g_pair.source, &g_pair.target);
    const double vs = suggest(&g_pair.source, NULL), vt = suggest(&g_pair.target, NULL);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    cv = scn_config(v);
    REQUIRE(kissm_create(&cv, &mv) == KISSM_OK);
    REQUIRE(kissm_features_compute(mv, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(mv, &t, &ft) == KISSM_OK);
    scn_result_poison(&r);
    CHECK_MSG(kissm_register_features(m, fs, ft, &r) == KISSM_OK, "%s", kissm_last_error_message());
    CHECK(r.voxel_size_used == v);
    register_with(v, 0, &g_pair.source, &g_pair.target, &points);
    CHECK(scn_result_equal(&r, &points));

    REQUIRE(kissm_features_compute(m, &s, &fs_own) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &t, &ft_own) == KISSM_OK);
    if (vs != vt) {
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register_features(m, fs_own, ft_own, &r), KISSM_ERR_FEATURES_MISMATCH);
        CHECK(strstr(kissm_last_error_message(), "voxel") != NULL);
        CHECK(scn_result_is_reset(&r));
    } else {
        fprintf(stderr, "  (the clouds' own suggestions agree: the mismatch case is not reached)\n");
    }
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_features_destroy(fs_own);
    kissm_features_destroy(ft_own);
    kissm_destroy(m);
    kissm_destroy(mv);
}

int main(void) {
    scn_make_pair(&g_pair, 1, 25.0, 0.01);
    RUN_TEST(test_suggestion_rule);
    RUN_TEST(test_suggestion_invariance);
    RUN_TEST(test_compact_and_wide_counts);
    RUN_TEST(test_register_auto);
    RUN_TEST(test_features_auto);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
