/* SPDX-License-Identifier: MIT */
/* Bitwise determinism: thread counts, reused and fresh handles, repeated calls, 50 runs, separate
 * processes, permuted input. C99 (+ POSIX fork and pipe for the process test). */
#if defined(__unix__) || defined(__APPLE__)
#  define _POSIX_C_SOURCE 200809L
#  include <sys/types.h>
#  include <sys/wait.h>
#  include <unistd.h>
#  define HAVE_FORK 1
#endif
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.5
/* The reference and most runs use the default mode; the others are checked at 1 and 4 threads. */
#define DEFAULT_MODE KISSM_VIEWPOINT_LOCAL

static scn_pair g_pair;
static kissm_result g_reference; /* num_threads = 1, fresh handle */

static int run_once(int32_t num_threads, int32_t viewpoint_mode, const kissm_points *s, const kissm_points *t,
                    kissm_result *r) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    int32_t st;
    c.num_threads = num_threads;
    c.viewpoint_mode = viewpoint_mode;
    if (kissm_create(&c, &m) != KISSM_OK) return 0;
    scn_result_poison(r);
    st = kissm_register(m, s, t, r);
    kissm_destroy(m);
    return st == KISSM_OK;
}

static void report_difference(const char *what, const kissm_result *a, const kissm_result *b) {
    if (scn_result_equal(a, b)) return;
    fprintf(stderr, "  %s differs:\n", what);
    scn_result_print("reference", a);
    scn_result_print("other", b);
}

/* The automatic voxel size (voxel_size 0, docs/design/voxel_auto.md): the registration at every thread count, with
 * the same voxel_size_used, and with the source's points shuffled. */
static void test_auto_voxel_thread_counts(void) {
    const int32_t counts[] = {1, 2, 3, 8, 0};
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target), sp;
    kissm_result reference, r;
    scn_cloud shuffled;
    size_t i;
    for (i = 0; i < sizeof(counts) / sizeof(counts[0]); ++i) {
        kissm_config c = scn_config(0.0);
        kissm_matcher *m = NULL;
        c.num_threads = counts[i];
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        scn_result_poison(i == 0 ? &reference : &r);
        CHECK_EQ_INT(kissm_register(m, &s, &t, i == 0 ? &reference : &r), KISSM_OK);
        if (i > 0) {
            CHECK_MSG(scn_result_equal(&reference, &r), "auto voxel, num_threads %d", (int)counts[i]);
            report_difference("auto voxel", &reference, &r);
        } else {
            CHECK(reference.valid == 1 && reference.voxel_size_used > 0.0);
        }
        kissm_destroy(m);
    }
    scn_cloud_init(&shuffled);
    scn_cloud_copy(&shuffled, &g_pair.source);
    scn_cloud_shuffle(&shuffled, 11);
    sp = scn_points(&shuffled);
    {
        kissm_config c = scn_config(0.0);
        kissm_matcher *m = NULL;
        c.num_threads = 2;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        CHECK_EQ_INT(kissm_register(m, &sp, &t, &r), KISSM_OK);
        CHECK(r.voxel_size_used == reference.voxel_size_used);
        CHECK(memcmp(r.transform, reference.transform, sizeof r.transform) == 0);
        kissm_destroy(m);
    }
    scn_cloud_free(&shuffled);
}

static void test_thread_counts(void) {
    const int32_t counts[] = {1, 2, 3, 4, 8, 0};
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    size_t i;
    REQUIRE(scn_config(VOXEL).viewpoint_mode == DEFAULT_MODE);
    REQUIRE(run_once(1, DEFAULT_MODE, &s, &t, &g_reference));
    REQUIRE(g_reference.valid == 1);
    CHECK(scn_rotation_error_deg(g_reference.rotation, g_pair.truth.R) < 2.0);
    for (i = 0; i < sizeof(counts) / sizeof(counts[0]); ++i) {
        kissm_result r;
        char what[64];
        CHECK(run_once(counts[i], DEFAULT_MODE, &s, &t, &r));
        sprintf(what, "num_threads %d", (int)counts[i]);
        CHECK_MSG(scn_result_equal(&g_reference, &r), "%s", what);
        report_difference(what, &g_reference, &r);
    }
    /* the other viewpoint modes, too */
    {
        const int32_t modes[3] = {KISSM_VIEWPOINT_FIXED, KISSM_VIEWPOINT_CLOUD_CENTER, KISSM_VIEWPOINT_SIGN_FREE};
        int k;
        for (k = 0; k < 3; ++k) {
            kissm_result a, b;
            char label[64];
            CHECK(run_once(1, modes[k], &s, &t, &a));
            CHECK(run_once(4, modes[k], &s, &t, &b));
            CHECK(a.valid == 1);
            CHECK_MSG(scn_result_equal(&a, &b), "viewpoint mode %d", (int)modes[k]);
            sprintf(label, "viewpoint mode %d, 1 vs 4 threads", (int)modes[k]);
            report_difference(label, &a, &b);
        }
    }
}

static void test_repeated_calls(void) {
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    int32_t threads;
    for (threads = 0; threads <= 2; threads += 2) {
        kissm_config c = scn_config(VOXEL);
        kissm_matcher *m = NULL;
        int i;
        c.num_threads = threads;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        for (i = 0; i < 5; ++i) {
            kissm_result r;
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
            CHECK_MSG(scn_result_equal(&g_reference, &r), "reused handle (num_threads %d), run %d", (int)threads, i);
        }
        /* another pair in between must not leave anything behind */
        {
            kissm_result other, r;
            scn_result_poison(&other);
            CHECK_EQ_INT(kissm_register(m, &t, &s, &other), KISSM_OK);
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
            CHECK(scn_result_equal(&g_reference, &r));
        }
        kissm_destroy(m);
        for (i = 0; i < 5; ++i) {
            kissm_result r;
            CHECK(run_once(threads, DEFAULT_MODE, &s, &t, &r));
            CHECK_MSG(scn_result_equal(&g_reference, &r), "fresh handle (num_threads %d), run %d", (int)threads, i);
        }
    }
}

/* The points in another order: voxel centroids are integer sums of fixed-point offsets and everything after
 * works on voxels in key order, so the result is identical. */
static void test_permutation(void) {
    scn_cloud s2, t2;
    kissm_points s, t;
    kissm_result r;
    uint64_t seed;
    scn_cloud_init(&s2);
    scn_cloud_init(&t2);
    for (seed = 1; seed <= 3; ++seed) {
        char what[64];
        scn_cloud_copy(&s2, &g_pair.source);
        scn_cloud_copy(&t2, &g_pair.target);
        scn_cloud_shuffle(&s2, seed);
        scn_cloud_shuffle(&t2, seed + 100);
        REQUIRE(memcmp(s2.xyz, g_pair.source.xyz, 3 * sizeof(double) * 16) != 0); /* really shuffled */
        s = scn_points(&s2);
        t = scn_points(&t2);
        CHECK(run_once(seed == 2 ? 0 : 1, DEFAULT_MODE, &s, &t, &r));
        sprintf(what, "permutation %d", (int)seed);
        CHECK_MSG(scn_result_equal(&g_reference, &r), "%s", what);
        report_difference(what, &g_reference, &r);
    }
    /* reversed order */
    {
        size_t i, n = g_pair.source.count;
        scn_cloud_copy(&s2, &g_pair.source);
        for (i = 0; i < n / 2; ++i) {
            double tmp[3];
            memcpy(tmp, s2.xyz + 3 * i, sizeof(tmp));
            memcpy(s2.xyz + 3 * i, s2.xyz + 3 * (n - 1 - i), sizeof(tmp));
            memcpy(s2.xyz + 3 * (n - 1 - i), tmp, sizeof(tmp));
        }
        s = scn_points(&s2);
        t = scn_points(&g_pair.target);
        CHECK(run_once(2, DEFAULT_MODE, &s, &t, &r));
        CHECK_MSG(scn_result_equal(&g_reference, &r), "reversed source");
        report_difference("reversed source", &g_reference, &r);
    }
    scn_cloud_free(&s2);
    scn_cloud_free(&t2);
}

/* Features objects are deterministic too: registering features made with different thread counts. */
static void test_features_thread_counts(void) {
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_config c1 = scn_config(VOXEL), c4 = scn_config(VOXEL);
    kissm_matcher *m1 = NULL, *m4 = NULL;
    kissm_features *s1 = NULL, *t4 = NULL;
    kissm_result r;
    c1.num_threads = 1;
    c4.num_threads = 4;
    REQUIRE(kissm_create(&c1, &m1) == KISSM_OK);
    REQUIRE(kissm_create(&c4, &m4) == KISSM_OK);
    REQUIRE(kissm_features_compute(m1, &s, &s1) == KISSM_OK);
    REQUIRE(kissm_features_compute(m4, &t, &t4) == KISSM_OK);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register_features(m4, s1, t4, &r), KISSM_OK);
    CHECK(scn_result_equal(&g_reference, &r));
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register_features(m1, s1, t4, &r), KISSM_OK);
    CHECK(scn_result_equal(&g_reference, &r));
    {
        /* signatures of features made at 1 and 4 threads: the same bits */
        kissm_features *s4 = NULL;
        double a[KISSM_SIGNATURE_SIZE], b[KISSM_SIGNATURE_SIZE];
        REQUIRE(kissm_features_compute(m4, &s, &s4) == KISSM_OK);
        CHECK_EQ_INT(kissm_features_signature(s1, a), KISSM_OK);
        CHECK_EQ_INT(kissm_features_signature(s4, b), KISSM_OK);
        CHECK(memcmp(a, b, sizeof a) == 0);
        kissm_features_destroy(s4);
    }
    kissm_features_destroy(s1);
    kissm_features_destroy(t4);
    kissm_destroy(m1);
    kissm_destroy(m4);
}

/* KISSM_DETERMINISM_RUNS overrides the count of test_fifty_runs (the sanitizer presets use 16, which still
 * visits every thread count with a fresh and a reused handle: each call is ~10x slower there). */
static int fifty_runs_count(void) {
    const char *env = getenv("KISSM_DETERMINISM_RUNS");
    const int n = env != NULL ? atoi(env) : 0;
    return n >= 8 ? n : 50;
}

/* 50 runs cycling through 1, 2, 4 and 8 threads, alternating a fresh handle and one reused handle per
 * thread count: all equal the reference bit for bit. */
static void test_fifty_runs(void) {
    const int32_t counts[] = {1, 2, 4, 8};
    kissm_matcher *reused[4] = {NULL, NULL, NULL, NULL};
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    const int count = fifty_runs_count();
    int i, equal = 0;
    for (i = 0; i < 4; ++i) {
        kissm_config c = scn_config(VOXEL);
        c.num_threads = counts[i];
        REQUIRE(kissm_create(&c, &reused[i]) == KISSM_OK);
    }
    for (i = 0; i < count; ++i) {
        kissm_result r;
        int ok;
        if (i % 2 == 0) {
            ok = run_once(counts[i % 4], DEFAULT_MODE, &s, &t, &r);
        } else {
            scn_result_poison(&r);
            ok = kissm_register(reused[i % 4], &s, &t, &r) == KISSM_OK;
        }
        equal += ok && scn_result_equal(&g_reference, &r);
    }
    CHECK_EQ_INT(equal, count);
    for (i = 0; i < 4; ++i) kissm_destroy(reused[i]);
}

#ifdef HAVE_FORK
/* Separate processes (forked before any registration of theirs, 1 and 4 threads) send their results back
 * through a pipe: all equal the parent's reference. */
static void test_separate_processes(void) {
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    int k, equal = 0;
    for (k = 0; k < 4; ++k) {
        int fd[2];
        pid_t child;
        kissm_result r;
        size_t got = 0;
        int status = 0;
        REQUIRE(pipe(fd) == 0);
        fflush(NULL);
        child = fork();
        REQUIRE(child >= 0);
        if (child == 0) {
            kissm_result mine;
            size_t sent = 0;
            close(fd[0]);
            if (!run_once(k % 2 ? 4 : 1, DEFAULT_MODE, &s, &t, &mine)) _exit(1);
            while (sent < sizeof(mine)) {
                const ssize_t n = write(fd[1], (const char *)&mine + sent, sizeof(mine) - sent);
                if (n <= 0) _exit(1);
                sent += (size_t)n;
            }
            _exit(0);
        }
        close(fd[1]);
        while (got < sizeof(r)) {
            const ssize_t n = read(fd[0], (char *)&r + got, sizeof(r) - got);
            if (n <= 0) break;
            got += (size_t)n;
        }
        close(fd[0]);
        waitpid(child, &status, 0);
        equal +=
            got == sizeof(r) && WIFEXITED(status) && WEXITSTATUS(status) == 0 && scn_result_equal(&g_reference, &r);
    }
    CHECK_EQ_INT(equal, 4);
}
#endif

/* Refinement: kissm_register with refine_mode set, kissm_refine and kissm_refine_features give the same bits
 * at every thread count, on fresh and reused handles, for permuted input, and the features path equals the
 * points path. */
static int run_refine(int which, int32_t mode, int32_t num_threads, kissm_matcher *reuse, const kissm_points *s,
                      const kissm_points *t, const double initial[16], kissm_result *r) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = reuse;
    int32_t st;
    c.num_threads = num_threads;
    c.refine_mode = mode;
    if (m == NULL && kissm_create(&c, &m) != KISSM_OK) return 0;
    scn_result_poison(r);
    st = which == 0 ? kissm_register(m, s, t, r) : kissm_refine(m, s, t, initial, r);
    if (reuse == NULL) kissm_destroy(m);
    return st == KISSM_OK;
}

static void test_refine_determinism(void) {
    const int32_t counts[] = {2, 3, 8, 0}; /* 4: the features path below */
    const int32_t modes[2] = {KISSM_REFINE_GICP, KISSM_REFINE_POINT_TO_PLANE};
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    double initial[16];
    scn_pose start;
    const double axis[3] = {1.0, 1.0, 0.0}, shift[3] = {0.3, -0.2, 0.1};
    int mi, which;
    scn_pose_axis_angle(&start, axis, 0.05, shift);
    {
        scn_pose composed;
        scn_pose_compose(&g_pair.truth, &start, &composed);
        scn_pose_to_matrix(&composed, initial);
    }
    for (mi = 0; mi < 2; ++mi) {
        for (which = 0; which < 2; ++which) {
            const char *what = which == 0 ? "register + refine" : "kissm_refine";
            kissm_result ref, r;
            kissm_matcher *reused = NULL;
            size_t i;
            int k;
            REQUIRE(run_refine(which, modes[mi], 1, NULL, &s, &t, initial, &ref));
            CHECK_MSG(ref.valid == 1 && ref.refine_iterations >= 1, "%s mode %d: valid %d", what, (int)modes[mi],
                      (int)ref.valid);
            for (i = 0; i < sizeof(counts) / sizeof(counts[0]); ++i) {
                CHECK(run_refine(which, modes[mi], counts[i], NULL, &s, &t, initial, &r));
                CHECK_MSG(scn_result_equal(&ref, &r), "%s mode %d: %d threads differ from 1", what, (int)modes[mi],
                          (int)counts[i]);
                report_difference(what, &ref, &r);
            }
            /* a reused handle, with other calls in between */
            {
                kissm_config c = scn_config(VOXEL);
                c.num_threads = 2;
                c.refine_mode = modes[mi];
                REQUIRE(kissm_create(&c, &reused) == KISSM_OK);
            }
            for (k = 0; k < 2; ++k) {
                kissm_result other;
                CHECK(run_refine(which, modes[mi], 0, reused, &s, &t, initial, &r));
                CHECK_MSG(scn_result_equal(&ref, &r), "%s mode %d: reused handle, run %d", what, (int)modes[mi], k);
                CHECK(run_refine(1 - which, modes[mi], 0, reused, &t, &s, initial, &other));
            }
            kissm_destroy(reused);
            /* permuted input */
            {
                scn_cloud s2, t2;
                kissm_points ps, pt;
                scn_cloud_init(&s2);
                scn_cloud_init(&t2);
                scn_cloud_copy(&s2, &g_pair.source);
                scn_cloud_copy(&t2, &g_pair.target);
                scn_cloud_shuffle(&s2, 7);
                scn_cloud_shuffle(&t2, 8);
                ps = scn_points(&s2);
                pt = scn_points(&t2);
                CHECK(run_refine(which, modes[mi], 3, NULL, &ps, &pt, initial, &r));
                CHECK_MSG(scn_result_equal(&ref, &r), "%s mode %d: permuted input", what, (int)modes[mi]);
                scn_cloud_free(&s2);
                scn_cloud_free(&t2);
            }
        }
        /* the features path, features made at other thread counts than the call */
        {
            kissm_config c1 = scn_config(VOXEL), c4 = scn_config(VOXEL);
            kissm_matcher *m1 = NULL, *m4 = NULL;
            kissm_features *fs = NULL, *ft = NULL;
            kissm_result direct, via_register, via_refine, r;
            c1.num_threads = 1;
            c4.num_threads = 4;
            c1.refine_mode = c4.refine_mode = modes[mi];
            REQUIRE(kissm_create(&c1, &m1) == KISSM_OK);
            REQUIRE(kissm_create(&c4, &m4) == KISSM_OK);
            REQUIRE(kissm_features_compute(m4, &s, &fs) == KISSM_OK);
            REQUIRE(kissm_features_compute(m1, &t, &ft) == KISSM_OK);
            REQUIRE(run_refine(0, modes[mi], 1, NULL, &s, &t, initial, &via_register));
            REQUIRE(run_refine(1, modes[mi], 1, NULL, &s, &t, initial, &direct));
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register_features(m1, fs, ft, &r), KISSM_OK);
            CHECK_MSG(scn_result_equal(&via_register, &r), "mode %d: register_features differs", (int)modes[mi]);
            scn_result_poison(&via_refine);
            CHECK_EQ_INT(kissm_refine_features(m4, fs, ft, initial, &via_refine), KISSM_OK);
            CHECK_MSG(scn_result_equal(&direct, &via_refine), "mode %d: refine_features differs from refine",
                      (int)modes[mi]);
            report_difference("refine_features", &direct, &via_refine);
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_refine_features(m1, fs, ft, initial, &r), KISSM_OK);
            CHECK(scn_result_equal(&via_refine, &r));
            kissm_features_destroy(fs);
            kissm_features_destroy(ft);
            kissm_destroy(m1);
            kissm_destroy(m4);
        }
    }
}

int main(void) {
    scn_make_pair(&g_pair, 5, 15.0, 0.01);
    RUN_TEST(test_thread_counts);
    RUN_TEST(test_auto_voxel_thread_counts);
    RUN_TEST(test_repeated_calls);
    RUN_TEST(test_fifty_runs);
#ifdef HAVE_FORK
    RUN_TEST(test_separate_processes);
#endif
    RUN_TEST(test_permutation);
    RUN_TEST(test_features_thread_counts);
    RUN_TEST(test_refine_determinism);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
