/* SPDX-License-Identifier: MIT */
/* Features computed once and matched against many: equal to kissm_register, mismatch detection, lifetime
 * independent of the matcher, and sharing between threads (pthreads). C99. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.5
#define NUM_TARGETS 3

static scn_pair g_pair;
/* More targets: the same layout scanned again (independent samples, other crops), each with its truth. */
static scn_cloud g_targets[NUM_TARGETS];
static scn_pose g_truths[NUM_TARGETS];

/* Registration results compare equal except the time fields and, for kissm_register_features, the
 * voxelisation and feature times, which are 0 by contract. */
static void check_feature_times(const kissm_result *r) {
    double sum;
    CHECK(r->time_voxelize_ms == 0.0);
    CHECK(r->time_features_ms == 0.0);
    CHECK(r->time_matching_ms >= 0.0 && r->time_pruning_ms >= 0.0 && r->time_solver_ms >= 0.0 &&
          r->time_refine_ms >= 0.0); /* refinement: a coarse pose confirmed by it (validity.hpp) */
    sum = r->time_voxelize_ms + r->time_features_ms + r->time_matching_ms + r->time_pruning_ms + r->time_solver_ms +
          r->time_refine_ms;
    CHECK(fabs(r->time_total_ms - sum) <= 1e-9 * (sum > 1.0 ? sum : 1.0));
}

static void test_equal_to_register(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_features *fs = NULL, *ft = NULL;
    kissm_result direct, via;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
    REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
    REQUIRE(fs != NULL && ft != NULL && fs != ft);

    scn_result_poison(&direct);
    CHECK_EQ_INT(kissm_register(m, &s, &t, &direct), KISSM_OK);
    scn_result_poison(&via);
    CHECK_EQ_INT(kissm_register_features(m, fs, ft, &via), KISSM_OK);
    CHECK(scn_result_poison_left(&via) == 0);
    CHECK_EQ_INT(direct.valid, 1);
    CHECK(scn_rotation_error_deg(direct.rotation, g_pair.truth.R) < 2.0);
    CHECK_MSG(scn_result_equal(&direct, &via), "register_features differs from register");
    if (!scn_result_equal(&direct, &via)) {
        scn_result_print("register", &direct);
        scn_result_print("register_features", &via);
    }
    check_feature_times(&via);

    /* counts of the features objects equal the result's */
    CHECK_EQ_INT(kissm_features_num_points(fs), direct.num_source_points);
    CHECK_EQ_INT(kissm_features_num_points(ft), direct.num_target_points);
    CHECK_EQ_INT(kissm_features_num_voxels(fs), direct.num_source_voxels);
    CHECK_EQ_INT(kissm_features_num_voxels(ft), direct.num_target_voxels);
    CHECK_EQ_INT(kissm_features_num_keypoints(fs), direct.num_source_keypoints);
    CHECK_EQ_INT(kissm_features_num_keypoints(ft), direct.num_target_keypoints);
    CHECK(kissm_features_num_keypoints(fs) > 100);
    /* memory: at least the descriptors twice (rows and the index's copy by slot) and the voxels */
    CHECK(kissm_features_memory_bytes(fs) > kissm_features_num_keypoints(fs) * 2 * 33 * sizeof(float) +
                                                kissm_features_num_voxels(fs) * 3 * sizeof(float));
    CHECK(kissm_features_memory_bytes(fs) < kissm_features_num_voxels(fs) * 1024);

    /* swapped features equal the swapped registration */
    scn_result_poison(&direct);
    scn_result_poison(&via);
    CHECK_EQ_INT(kissm_register(m, &t, &s, &direct), KISSM_OK);
    CHECK_EQ_INT(kissm_register_features(m, ft, fs, &via), KISSM_OK);
    CHECK(scn_result_equal(&direct, &via));

    /* a cloud against itself */
    CHECK_EQ_INT(kissm_register(m, &s, &s, &direct), KISSM_OK);
    CHECK_EQ_INT(kissm_register_features(m, fs, fs, &via), KISSM_OK);
    CHECK(scn_result_equal(&direct, &via));
    CHECK_EQ_INT(via.valid, 1);
    {
        const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zero[3] = {0, 0, 0};
        CHECK(scn_rotation_error_deg(via.rotation, I) < 0.5);
        CHECK(scn_translation_error(via.translation, zero) < 0.5 * VOXEL);
    }

    /* the same features registered twice: identical */
    {
        kissm_result again;
        scn_result_poison(&again);
        CHECK_EQ_INT(kissm_register_features(m, fs, fs, &again), KISSM_OK);
        CHECK(scn_result_equal(&via, &again));
    }

    /* Features of float32 input equal kissm_register of the same float32 input. */
    {
        float *s32 = scn_cloud_to_float(&g_pair.source);
        kissm_points p32 = scn_points_f32(s32, g_pair.source.count);
        kissm_features *f32 = NULL;
        REQUIRE(kissm_features_compute(m, &p32, &f32) == KISSM_OK);
        CHECK_EQ_INT(kissm_register(m, &p32, &t, &direct), KISSM_OK);
        CHECK_EQ_INT(kissm_register_features(m, f32, ft, &via), KISSM_OK);
        CHECK(scn_result_equal(&direct, &via));
        kissm_features_destroy(f32);
        free(s32);
    }
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_destroy(m);
}

/* DROP features count the dropped points and equal the registration. */
static void test_nonfinite_features(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    scn_cloud cloud;
    kissm_points s, t = scn_points(&g_pair.target);
    kissm_features *fs = NULL, *ft = NULL;
    kissm_result direct, via;
    scn_cloud_init(&cloud);
    scn_cloud_copy(&cloud, &g_pair.source);
    cloud.xyz[0] = NAN;
    cloud.xyz[3 * 100 + 2] = INFINITY;
    s = scn_points(&cloud);
    c.nonfinite_policy = KISSM_NONFINITE_DROP;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
    CHECK_EQ_INT(kissm_features_num_points(fs), cloud.count);
    scn_result_poison(&direct);
    scn_result_poison(&via);
    CHECK_EQ_INT(kissm_register(m, &s, &t, &direct), KISSM_OK);
    CHECK_EQ_INT(kissm_register_features(m, fs, ft, &via), KISSM_OK);
    CHECK_EQ_INT(via.num_source_nonfinite, 2);
    CHECK_EQ_INT(via.num_source_points, cloud.count);
    CHECK(scn_result_equal(&direct, &via));
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_destroy(m);
    scn_cloud_free(&cloud);
}

/* A matcher whose descriptor settings differ refuses the features; one whose matching/solver settings
 * differ accepts them (and equals its own kissm_register). */
static void test_mismatch(void) {
    kissm_config c = scn_config(VOXEL);
    c.viewpoint_mode = KISSM_VIEWPOINT_FIXED; /* so that the viewpoint itself matters (case 6) */
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_features *fs = NULL, *ft = NULL;
    int i;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
    kissm_destroy(m);

    for (i = 0; i < 8; ++i) {
        kissm_config d = c;
        kissm_matcher *other = NULL;
        kissm_result r;
        const char *what = "";
        switch (i) {
        case 0:
            d.voxel_size = 0.6;
            what = "voxel_size";
            break;
        case 1:
            d.voxel_size = 0.45;
            what = "voxel_size (smaller)";
            break;
        case 2:
            d.normal_radius_gain = 3.0;
            what = "normal_radius_gain";
            break;
        case 3:
            d.fpfh_radius_gain = 6.0;
            what = "fpfh_radius_gain";
            break;
        case 4:
            d.max_linearity = 0.9;
            what = "max_linearity";
            break;
        case 5:
            d.min_normal_neighbors = 5;
            what = "min_normal_neighbors";
            break;
        case 6:
            d.viewpoint[2] = 1.0;
            what = "viewpoint (fixed mode)";
            break;
        case 7:
            d.viewpoint_mode = KISSM_VIEWPOINT_CLOUD_CENTER;
            what = "viewpoint_mode";
            break;
        default: break;
        }
        REQUIRE(kissm_create(&d, &other) == KISSM_OK);
        scn_result_poison(&r);
        CHECK_MSG(kissm_register_features(other, fs, ft, &r) == KISSM_ERR_FEATURES_MISMATCH, "%s", what);
        CHECK(scn_result_is_reset(&r));
        CHECK(strlen(kissm_last_error_message()) > 0);
        /* one side mismatching is enough */
        {
            kissm_features *own = NULL;
            REQUIRE(kissm_features_compute(other, &t, &own) == KISSM_OK);
            scn_result_poison(&r);
            CHECK_MSG(kissm_register_features(other, fs, own, &r) == KISSM_ERR_FEATURES_MISMATCH, "%s (source)", what);
            CHECK(strstr(kissm_last_error_message(), "source") != NULL);
            CHECK(scn_result_is_reset(&r));
            scn_result_poison(&r);
            CHECK_MSG(kissm_register_features(other, own, ft, &r) == KISSM_ERR_FEATURES_MISMATCH, "%s (target)", what);
            CHECK(strstr(kissm_last_error_message(), "target") != NULL);
            CHECK(scn_result_is_reset(&r));
            /* and the matcher is fine with its own features */
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register_features(other, own, own, &r), KISSM_OK);
            kissm_features_destroy(own);
        }
        kissm_destroy(other);
    }

    /* Settings that only affect matching, pruning, the solver or threads: accepted. */
    for (i = 0; i < 5; ++i) {
        kissm_config d = c;
        kissm_matcher *other = NULL;
        kissm_result via, direct;
        switch (i) {
        case 0: d.ratio_test = 0.95; break;
        case 1: d.max_correspondences = 300; break;
        case 2: d.min_inliers = 5; break;
        case 3:
            d.solver_noise_bound_gain = 1.0;
            d.prune_noise_bound_gain = 1.5;
            break;
        case 4: d.num_threads = 1; break;
        default: break;
        }
        REQUIRE(kissm_create(&d, &other) == KISSM_OK);
        scn_result_poison(&via);
        CHECK_MSG(kissm_register_features(other, fs, ft, &via) == KISSM_OK, "case %d: %s", i,
                  kissm_last_error_message());
        scn_result_poison(&direct);
        CHECK_EQ_INT(kissm_register(other, &s, &t, &direct), KISSM_OK);
        CHECK_MSG(scn_result_equal(&direct, &via), "case %d", i);
        if (i == 1) CHECK(via.num_initial_correspondences <= 300);
        kissm_destroy(other);
    }

    /* Under KISSM_VIEWPOINT_CLOUD_CENTER the viewpoint field is unused: features made with one viewpoint
     * are accepted by a matcher with another. */
    {
        kissm_config a = scn_config(VOXEL), b = scn_config(VOXEL);
        kissm_matcher *ma = NULL, *mb = NULL;
        kissm_features *fa = NULL;
        kissm_result via, direct;
        a.viewpoint_mode = b.viewpoint_mode = KISSM_VIEWPOINT_CLOUD_CENTER;
        b.viewpoint[0] = 5.0;
        REQUIRE(kissm_create(&a, &ma) == KISSM_OK);
        REQUIRE(kissm_create(&b, &mb) == KISSM_OK);
        REQUIRE(kissm_features_compute(ma, &s, &fa) == KISSM_OK);
        {
            kissm_features *fb = NULL;
            REQUIRE(kissm_features_compute(mb, &t, &fb) == KISSM_OK);
            scn_result_poison(&direct);
            scn_result_poison(&via);
            CHECK_MSG(kissm_register_features(mb, fa, fb, &via) == KISSM_OK, "%s", kissm_last_error_message());
            CHECK_EQ_INT(kissm_register(ma, &s, &t, &direct), KISSM_OK);
            CHECK(scn_result_equal(&direct, &via));
            kissm_features_destroy(fb);
        }
        kissm_features_destroy(fa);
        kissm_destroy(ma);
        kissm_destroy(mb);
    }

    /* Non-finite policy is a descriptor setting too (the clouds differ under it). */
    {
        kissm_config d = scn_config(VOXEL);
        kissm_matcher *other = NULL;
        kissm_result r;
        d.nonfinite_policy = KISSM_NONFINITE_DROP;
        REQUIRE(kissm_create(&d, &other) == KISSM_OK);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register_features(other, fs, ft, &r), KISSM_ERR_FEATURES_MISMATCH);
        kissm_destroy(other);
    }
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
}

/* One source described once, registered against several targets; the features outlive their matcher. */
static void test_one_against_many(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *maker = NULL, *user = NULL;
    kissm_points s = scn_points(&g_pair.source);
    kissm_features *fs = NULL, *ft[NUM_TARGETS] = {NULL, NULL, NULL};
    int i;
    REQUIRE(kissm_create(&c, &maker) == KISSM_OK);
    REQUIRE(kissm_features_compute(maker, &s, &fs) == KISSM_OK);
    for (i = 0; i < NUM_TARGETS; ++i) {
        kissm_points t = scn_points(&g_targets[i]);
        REQUIRE(kissm_features_compute(maker, &t, &ft[i]) == KISSM_OK);
    }
    kissm_destroy(maker); /* the features must not depend on it */

    REQUIRE(kissm_create(&c, &user) == KISSM_OK);
    for (i = 0; i < NUM_TARGETS; ++i) {
        kissm_points t = scn_points(&g_targets[i]);
        kissm_result via, direct;
        scn_result_poison(&via);
        CHECK_EQ_INT(kissm_register_features(user, fs, ft[i], &via), KISSM_OK);
        CHECK_MSG(via.valid == 1 && scn_rotation_error_deg(via.rotation, g_truths[i].R) < 2.0 &&
                      scn_translation_error(via.translation, g_truths[i].t) < 2.0 * VOXEL,
                  "target %d", i);
        scn_result_poison(&direct);
        CHECK_EQ_INT(kissm_register(user, &s, &t, &direct), KISSM_OK);
        CHECK_MSG(scn_result_equal(&direct, &via), "target %d", i);
        check_feature_times(&via);
    }
    /* the same again after interleaving: every result still the same */
    for (i = NUM_TARGETS - 1; i >= 0; --i) {
        kissm_points t = scn_points(&g_targets[i]);
        kissm_result via, direct;
        scn_result_poison(&direct);
        scn_result_poison(&via);
        CHECK_EQ_INT(kissm_register_features(user, fs, ft[i], &via), KISSM_OK);
        CHECK_EQ_INT(kissm_register(user, &s, &t, &direct), KISSM_OK);
        CHECK(scn_result_equal(&direct, &via));
    }
    kissm_destroy(user);
    /* and with no matcher alive at all, the counts are still there */
    CHECK_EQ_INT(kissm_features_num_points(fs), g_pair.source.count);
    CHECK(kissm_features_num_keypoints(fs) > 0);
    kissm_features_destroy(fs);
    for (i = 0; i < NUM_TARGETS; ++i) kissm_features_destroy(ft[i]);
}

/* ---------------------------------------------------------------------------------------------- */
/* Threads: 4 threads, each with its own matcher, share one set of features                         */
/* ---------------------------------------------------------------------------------------------- */

#define NUM_THREADS 4
#define ROUNDS 3

typedef struct thread_job {
    const kissm_features *source;
    kissm_features *const *targets;
    int first; /* target to start with (threads start at different targets) */
    int32_t status[ROUNDS * NUM_TARGETS];
    kissm_result results[ROUNDS * NUM_TARGETS]; /* indexed by round * NUM_TARGETS + target */
    int create_failed;
} thread_job;

static void *thread_main(void *arg) {
    thread_job *job = (thread_job *)arg;
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    int round, k;
    c.num_threads = 1 + job->first % 2;
    if (kissm_create(&c, &m) != KISSM_OK) {
        job->create_failed = 1;
        return NULL;
    }
    for (round = 0; round < ROUNDS; ++round)
        for (k = 0; k < NUM_TARGETS; ++k) {
            const int target = (job->first + k) % NUM_TARGETS;
            const int slot = round * NUM_TARGETS + target;
            scn_result_poison(&job->results[slot]);
            job->status[slot] = kissm_register_features(m, job->source, job->targets[target], &job->results[slot]);
        }
    kissm_destroy(m);
    return NULL;
}

static void test_threads(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source);
    kissm_features *fs = NULL, *ft[NUM_TARGETS];
    kissm_result serial[NUM_TARGETS];
    thread_job *jobs = (thread_job *)calloc(NUM_THREADS, sizeof(thread_job));
    pthread_t threads[NUM_THREADS];
    int started[NUM_THREADS];
    int i, k;
    REQUIRE(jobs != NULL);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
    for (k = 0; k < NUM_TARGETS; ++k) {
        kissm_points t = scn_points(&g_targets[k]);
        REQUIRE(kissm_features_compute(m, &t, &ft[k]) == KISSM_OK);
        scn_result_poison(&serial[k]);
        CHECK_EQ_INT(kissm_register_features(m, fs, ft[k], &serial[k]), KISSM_OK);
        CHECK_EQ_INT(serial[k].valid, 1);
    }
    kissm_destroy(m);

    for (i = 0; i < NUM_THREADS; ++i) {
        jobs[i].source = fs;
        jobs[i].targets = ft;
        jobs[i].first = i;
        started[i] = pthread_create(&threads[i], NULL, thread_main, &jobs[i]) == 0;
        CHECK(started[i]);
    }
    for (i = 0; i < NUM_THREADS; ++i)
        if (started[i]) pthread_join(threads[i], NULL);
    for (i = 0; i < NUM_THREADS; ++i) {
        if (!started[i]) continue;
        CHECK(!jobs[i].create_failed);
        for (k = 0; k < ROUNDS * NUM_TARGETS; ++k) {
            CHECK_MSG(jobs[i].status[k] == KISSM_OK, "thread %d slot %d: %d", i, k, (int)jobs[i].status[k]);
            CHECK_MSG(scn_result_equal(&jobs[i].results[k], &serial[k % NUM_TARGETS]), "thread %d slot %d", i, k);
        }
    }
    kissm_features_destroy(fs);
    for (k = 0; k < NUM_TARGETS; ++k) kissm_features_destroy(ft[k]);
    free(jobs);
}

/* The signature of a cloud's features: unit-length blocks, nearly the same for the cloud moved rigidly (the
 * voxel grid differs) and far from another place's; zeros without keypoints. */
static double signature_distance(const double *a, const double *b) {
    double sum = 0.0;
    int k;
    for (k = 0; k < KISSM_SIGNATURE_SIZE; ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
    return sqrt(sum);
}

static void signature_of(kissm_matcher *m, const scn_cloud *cloud, double *out) {
    kissm_points p = scn_points(cloud);
    kissm_features *f = NULL;
    REQUIRE(kissm_features_compute(m, &p, &f) == KISSM_OK);
    CHECK_EQ_INT(kissm_features_signature(f, out), KISSM_OK);
    kissm_features_destroy(f);
}

static void test_signature(void) {
    static const int blocks[4] = {0, 33, 66, KISSM_SIGNATURE_SIZE};
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    scn_cloud moved, other, line;
    scn_pose pose;
    const double axis[3] = {1.0, -2.0, 3.0}, shift[3] = {40.0, -25.0, 3.0};
    double here[KISSM_SIGNATURE_SIZE], there[KISSM_SIGNATURE_SIZE], elsewhere[KISSM_SIGNATURE_SIZE];
    double zeros[KISSM_SIGNATURE_SIZE], near, far;
    int b, k;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    signature_of(m, &g_pair.source, here);
    for (b = 0; b < 3; ++b) {
        double squares = 0.0;
        for (k = blocks[b]; k < blocks[b + 1]; ++k) squares += here[k] * here[k];
        CHECK_MSG(fabs(squares - 1.0) < 1e-12, "block %d: squared length %.17g", b, squares);
    }
    scn_cloud_init(&moved);
    scn_cloud_copy(&moved, &g_pair.source);
    scn_pose_axis_angle(&pose, axis, 2.6, shift);
    scn_cloud_apply(&moved, &pose);
    signature_of(m, &moved, there);
    scn_cloud_init(&other);
    scn_make_scene(&other, 11, 5, 15.0, 0.01);
    signature_of(m, &other, elsewhere);
    near = signature_distance(here, there);
    far = signature_distance(here, elsewhere);
    fprintf(stderr, "  signature distance: moved %.4f, another place %.4f\n", near, far);
    CHECK(near < 0.1);
    CHECK(far > 3.0 * near);

    scn_cloud_init(&line);
    scn_make_line(&line, 2, 2000, 0.001);
    {
        kissm_points p = scn_points(&line);
        kissm_features *f = NULL;
        REQUIRE(kissm_features_compute(m, &p, &f) == KISSM_OK);
        CHECK_EQ_INT(kissm_features_num_keypoints(f), 0);
        for (k = 0; k < KISSM_SIGNATURE_SIZE; ++k) zeros[k] = 1.0;
        CHECK_EQ_INT(kissm_features_signature(f, zeros), KISSM_OK);
        for (k = 0; k < KISSM_SIGNATURE_SIZE; ++k) CHECK(zeros[k] == 0.0);
        kissm_features_destroy(f);
    }
    scn_cloud_free(&moved);
    scn_cloud_free(&other);
    scn_cloud_free(&line);
    kissm_destroy(m);
}

/* A failing kissm_features_compute leaves *out alone; cancelling one does too. */
static int32_t cancel_at_features(void *user, int32_t stage, double fraction) {
    (void)user;
    (void)fraction;
    return stage == KISSM_STAGE_FEATURES;
}

static void test_compute_failures(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source);
    kissm_features *f = (kissm_features *)(uintptr_t)0x4321;
    c.progress_fn = cancel_at_features;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    CHECK_EQ_INT(kissm_features_compute(m, &s, &f), KISSM_ERR_CANCELLED);
    CHECK(f == (kissm_features *)(uintptr_t)0x4321);
    kissm_destroy(m);
}

int main(void) {
    int i;
    scn_make_pair(&g_pair, 3, 15.0, 0.01);
    for (i = 0; i < NUM_TARGETS; ++i) {
        /* another scan of layout 3: new samples, cropped to a different part, seen from another pose */
        const double axis[3] = {0.2 * i, 1.0, 0.5 - 0.3 * i};
        const double t[3] = {1.0 + i, -2.0 * i, 0.5};
        const double keep[3] = {-1.0, 0.0, 0.0};
        scn_pose move;
        scn_cloud_init(&g_targets[i]);
        scn_make_scene(&g_targets[i], 3, 1000 + (uint64_t)i, 15.0, 0.01);
        scn_cloud_crop(&g_targets[i], keep, 8.0 - 2.0 * i);
        /* a sensor 1.7 m above the ground somewhere in the yard: keep the fixed-viewpoint convention */
        scn_pose_axis_angle(&move, axis, 0.7 + 0.9 * i, t);
        scn_pose_inverse(&move, &g_truths[i]);
        scn_cloud_apply(&g_targets[i], &g_truths[i]);
    }
    RUN_TEST(test_equal_to_register);
    RUN_TEST(test_nonfinite_features);
    RUN_TEST(test_mismatch);
    RUN_TEST(test_one_against_many);
    RUN_TEST(test_threads);
    RUN_TEST(test_compute_failures);
    RUN_TEST(test_signature);
    for (i = 0; i < NUM_TARGETS; ++i) scn_cloud_free(&g_targets[i]);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
