/* SPDX-License-Identifier: MIT */
/* Multiway alignment through the C API (kissm_align_features, kissm_sequence_loops): five scans of the yard, each
 * an independent sample cropped to its own half and seen from its own sensor pose, placed in scan 0's frame
 * within 2 degrees and 2 voxels of the truth by every pair policy; a scan without features not placed; the same
 * bits at 1 and 3 threads; the registrations as kissm_register_features writes them; bad input with exact
 * statuses and nothing written; the loop-candidate rule against cases worked out by hand. C99. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define SCANS 5
#define VOXEL 0.3
#define PI 3.14159265358979323846

static scn_pose g_world_from_scan[SCANS]; /* the truth */
static kissm_features *g_features[SCANS];
static kissm_matcher *g_matcher;

/* Scan k: the scene sampled anew, cropped to a half plane turning with k, seen from a sensor turned 70k degrees
 * about a tilted axis and moved by a few metres. */
static void make_scans(void) {
    const double axis[3] = {0.3, -0.2, 1.0};
    kissm_config config = scn_config(VOXEL);
    int k;
    config.refine_mode = KISSM_REFINE_GICP;
    REQUIRE(kissm_create(&config, &g_matcher) == KISSM_OK);
    for (k = 0; k < SCANS; ++k) {
        const double a = 0.6 * k, keep[3] = {cos(a), sin(a), 0.0};
        const double t[3] = {1.0 * k, -0.5 * k, 0.1 * k};
        scn_cloud cloud;
        scn_pose scan_from_world;
        kissm_points points;
        scn_cloud_init(&cloud);
        scn_make_scene(&cloud, 7, 100 + (uint64_t)k, 25.0, 0.01);
        scn_cloud_crop(&cloud, keep, 7.0);
        scn_pose_axis_angle(&g_world_from_scan[k], axis, (70.0 * k) * PI / 180.0, t);
        scn_pose_inverse(&g_world_from_scan[k], &scan_from_world);
        scn_cloud_apply(&cloud, &scan_from_world);
        points = scn_points(&cloud);
        REQUIRE(kissm_features_compute(g_matcher, &points, &g_features[k]) == KISSM_OK);
        scn_cloud_free(&cloud);
    }
}

/* Every placed scan within 2 degrees and 2 voxels of the truth, relative to scan 0; returns how many are placed. */
static int check_poses(const kissm_alignment *a, const int expect_placed[SCANS]) {
    double poses[SCANS * 16];
    uint8_t placed[SCANS];
    uint64_t components[SCANS];
    scn_pose zero_inverse, truth, got;
    int k, count = 0;
    if (kissm_alignment_poses(a, poses, placed, components) != KISSM_OK) {
        CHECK(!"kissm_alignment_poses failed");
        return -1;
    }
    scn_pose_inverse(&g_world_from_scan[0], &zero_inverse);
    for (k = 0; k < SCANS; ++k) {
        CHECK_EQ_INT(placed[k], expect_placed[k]);
        if (!placed[k]) {
            CHECK(isnan(poses[16 * k]) && isnan(poses[16 * k + 15]));
            continue;
        }
        ++count;
        CHECK_EQ_INT(components[k], 0);
        scn_pose_compose(&zero_inverse, &g_world_from_scan[k], &truth);
        scn_pose_from_matrix(poses + 16 * k, &got);
        CHECK_MSG(scn_rotation_error_deg(got.R, truth.R) < 2.0, "scan %d: %.3f deg", k,
                  scn_rotation_error_deg(got.R, truth.R));
        CHECK_MSG(scn_translation_error(got.t, truth.t) < 2.0 * VOXEL, "scan %d: %.3f m", k,
                  scn_translation_error(got.t, truth.t));
    }
    return count;
}

static kissm_align_options options(int32_t pairs) {
    kissm_align_options o;
    CHECK_EQ_INT(kissm_align_options_init(&o, sizeof o), KISSM_OK);
    o.pairs = pairs;
    return o;
}

static void test_defaults(void) {
    kissm_align_options o;
    memset(&o, 0x5A, sizeof o);
    CHECK_EQ_INT(kissm_align_options_init(&o, sizeof o), KISSM_OK);
    CHECK_EQ_INT(o.struct_size, sizeof o);
    CHECK_EQ_INT(o.pairs, KISSM_PAIRS_ALL);
    CHECK(o.pair_list == NULL && o.num_pairs == 0 && o.priors == NULL);
    CHECK(o.loop_radius == 0.0);
    CHECK_EQ_INT(o.loop_gap, 10);
    CHECK_EQ_INT(o.loops_per_scan, 5);
    CHECK(o.bound == KISSM_POSE_GRAPH_DEFAULT_BOUND);
    CHECK(o.sessions == NULL);
    CHECK_EQ_INT(o.stride, 10);
    CHECK_EQ_INT(o.reserved, 0);
    CHECK_EQ_INT(o.similar_per_scan, 3);
    CHECK_EQ_INT(o.reserved2, 0);
    CHECK_EQ_INT(kissm_abi_sizeof(KISSM_STRUCT_ALIGN_OPTIONS), sizeof o);
    CHECK_EQ_INT(kissm_align_options_init(&o, sizeof o - 8), KISSM_ERR_STRUCT_SIZE);
    CHECK_EQ_INT(kissm_align_options_init(NULL, sizeof o), KISSM_ERR_NULL_ARGUMENT);
}

static void test_all_pairs(void) {
    const int all[SCANS] = {1, 1, 1, 1, 1};
    kissm_alignment *a = NULL;
    uint64_t k, accepted = 0;
    CHECK_EQ_INT(kissm_align_features(g_matcher, (const kissm_features *const *)g_features, SCANS, NULL, &a), KISSM_OK);
    REQUIRE(a != NULL);
    CHECK_EQ_INT(kissm_alignment_num_scans(a), SCANS);
    CHECK_EQ_INT(kissm_alignment_num_registrations(a), SCANS * (SCANS - 1) / 2);
    CHECK_EQ_INT(check_poses(a, all), SCANS);
    /* Registration order: (j, i) for i < j, i outer; each the bits of kissm_register_features. */
    for (k = 0; k < kissm_alignment_num_registrations(a); ++k) {
        uint64_t source = 99, target = 99;
        int32_t edge = 7;
        double information[36], residual = 0.0;
        kissm_result got, direct;
        kissm_result_init(&got, sizeof got);
        kissm_result_init(&direct, sizeof direct);
        REQUIRE(kissm_alignment_registration(a, k, &source, &target, &got, &edge, information, &residual) == KISSM_OK);
        CHECK(source > target);
        REQUIRE(kissm_register_features(g_matcher, g_features[source], g_features[target], &direct) == KISSM_OK);
        CHECK(scn_result_equal(&got, &direct));
        if (got.valid) {
            CHECK(edge == 0 || edge == 1);
            CHECK(memcmp(information, got.information, sizeof information) == 0); /* refined: its own */
            CHECK(isfinite(residual));
            accepted += edge == 1;
        } else {
            CHECK_EQ_INT(edge, -1);
            CHECK(isnan(information[0]) && isnan(residual));
        }
    }
    CHECK(accepted >= SCANS - 1);
    kissm_alignment_destroy(a);
}

static void test_sequence_and_list(void) {
    const int all[SCANS] = {1, 1, 1, 1, 1};
    const uint64_t list[] = {1, 0, 2, 1, 3, 2, 4, 3, 4, 0};
    kissm_align_options o = options(KISSM_PAIRS_SEQUENCE);
    kissm_alignment *a = NULL;
    uint64_t source, target;
    o.loop_gap = 3;
    o.loops_per_scan = 2;
    o.loop_radius = 50.0;
    REQUIRE(kissm_align_features(g_matcher, (const kissm_features *const *)g_features, SCANS, &o, &a) == KISSM_OK);
    /* Round 1: (1,0) (2,1) (3,2) (4,3); round 2 with every scan within 50 m: (3,0), then (4,0) (4,1). */
    CHECK_EQ_INT(kissm_alignment_num_registrations(a), 7);
    REQUIRE(kissm_alignment_registration(a, 4, &source, &target, NULL, NULL, NULL, NULL) == KISSM_OK);
    CHECK(source == 3 && target == 0);
    REQUIRE(kissm_alignment_registration(a, 6, &source, &target, NULL, NULL, NULL, NULL) == KISSM_OK);
    CHECK(source == 4 && target == 1);
    CHECK_EQ_INT(check_poses(a, all), SCANS);
    kissm_alignment_destroy(a);

    o = options(KISSM_PAIRS_LIST);
    o.pair_list = list;
    o.num_pairs = 5;
    REQUIRE(kissm_align_features(g_matcher, (const kissm_features *const *)g_features, SCANS, &o, &a) == KISSM_OK);
    CHECK_EQ_INT(kissm_alignment_num_registrations(a), 5);
    REQUIRE(kissm_alignment_registration(a, 4, &source, &target, NULL, NULL, NULL, NULL) == KISSM_OK);
    CHECK(source == 4 && target == 0);
    CHECK_EQ_INT(check_poses(a, all), SCANS);
    kissm_alignment_destroy(a);
}

/* Two sessions, scans 0-2 and 3-4: each session's consecutive pairs trusted, the grid across (stride 2: 3 and
 * every other scan of session 0 ... here 3-0 and 3-2), then the merged poses' nearest: everything placed. */
static void test_sessions(void) {
    const int all[SCANS] = {1, 1, 1, 1, 1};
    const uint32_t sessions[SCANS] = {0, 0, 0, 1, 1};
    kissm_align_options o = options(KISSM_PAIRS_SESSIONS);
    kissm_alignment *a = NULL;
    uint64_t k, source, target;
    int32_t edge;
    kissm_result r;
    o.sessions = sessions;
    o.stride = 2;
    o.loop_radius = 50.0;
    o.loops_per_scan = 1;
    REQUIRE(kissm_align_features(g_matcher, (const kissm_features *const *)g_features, SCANS, &o, &a) == KISSM_OK);
    CHECK_EQ_INT(check_poses(a, all), SCANS);
    /* Odometry (1,0) (2,1) (4,3); the grid (3,0) (3,2); then each placed scan of session 1 with its nearest placed
     * scan of session 0 not yet paired with it. */
    REQUIRE(kissm_alignment_num_registrations(a) >= 5);
    for (k = 0; k < kissm_alignment_num_registrations(a); ++k) {
        kissm_result_init(&r, sizeof r);
        REQUIRE(kissm_alignment_registration(a, k, &source, &target, &r, &edge, NULL, NULL) == KISSM_OK);
        if (k < 3) {
            CHECK(source == target + 1 && sessions[source] == sessions[target]);
            CHECK(!r.valid || edge == 1); /* trusted: a valid odometry step is always an accepted edge */
        } else if (k < 5) {
            CHECK(source == 3 && target == (k == 3 ? 0 : 2));
        } else {
            CHECK(sessions[source] == 1 && sessions[target] == 0);
        }
    }
    kissm_alignment_destroy(a);
}

static void test_missing_features(void) {
    const int expect[SCANS] = {1, 1, 0, 1, 1};
    const kissm_features *some[SCANS];
    kissm_alignment *a = NULL;
    int k;
    for (k = 0; k < SCANS; ++k) some[k] = k == 2 ? NULL : g_features[k];
    REQUIRE(kissm_align_features(g_matcher, some, SCANS, NULL, &a) == KISSM_OK);
    CHECK_EQ_INT(kissm_alignment_num_registrations(a), 6); /* the pairs of four scans */
    CHECK_EQ_INT(check_poses(a, expect), SCANS - 1);
    kissm_alignment_destroy(a);
}

/* The same bits at 1 and 3 threads: poses, and every registration but its times. */
static void test_thread_independence(void) {
    kissm_align_options o = options(KISSM_PAIRS_SEQUENCE);
    kissm_alignment *a[2] = {NULL, NULL};
    double poses[2][SCANS * 16];
    int run;
    uint64_t k;
    o.loop_gap = 2;
    o.loop_radius = 50.0;
    for (run = 0; run < 2; ++run) {
        kissm_config config = scn_config(VOXEL);
        kissm_matcher *m = NULL;
        config.refine_mode = KISSM_REFINE_GICP;
        config.num_threads = run == 0 ? 1 : 3;
        REQUIRE(kissm_create(&config, &m) == KISSM_OK);
        REQUIRE(kissm_align_features(m, (const kissm_features *const *)g_features, SCANS, &o, &a[run]) == KISSM_OK);
        REQUIRE(kissm_alignment_poses(a[run], poses[run], NULL, NULL) == KISSM_OK);
        kissm_destroy(m);
    }
    CHECK(memcmp(poses[0], poses[1], sizeof poses[0]) == 0);
    REQUIRE(kissm_alignment_num_registrations(a[0]) == kissm_alignment_num_registrations(a[1]));
    for (k = 0; k < kissm_alignment_num_registrations(a[0]); ++k) {
        kissm_result r[2];
        double residual[2];
        for (run = 0; run < 2; ++run) {
            kissm_result_init(&r[run], sizeof r[run]);
            REQUIRE(kissm_alignment_registration(a[run], k, NULL, NULL, &r[run], NULL, NULL, &residual[run]) ==
                    KISSM_OK);
        }
        CHECK(scn_result_equal(&r[0], &r[1]));
        CHECK(memcmp(&residual[0], &residual[1], sizeof(double)) == 0);
    }
    kissm_alignment_destroy(a[0]);
    kissm_alignment_destroy(a[1]);
}

/* kissm_align_features refuses the options with KISSM_ERR_INVALID_ARGUMENT and a message containing `about`. */
static void expect_refused(const kissm_features *const *f, const kissm_align_options *o, kissm_alignment **a,
                           const char *about) {
    CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, o, a), KISSM_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(kissm_last_error_message(), about) != NULL, "expected '%s', got '%s'", about,
              kissm_last_error_message());
}

static void test_bad_input(void) {
    const kissm_features *const *f = (const kissm_features *const *)g_features;
    const uint64_t self_pair[] = {1, 1}, far_pair[] = {5, 0};
    kissm_alignment *sentinel = (kissm_alignment *)&sentinel, *a = sentinel;
    kissm_align_options o = options(KISSM_PAIRS_ALL);
    kissm_matcher *other = NULL;
    kissm_config config = scn_config(2 * VOXEL);
    kissm_result r;

    CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, NULL, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_align_features(NULL, f, SCANS, NULL, &a), KISSM_ERR_NULL_ARGUMENT);
    CHECK(a == NULL);
    a = sentinel;
    CHECK_EQ_INT(kissm_align_features(g_matcher, NULL, SCANS, NULL, &a), KISSM_ERR_NULL_ARGUMENT);
    CHECK(a == NULL);
    CHECK_EQ_INT(kissm_align_features(g_matcher, f, 0, NULL, &a), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "num_scans") != NULL);

    o.pairs = -1;
    expect_refused(f, &o, &a, "options->pairs");
    o = options(KISSM_PAIRS_LIST);
    o.num_pairs = 1;
    CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, &o, &a), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "options->pair_list") != NULL);
    o.pair_list = self_pair;
    expect_refused(f, &o, &a, "itself");
    o.pair_list = far_pair;
    expect_refused(f, &o, &a, "options->pair_list pair 0");
    o = options(KISSM_PAIRS_ALL);
    o.num_pairs = 1;
    CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, &o, &a), KISSM_ERR_INVALID_ARGUMENT);
    o = options(KISSM_PAIRS_ALL);
    o.priors = (const double *)self_pair;
    expect_refused(f, &o, &a, "options->priors");
    o = options(KISSM_PAIRS_SEQUENCE);
    o.loop_radius = -1.0;
    expect_refused(f, &o, &a, "options->loop_radius");
    o.loop_radius = NAN;
    CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, &o, &a), KISSM_ERR_INVALID_ARGUMENT);
    o = options(KISSM_PAIRS_SEQUENCE);
    o.loop_gap = 0;
    expect_refused(f, &o, &a, "options->loop_gap");
    o = options(KISSM_PAIRS_SEQUENCE);
    o.loops_per_scan = -1;
    expect_refused(f, &o, &a, "options->loops_per_scan");
    o = options(KISSM_PAIRS_ALL);
    o.bound = 0.0;
    expect_refused(f, &o, &a, "options->bound");
    o = options(KISSM_PAIRS_ALL);
    o.struct_size = 12;
    CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, &o, &a), KISSM_ERR_STRUCT_SIZE);
    CHECK(a == NULL);

    {
        const uint32_t unordered[SCANS] = {0, 1, 0, 1, 1}, late_start[SCANS] = {1, 1, 1, 1, 1};
        o = options(KISSM_PAIRS_SESSIONS);
        CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, &o, &a), KISSM_ERR_NULL_ARGUMENT);
        CHECK(strstr(kissm_last_error_message(), "options->sessions") != NULL);
        o.sessions = unordered;
        expect_refused(f, &o, &a, "options->sessions[2] is 0; 1 or 2");
        o.sessions = late_start;
        expect_refused(f, &o, &a, "options->sessions[0] is 1");
        o = options(KISSM_PAIRS_SEQUENCE);
        o.sessions = unordered;
        expect_refused(f, &o, &a, "options->sessions is read by KISSM_PAIRS_SESSIONS only");
        o = options(KISSM_PAIRS_ALL);
        o.stride = 0;
        expect_refused(f, &o, &a, "options->stride");
        o = options(KISSM_PAIRS_ALL);
        o.reserved = 1;
        expect_refused(f, &o, &a, "options->reserved");
        o = options(KISSM_PAIRS_SEQUENCE);
        o.similar_per_scan = -1;
        expect_refused(f, &o, &a, "options->similar_per_scan is -1");
        o.similar_per_scan = 1000001;
        expect_refused(f, &o, &a, "options->similar_per_scan");
        o = options(KISSM_PAIRS_SEQUENCE);
        o.reserved2 = 7;
        expect_refused(f, &o, &a, "options->reserved2");
        CHECK(a == NULL);
        o = options(4);
        CHECK_EQ_INT(kissm_align_features(g_matcher, f, SCANS, &o, &a), KISSM_ERR_INVALID_ARGUMENT);
        CHECK(a == NULL);
    }

    /* Features of another voxel size: refused before any registration. */
    REQUIRE(kissm_create(&config, &other) == KISSM_OK);
    CHECK_EQ_INT(kissm_align_features(other, f, SCANS, NULL, &a), KISSM_ERR_FEATURES_MISMATCH);
    CHECK(strstr(kissm_last_error_message(), "features[0]") != NULL);
    kissm_destroy(other);

    /* The outcome's accessors. */
    REQUIRE(kissm_align_features(g_matcher, f, 2, NULL, &a) == KISSM_OK);
    CHECK_EQ_INT(kissm_alignment_poses(NULL, NULL, NULL, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_alignment_registration(a, 1, NULL, NULL, NULL, NULL, NULL, NULL), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "index") != NULL);
    memset(&r, 0, sizeof r);
    r.struct_size = 8;
    CHECK_EQ_INT(kissm_alignment_registration(a, 0, NULL, NULL, &r, NULL, NULL, NULL), KISSM_ERR_STRUCT_SIZE);
    CHECK_EQ_INT(kissm_alignment_registration(NULL, 0, NULL, NULL, NULL, NULL, NULL, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_alignment_num_scans(NULL), 0);
    CHECK_EQ_INT(kissm_alignment_num_registrations(NULL), 0);
    kissm_alignment_destroy(a);
    kissm_alignment_destroy(NULL);
}

/* A step of d metres along x, as a row-major transform. */
static void step_x(double d, double m[16]) {
    memset(m, 0, 16 * sizeof(double));
    m[0] = m[5] = m[10] = m[15] = 1.0;
    m[3] = d;
}

static void test_sequence_loops(void) {
    /* Eight scans: out along x 1 m a step to x = 4, then back (4 -> 1 at x = 3, 2, 1, 0). Scan positions
     * 0 1 2 3 4 3 2 1; with gap 3 and radius 0.5 (+2% of the path between), scan 5 (x 3) meets 2? no: 1 m apart;
     * it meets scan 3 (0 m), but 5 - 3 < 3; scan 6 (x 2) meets 2 (gap 4), scan 7 (x 1) meets 1 (gap 6). */
    double steps[7 * 16], priors[8 * 16];
    uint8_t valid[7] = {1, 1, 1, 1, 1, 1, 1};
    uint64_t pairs[32], count = 99;
    int k;
    for (k = 0; k < 7; ++k) step_x(k < 4 ? 1.0 : -1.0, steps + 16 * k);
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.5, 3, 5, pairs, 16, &count), KISSM_OK);
    CHECK_EQ_INT(count, 2);
    CHECK(pairs[0] == 6 && pairs[1] == 2 && pairs[2] == 7 && pairs[3] == 1);
    /* Counting only. */
    count = 99;
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, valid, NULL, 0.5, 3, 5, NULL, 0, &count), KISSM_OK);
    CHECK_EQ_INT(count, 2);
    /* A broken step 4 (4 -> 5) starts a new piece: scans 5 to 7 get no candidates among 0 to 4. */
    valid[4] = 0;
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, valid, NULL, 0.5, 3, 5, pairs, 16, &count), KISSM_OK);
    CHECK_EQ_INT(count, 0);
    valid[4] = 1;
    /* The drift: a radius of 0.95 grows by 2% of the path between the scans (scan 7 to 0: 7 m, +0.14 m). Scan 5
     * (x 3) meets 2 (1 m, allowed 1.01); 6 (x 2) meets 1 (1.05), 2 and 3 (1.01); 7 (x 1) meets 0 (1.09), 1, 2. */
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.95, 3, 5, pairs, 16, &count), KISSM_OK);
    CHECK_EQ_INT(count, 7);
    CHECK(pairs[0] == 5 && pairs[1] == 2 && pairs[2] == 6 && pairs[3] == 1 && pairs[4] == 6 && pairs[5] == 2);
    CHECK(pairs[6] == 6 && pairs[7] == 3 && pairs[8] == 7 && pairs[9] == 0 && pairs[10] == 7 && pairs[11] == 1);
    CHECK(pairs[12] == 7 && pairs[13] == 2);
    /* per_scan 1 keeps the nearest. */
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.95, 3, 1, pairs, 16, &count), KISSM_OK);
    CHECK_EQ_INT(count, 3);
    CHECK(pairs[0] == 5 && pairs[1] == 2 && pairs[2] == 6 && pairs[3] == 2 && pairs[4] == 7 && pairs[5] == 1);
    /* Priors: the same positions, no drift; a scan without one (NaN translation) gets and gives none. */
    for (k = 0; k < 8; ++k) step_x(k <= 4 ? k : 8 - k, priors + 16 * k);
    CHECK_EQ_INT(kissm_sequence_loops(8, NULL, NULL, priors, 0.95, 3, 5, pairs, 16, &count), KISSM_OK);
    CHECK_EQ_INT(count, 2);
    priors[16 * 1 + 3] = NAN;
    CHECK_EQ_INT(kissm_sequence_loops(8, NULL, NULL, priors, 0.5, 3, 5, pairs, 16, &count), KISSM_OK);
    CHECK_EQ_INT(count, 1);
    CHECK(pairs[0] == 6 && pairs[1] == 2);

    /* Bad input. */
    count = 99;
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.5, 3, 5, pairs, 1, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "capacity") != NULL);
    CHECK_EQ_INT(count, 2);
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.5, 3, 5, pairs, 16, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_loops(8, NULL, NULL, NULL, 0.5, 3, 5, pairs, 16, &count), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, priors, 0.5, 3, 5, pairs, 16, &count),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_loops(8, NULL, valid, priors, 0.5, 3, 5, pairs, 16, &count),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_loops(0, steps, NULL, NULL, 0.5, 3, 5, pairs, 16, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.0, 3, 5, pairs, 16, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "radius") != NULL);
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, INFINITY, 3, 5, pairs, 16, &count),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.5, 0, 5, pairs, 16, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "gap") != NULL);
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, NULL, NULL, 0.5, 3, 2000000, pairs, 16, &count),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "per_scan") != NULL);
    valid[3] = 2;
    CHECK_EQ_INT(kissm_sequence_loops(8, steps, valid, NULL, 0.5, 3, 5, pairs, 16, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "step_valid[3]") != NULL);
}

static void test_sequence_similar(void) {
    /* Six scans, signatures that differ in their first two numbers: (0,0) (1,0) (0,1) (1,0) (none) (0.1,0). */
    double signatures[6 * KISSM_SIGNATURE_SIZE];
    const double first[6][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 0}, {NAN, NAN}, {0.1, 0}};
    uint8_t apart[5] = {0, 0, 0, 0, 0}, broken[5] = {1, 1, 0, 1, 1}, whole[5] = {1, 1, 1, 1, 1};
    uint64_t pairs[40], count = 99;
    int k;
    memset(signatures, 0, sizeof signatures);
    for (k = 0; k < 6; ++k) {
        signatures[KISSM_SIGNATURE_SIZE * k] = first[k][0];
        signatures[KISSM_SIGNATURE_SIZE * k + 1] = first[k][1];
    }
    /* Every step broken: each scan its own piece. The nearest at least 2 back; scan 4 has no signature, scan 5's
     * nearest is 0 (0.01 away). */
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, signatures, 2, 1, pairs, 20, &count), KISSM_OK);
    CHECK_EQ_INT(count, 3);
    CHECK(pairs[0] == 2 && pairs[1] == 0 && pairs[2] == 3 && pairs[3] == 1 && pairs[4] == 5 && pairs[5] == 0);
    /* Two per scan: 3 takes 1 (0 away) and 0; 5 takes 0, then 1 over 3 (both 0.81 away: the lower). */
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, signatures, 2, 2, pairs, 20, &count), KISSM_OK);
    CHECK_EQ_INT(count, 5);
    CHECK(pairs[2] == 3 && pairs[3] == 0 && pairs[4] == 3 && pairs[5] == 1 && pairs[8] == 5 && pairs[9] == 1);
    /* Pieces 0-2 and 3-5: only pairs across. */
    CHECK_EQ_INT(kissm_sequence_similar(6, broken, signatures, 2, 1, pairs, 20, &count), KISSM_OK);
    CHECK_EQ_INT(count, 2);
    CHECK(pairs[0] == 3 && pairs[1] == 1 && pairs[2] == 5 && pairs[3] == 0);
    /* One piece (NULL or every step valid): none. Counting only. */
    CHECK_EQ_INT(kissm_sequence_similar(6, NULL, signatures, 1, 5, NULL, 0, &count), KISSM_OK);
    CHECK_EQ_INT(count, 0);
    CHECK_EQ_INT(kissm_sequence_similar(6, whole, signatures, 1, 5, NULL, 0, &count), KISSM_OK);
    CHECK_EQ_INT(count, 0);
    CHECK_EQ_INT(kissm_sequence_similar(1, NULL, signatures, 1, 5, pairs, 20, &count), KISSM_OK);
    CHECK_EQ_INT(count, 0);

    /* Bad input: exact codes, the argument named, nothing written but the count for a small capacity. */
    pairs[0] = 77;
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, signatures, 2, 1, pairs, 2, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "capacity") != NULL);
    CHECK_EQ_INT(count, 3);
    CHECK(pairs[0] == 77);
    count = 99;
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, NULL, 2, 1, pairs, 20, &count), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "signatures") != NULL);
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, signatures, 2, 1, pairs, 20, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_similar(0, apart, signatures, 2, 1, pairs, 20, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "num_scans") != NULL);
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, signatures, 0, 1, pairs, 20, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "gap") != NULL);
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, signatures, 2, 2000000, pairs, 20, &count),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "per_scan") != NULL);
    apart[2] = 2;
    CHECK_EQ_INT(kissm_sequence_similar(6, apart, signatures, 2, 1, pairs, 20, &count), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "step_valid[2]") != NULL);
    CHECK_EQ_INT(count, 99);
}

/* T_i_j for scans at x positions within their pieces, the later piece's frame `offset` metres along y in the
 * earlier one's. */
static void piece_link(const double *x, int i, int j, double offset, double out[16]) {
    step_x(x[j] - x[i], out);
    out[7] = offset;
}

static void test_sequence_corroborated(void) {
    /* Ten scans along x, 1 m a step, the chain broken after scans 3 and 7: pieces 0-3, 4-7, 8-9. */
    const double x[10] = {0, 1, 2, 3, 0, 1, 2, 3, 0, 1};
    double steps[9 * 16], transforms[7 * 16];
    uint8_t valid[9] = {1, 1, 1, 0, 1, 1, 1, 0, 1}, kept[7];
    /* Three registrations put piece 4-7 50 m along y (right), two agree on 500 m (wrong), one joins piece 8-9
     * alone, one lies within piece 0-3. */
    const uint64_t pairs[14] = {4, 0, 5, 1, 6, 2, 7, 3, 5, 0, 8, 1, 2, 0};
    const double offsets[7] = {50, 50, 50, 500, 500, 50, 0};
    int k;
    for (k = 0; k < 9; ++k) step_x(1.0, steps + 16 * k);
    for (k = 0; k < 7; ++k) piece_link(x, (int)pairs[2 * k + 1], (int)pairs[2 * k], offsets[k], transforms + 16 * k);
    memset(kept, 9, sizeof kept);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 7, pairs, transforms, kept), KISSM_OK);
    CHECK(kept[0] == 1 && kept[1] == 1 && kept[2] == 1 && kept[3] == 0 && kept[4] == 0 && kept[5] == 0);
    CHECK(kept[6] == 1);
    /* Two registrations of one later scan do not corroborate each other. */
    {
        const uint64_t same[4] = {4, 0, 4, 1};
        double two[32];
        piece_link(x, 0, 4, 50, two);
        piece_link(x, 1, 4, 50, two + 16);
        CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 2, same, two, kept), KISSM_OK);
        CHECK(kept[0] == 0 && kept[1] == 0);
    }
    /* A registration holding NaN agrees with none; nothing to judge is fine. */
    transforms[16 * 1 + 3] = NAN;
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 7, pairs, transforms, kept), KISSM_OK);
    CHECK(kept[0] == 1 && kept[1] == 0 && kept[2] == 1);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 0, NULL, NULL, NULL), KISSM_OK);
    CHECK_EQ_INT(kissm_sequence_corroborated(1, NULL, NULL, 1.0, 0, NULL, NULL, NULL), KISSM_OK);

    /* Bad input: nothing written. */
    memset(kept, 9, sizeof kept);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, NULL, valid, 1.0, 7, pairs, transforms, kept),
                 KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "steps") != NULL);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 7, NULL, transforms, kept),
                 KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "pairs") != NULL);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 7, pairs, NULL, kept), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "transforms") != NULL);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 7, pairs, transforms, NULL),
                 KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "out_kept") != NULL);
    CHECK_EQ_INT(kissm_sequence_corroborated(0, steps, valid, 1.0, 7, pairs, transforms, kept),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_corroborated(1, NULL, valid, 1.0, 0, NULL, NULL, NULL), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "step_valid") != NULL);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 0.0, 7, pairs, transforms, kept),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "radius") != NULL);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, NAN, 7, pairs, transforms, kept),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 100000001, pairs, transforms, kept),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "num_pairs") != NULL);
    {
        const uint64_t outside[4] = {4, 0, 10, 1};
        CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 2, outside, transforms, kept),
                     KISSM_ERR_INVALID_ARGUMENT);
        CHECK(strstr(kissm_last_error_message(), "pairs[1] is (10, 1)") != NULL);
    }
    valid[5] = 3;
    CHECK_EQ_INT(kissm_sequence_corroborated(10, steps, valid, 1.0, 7, pairs, transforms, kept),
                 KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "step_valid[5]") != NULL);
    for (k = 0; k < 7; ++k) CHECK_EQ_INT(kept[k], 9);
}

int main(void) {
    int k;
    RUN_TEST(test_defaults);
    RUN_TEST(test_sequence_loops);
    RUN_TEST(test_sequence_similar);
    RUN_TEST(test_sequence_corroborated);
    make_scans();
    RUN_TEST(test_all_pairs);
    RUN_TEST(test_sequence_and_list);
    RUN_TEST(test_sessions);
    RUN_TEST(test_missing_features);
    RUN_TEST(test_thread_independence);
    RUN_TEST(test_bad_input);
    for (k = 0; k < SCANS; ++k) kissm_features_destroy(g_features[k]);
    kissm_destroy(g_matcher);
    return TEST_SUMMARY();
}
