/* SPDX-License-Identifier: MIT */
/* Concurrency: eight threads, each with its own matcher, register different pairs at once and share
 * kissm_features objects; every result must equal the serial run's bit for bit. A child forked after the
 * parent has registered must register too, with the same result. C99 + pthreads; also run under TSan
 * (CMakePresets.json, label "concurrency"). */
#define _POSIX_C_SOURCE 200809L

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.5
#define NUM_PAIRS 4
#define NUM_WORKERS 8
#define ROUNDS 2

static scn_pair g_pairs[NUM_PAIRS];
static kissm_result g_serial[NUM_PAIRS]; /* one thread, one call at a time */
/* Computed once, then read by every worker at the same time (documented as safe). */
static kissm_features *g_source_features[NUM_PAIRS], *g_target_features[NUM_PAIRS];

static int register_pair(int pair, int32_t num_threads, kissm_result *r) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pairs[pair].source), t = scn_points(&g_pairs[pair].target);
    int32_t st;
    c.num_threads = num_threads;
    if (kissm_create(&c, &m) != KISSM_OK) return 0;
    scn_result_poison(r);
    st = kissm_register(m, &s, &t, r);
    kissm_destroy(m);
    return st == KISSM_OK;
}

/* Workers must not touch the harness counters (not thread-safe): they record, main checks. */
typedef struct worker {
    pthread_t thread;
    int pair;
    int32_t num_threads;
    int calls_ok; /* calls that returned KISSM_OK */
    int equal;    /* results equal to g_serial[pair] */
} worker;

static void *work(void *arg) {
    worker *w = (worker *)arg;
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pairs[w->pair].source), t = scn_points(&g_pairs[w->pair].target);
    kissm_result r;
    int round;
    c.num_threads = w->num_threads;
    if (kissm_create(&c, &m) != KISSM_OK) return NULL;
    for (round = 0; round < ROUNDS; ++round) {
        /* The same handle reused: from raw points, then from the shared features. */
        scn_result_poison(&r);
        if (kissm_register(m, &s, &t, &r) == KISSM_OK) {
            w->calls_ok++;
            w->equal += scn_result_equal(&g_serial[w->pair], &r);
        }
        scn_result_poison(&r);
        if (kissm_register_features(m, g_source_features[w->pair], g_target_features[w->pair], &r) == KISSM_OK) {
            w->calls_ok++;
            w->equal += scn_result_equal(&g_serial[w->pair], &r);
        }
    }
    kissm_destroy(m);
    return NULL;
}

/* Starts NUM_WORKERS workers running fn (pair i % NUM_PAIRS, 1 + i % 3 threads), joins them and checks that
 * each made `calls` calls, all OK and all equal to the serial run. */
static void run_workers(worker *workers, void *(*fn)(void *), int calls, const char *label) {
    int i, started = 0;
    memset(workers, 0, NUM_WORKERS * sizeof(*workers));
    for (i = 0; i < NUM_WORKERS; ++i) {
        workers[i].pair = i % NUM_PAIRS;
        workers[i].num_threads = 1 + i % 3;
        if (pthread_create(&workers[i].thread, NULL, fn, &workers[i]) == 0)
            started++;
        else
            break;
    }
    CHECK_EQ_INT(started, NUM_WORKERS);
    for (i = 0; i < started; ++i) pthread_join(workers[i].thread, NULL);
    for (i = 0; i < started; ++i) {
        CHECK_MSG(workers[i].calls_ok == calls, "%s %d: %d of %d calls OK", label, i, workers[i].calls_ok, calls);
        CHECK_MSG(workers[i].equal == calls, "%s %d (pair %d, %d threads): %d of %d results equal the serial run",
                  label, i, workers[i].pair, (int)workers[i].num_threads, workers[i].equal, calls);
    }
}

static void test_parallel_matchers_equal_serial(void) {
    worker workers[NUM_WORKERS];
    int i;
    for (i = 0; i < NUM_PAIRS; ++i) REQUIRE(register_pair(i, 1, &g_serial[i]));
    for (i = 0; i < NUM_PAIRS; ++i) CHECK(g_serial[i].valid == 1); /* the comparison means something */
    /* per-call pools of 1, 2 and 3 threads run side by side */
    run_workers(workers, work, 2 * ROUNDS, "worker");
}

static void test_fork_after_register(void) {
    kissm_result parent;
    pid_t child;
    int status = 0;
    /* The parent has run a multi-threaded call; its pool is gone, so the child starts clean. */
    REQUIRE(register_pair(1, 2, &parent));
    CHECK(scn_result_equal(&g_serial[1], &parent));
    fflush(NULL);
    child = fork();
    REQUIRE(child >= 0);
    if (child == 0) {
        kissm_result r;
        const int ok = register_pair(1, 2, &r) && scn_result_equal(&g_serial[1], &r) && register_pair(2, 3, &r) &&
                       scn_result_equal(&g_serial[2], &r);
        _exit(ok ? 0 : 1);
    }
    REQUIRE(waitpid(child, &status, 0) == child);
    CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "child status %d", status);
    /* And the parent still works afterwards. */
    REQUIRE(register_pair(3, 2, &parent));
    CHECK(scn_result_equal(&g_serial[3], &parent));
}

/* Refinement side by side: each worker its own matcher (GICP or point-to-plane, 1-3 threads), kissm_refine
 * from a prior, kissm_refine_features and kissm_register_features on features shared by all (computed with
 * refinement on, so their point index is shared too), kissm_register with refinement; all equal the serial
 * run. */
static kissm_features *g_refine_source[NUM_PAIRS], *g_refine_target[NUM_PAIRS];
static kissm_result g_serial_refine[2][NUM_PAIRS][3]; /* [mode][pair][call] */
static double g_initial[NUM_PAIRS][16];

static int32_t refine_mode_of(int k) { return k % 2 ? KISSM_REFINE_POINT_TO_PLANE : KISSM_REFINE_GICP; }

static int refine_calls(kissm_matcher *m, int pair, kissm_result out[3]) {
    kissm_points s = scn_points(&g_pairs[pair].source), t = scn_points(&g_pairs[pair].target);
    int ok = 0;
    scn_result_poison(&out[0]);
    ok += kissm_refine(m, &s, &t, g_initial[pair], &out[0]) == KISSM_OK;
    scn_result_poison(&out[1]);
    ok += kissm_refine_features(m, g_refine_source[pair], g_refine_target[pair], g_initial[pair], &out[1]) == KISSM_OK;
    scn_result_poison(&out[2]);
    ok += kissm_register(m, &s, &t, &out[2]) == KISSM_OK;
    return ok;
}

static void *refine_work(void *arg) {
    worker *w = (worker *)arg;
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    const int mode = w->num_threads % 2; /* see test_parallel_refine: mode from the worker's number */
    int round, k;
    c.num_threads = w->num_threads;
    c.refine_mode = refine_mode_of(mode);
    if (kissm_create(&c, &m) != KISSM_OK) return NULL;
    for (round = 0; round < ROUNDS; ++round) {
        kissm_result r[3];
        w->calls_ok += refine_calls(m, w->pair, r);
        for (k = 0; k < 3; ++k) w->equal += scn_result_equal(&g_serial_refine[mode][w->pair][k], &r[k]);
    }
    kissm_destroy(m);
    return NULL;
}

static void test_parallel_refine(void) {
    worker workers[NUM_WORKERS];
    int i, mode;
    for (i = 0; i < NUM_PAIRS; ++i) {
        const double axis[3] = {0.0, 1.0, 1.0}, shift[3] = {0.2, 0.1, -0.1};
        scn_pose p, start;
        scn_pose_axis_angle(&p, axis, 0.04, shift);
        scn_pose_compose(&g_pairs[i].truth, &p, &start);
        scn_pose_to_matrix(&start, g_initial[i]);
    }
    {
        kissm_config c = scn_config(VOXEL);
        kissm_matcher *m = NULL;
        c.refine_mode = KISSM_REFINE_GICP;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        for (i = 0; i < NUM_PAIRS; ++i) {
            kissm_points s = scn_points(&g_pairs[i].source), t = scn_points(&g_pairs[i].target);
            REQUIRE(kissm_features_compute(m, &s, &g_refine_source[i]) == KISSM_OK);
            REQUIRE(kissm_features_compute(m, &t, &g_refine_target[i]) == KISSM_OK);
        }
        kissm_destroy(m);
    }
    for (mode = 0; mode < 2; ++mode) {
        kissm_config c = scn_config(VOXEL);
        kissm_matcher *m = NULL;
        c.num_threads = 1;
        c.refine_mode = refine_mode_of(mode);
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        for (i = 0; i < NUM_PAIRS; ++i) {
            REQUIRE(refine_calls(m, i, g_serial_refine[mode][i]) == 3);
            CHECK(g_serial_refine[mode][i][0].refine_iterations >= 1 &&
                  g_serial_refine[mode][i][2].refine_iterations >= 1);
        }
        kissm_destroy(m);
    }
    run_workers(workers, refine_work, 3 * ROUNDS, "refine worker"); /* odd threads: point-to-plane, even: GICP */
    for (i = 0; i < NUM_PAIRS; ++i) {
        kissm_features_destroy(g_refine_source[i]);
        kissm_features_destroy(g_refine_target[i]);
    }
}

int main(void) {
    int i;
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    /* Seeds 40-42 and 44: scene 43's coarse pose (right, 0.89 degrees off, rotation uncertainty 1.17 degrees) is
     * checked by GICP, which does not converge within refine_max_iterations, so it is not valid, and a pair that is
     * not valid would make the comparison mean less. */
    for (i = 0; i < NUM_PAIRS; ++i) scn_make_pair(&g_pairs[i], 40 + (uint64_t)i + (i >= 3), 10.0, 0.01);
    if (kissm_create(&c, &m) != KISSM_OK) return 1;
    for (i = 0; i < NUM_PAIRS; ++i) {
        kissm_points s = scn_points(&g_pairs[i].source), t = scn_points(&g_pairs[i].target);
        if (kissm_features_compute(m, &s, &g_source_features[i]) != KISSM_OK ||
            kissm_features_compute(m, &t, &g_target_features[i]) != KISSM_OK)
            return 1;
    }
    kissm_destroy(m); /* features outlive the matcher that computed them */
    RUN_TEST(test_parallel_matchers_equal_serial);
    RUN_TEST(test_fork_after_register);
    RUN_TEST(test_parallel_refine);
    for (i = 0; i < NUM_PAIRS; ++i) {
        kissm_features_destroy(g_source_features[i]);
        kissm_features_destroy(g_target_features[i]);
        scn_pair_free(&g_pairs[i]);
    }
    return TEST_SUMMARY();
}
