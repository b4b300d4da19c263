/* SPDX-License-Identifier: MIT */
/* Log and progress callbacks, cancellation by the progress callback and by kissm_cancel() from another
 * thread (pthreads). C99. */
#define _POSIX_C_SOURCE 200809L

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.5

static scn_pair g_pair;
static pthread_t g_main_thread;

static void sleep_ms(double ms) {
    struct timespec ts;
    ts.tv_sec = (time_t)(ms / 1000.0);
    ts.tv_nsec = (long)((ms - 1000.0 * (double)ts.tv_sec) * 1e6);
    nanosleep(&ts, NULL);
}

/* ---------------------------------------------------------------------------------------------- */
/* Log callback                                                                                     */
/* ---------------------------------------------------------------------------------------------- */

typedef struct log_record {
    int calls;
    int by_level[6]; /* index = level, 0 and 5 for out of range */
    int empty_messages;
    int off_thread;
    char first[256];
} log_record;

static void on_log(void *user, int32_t level, const char *message) {
    log_record *rec = (log_record *)user;
    rec->calls++;
    rec->by_level[(level >= 1 && level <= 4) ? level : (level < 1 ? 0 : 5)]++;
    if (message == NULL || message[0] == '\0') rec->empty_messages++;
    if (!pthread_equal(pthread_self(), g_main_thread)) rec->off_thread++;
    if (rec->calls == 1 && message != NULL) {
        strncpy(rec->first, message, sizeof(rec->first) - 1);
        rec->first[sizeof(rec->first) - 1] = '\0';
    }
}

static void run_logged(int32_t log_level, int32_t num_threads, log_record *rec, kissm_result *r) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    memset(rec, 0, sizeof(*rec));
    c.log_fn = on_log;
    c.log_user_data = rec;
    c.log_level = log_level;
    c.num_threads = num_threads;
    if (kissm_create(&c, &m) != KISSM_OK) {
        CHECK_MSG(0, "create: %s", kissm_last_error_message());
        return;
    }
    scn_result_poison(r);
    CHECK_EQ_INT(kissm_register(m, &s, &t, r), KISSM_OK);
    kissm_destroy(m);
}

static void test_log(void) {
    log_record rec;
    kissm_result r, quiet;
    /* INFO: messages arrive, on the calling thread, with levels up to INFO */
    run_logged(KISSM_LOG_INFO, 2, &rec, &r);
    CHECK_EQ_INT(r.valid, 1);
    CHECK_MSG(rec.calls > 0, "no log message at KISSM_LOG_INFO");
    CHECK(rec.by_level[KISSM_LOG_INFO] > 0);
    CHECK_EQ_INT(rec.by_level[0], 0);
    CHECK_EQ_INT(rec.by_level[KISSM_LOG_DEBUG], 0);
    CHECK_EQ_INT(rec.by_level[5], 0);
    CHECK_EQ_INT(rec.empty_messages, 0);
    CHECK_EQ_INT(rec.off_thread, 0);
    if (rec.calls > 0) fprintf(stderr, "  first INFO message: %s\n", rec.first);

    /* DEBUG: at least as much, levels within range */
    run_logged(KISSM_LOG_DEBUG, 2, &rec, &quiet);
    CHECK(rec.calls > 0);
    CHECK_EQ_INT(rec.by_level[0] + rec.by_level[5], 0);
    CHECK_EQ_INT(rec.off_thread, 0);
    CHECK(scn_result_equal(&r, &quiet)); /* logging changes nothing */

    /* WARN (the default) on a clean pair: no INFO or DEBUG messages */
    run_logged(KISSM_LOG_WARN, 2, &rec, &quiet);
    CHECK_EQ_INT(rec.by_level[KISSM_LOG_INFO] + rec.by_level[KISSM_LOG_DEBUG], 0);
    CHECK(scn_result_equal(&r, &quiet));

    /* ERROR and 0 (nothing) */
    run_logged(KISSM_LOG_ERROR, 1, &rec, &quiet);
    CHECK_EQ_INT(rec.by_level[KISSM_LOG_WARN] + rec.by_level[KISSM_LOG_INFO] + rec.by_level[KISSM_LOG_DEBUG], 0);
    run_logged(0, 1, &rec, &quiet);
    CHECK_EQ_INT(rec.calls, 0);
    CHECK(scn_result_equal(&r, &quiet));

    /* log_fn NULL with a verbose level: fine, silent */
    {
        kissm_config c = scn_config(VOXEL);
        kissm_matcher *m = NULL;
        kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
        c.log_level = KISSM_LOG_DEBUG;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        scn_result_poison(&quiet);
        CHECK_EQ_INT(kissm_register(m, &s, &t, &quiet), KISSM_OK);
        CHECK(scn_result_equal(&r, &quiet));
        kissm_destroy(m);
    }
}

/* ---------------------------------------------------------------------------------------------- */
/* Progress callback                                                                                */
/* ---------------------------------------------------------------------------------------------- */

#define MAX_EVENTS 4096

typedef struct progress_record {
    int calls;
    int32_t stage[MAX_EVENTS];
    double fraction[MAX_EVENTS];
    int off_thread;
    int cancel_stage; /* return 1 on the first call at this stage (0 = never) */
    int cancel_after; /* ... or on this call number (1-based; 0 = never) */
    int cancels_returned;
} progress_record;

static int32_t on_progress(void *user, int32_t stage, double fraction) {
    progress_record *rec = (progress_record *)user;
    if (rec->calls < MAX_EVENTS) {
        rec->stage[rec->calls] = stage;
        rec->fraction[rec->calls] = fraction;
    }
    rec->calls++;
    if (!pthread_equal(pthread_self(), g_main_thread)) rec->off_thread++;
    if ((rec->cancel_stage != 0 && stage == rec->cancel_stage) ||
        (rec->cancel_after != 0 && rec->calls == rec->cancel_after)) {
        rec->cancel_stage = 0;
        rec->cancel_after = 0;
        rec->cancels_returned++;
        return 1;
    }
    return 0;
}

static void print_events(const progress_record *rec) {
    int i;
    fprintf(stderr, "  progress events:");
    for (i = 0; i < rec->calls && i < MAX_EVENTS; ++i)
        fprintf(stderr, " (%d, %.3g)", (int)rec->stage[i], rec->fraction[i]);
    fprintf(stderr, "\n");
}

/* Stages 1..6, fractions in [0, 1], (stage, fraction) never going back. */
static int check_events(const char *what, const progress_record *rec, int32_t first_stage, int32_t last_stage) {
    int i, ok = 1;
    const int n = rec->calls < MAX_EVENTS ? rec->calls : MAX_EVENTS;
    CHECK_MSG(rec->calls > 0, "%s: no progress call", what);
    CHECK_EQ_INT(rec->off_thread, 0);
    for (i = 0; i < n; ++i) {
        if (rec->stage[i] < KISSM_STAGE_VOXELIZE || rec->stage[i] > KISSM_STAGE_REFINE) ok = 0;
        if (!(rec->fraction[i] >= 0.0 && rec->fraction[i] <= 1.0)) ok = 0;
    }
    CHECK_MSG(ok, "%s: a stage or fraction out of range", what);
    {
        int monotone = 1;
        for (i = 1; i < n; ++i)
            if (rec->stage[i] < rec->stage[i - 1] ||
                (rec->stage[i] == rec->stage[i - 1] && rec->fraction[i] < rec->fraction[i - 1]))
                monotone = 0;
        CHECK_MSG(monotone, "%s: progress goes backwards (stages must be non-decreasing)", what);
        if (!monotone) print_events(rec);
        ok = ok && monotone;
    }
    if (n > 0) {
        CHECK_MSG(rec->stage[0] == first_stage, "%s: first stage %d", what, (int)rec->stage[0]);
        CHECK_MSG(rec->stage[n - 1] == last_stage, "%s: last stage %d", what, (int)rec->stage[n - 1]);
    }
    return ok;
}

static void test_progress(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    progress_record *rec = (progress_record *)calloc(1, sizeof(progress_record));
    kissm_result r, plain;
    int stage;
    REQUIRE(rec != NULL);
    c.progress_fn = on_progress;
    c.progress_user_data = rec;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);

    /* kissm_register: every stage, in order */
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
    CHECK_EQ_INT(r.valid, 1);
    check_events("kissm_register", rec, KISSM_STAGE_VOXELIZE, KISSM_STAGE_SOLVER);
    {
        int seen[6] = {0, 0, 0, 0, 0, 0}, i;
        for (i = 0; i < rec->calls && i < MAX_EVENTS; ++i)
            if (rec->stage[i] >= 1 && rec->stage[i] <= 5) seen[rec->stage[i]] = 1;
        for (i = 1; i <= 5; ++i) CHECK_MSG(seen[i], "stage %d never reported", i);
    }
    /* the callback changes nothing */
    {
        kissm_config q = scn_config(VOXEL);
        kissm_matcher *qm = NULL;
        REQUIRE(kissm_create(&q, &qm) == KISSM_OK);
        scn_result_poison(&plain);
        CHECK_EQ_INT(kissm_register(qm, &s, &t, &plain), KISSM_OK);
        CHECK(scn_result_equal(&r, &plain));
        kissm_destroy(qm);
    }

    /* kissm_features_compute: voxelisation and features only */
    {
        kissm_features *fs = NULL, *ft = NULL;
        memset(rec, 0, sizeof(*rec));
        CHECK_EQ_INT(kissm_features_compute(m, &s, &fs), KISSM_OK);
        check_events("kissm_features_compute", rec, KISSM_STAGE_VOXELIZE, KISSM_STAGE_FEATURES);
        CHECK_EQ_INT(kissm_features_compute(m, &t, &ft), KISSM_OK);
        /* kissm_register_features: matching onwards */
        memset(rec, 0, sizeof(*rec));
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register_features(m, fs, ft, &r), KISSM_OK);
        check_events("kissm_register_features", rec, KISSM_STAGE_MATCHING, KISSM_STAGE_SOLVER);
        CHECK(scn_result_equal(&r, &plain));

        /* cancelling register_features at each of its stages */
        for (stage = KISSM_STAGE_MATCHING; stage <= KISSM_STAGE_SOLVER; ++stage) {
            memset(rec, 0, sizeof(*rec));
            rec->cancel_stage = stage;
            scn_result_poison(&r);
            CHECK_MSG(kissm_register_features(m, fs, ft, &r) == KISSM_ERR_CANCELLED, "register_features, stage %d",
                      stage);
            CHECK_EQ_INT(rec->cancels_returned, 1);
            CHECK(scn_result_is_reset(&r));
            CHECK(strstr(kissm_last_error_message(), "cancel") != NULL);
        }
        /* cancelling features_compute: *out untouched */
        {
            kissm_features *f = (kissm_features *)(uintptr_t)0x777;
            memset(rec, 0, sizeof(*rec));
            rec->cancel_stage = KISSM_STAGE_FEATURES;
            CHECK_EQ_INT(kissm_features_compute(m, &s, &f), KISSM_ERR_CANCELLED);
            CHECK(f == (kissm_features *)(uintptr_t)0x777);
        }
        kissm_features_destroy(fs);
        kissm_features_destroy(ft);
    }

    /* kissm_register cancelled at each stage, and on the very first call; each time the next call works */
    for (stage = 0; stage <= KISSM_STAGE_SOLVER; ++stage) {
        memset(rec, 0, sizeof(*rec));
        if (stage == 0)
            rec->cancel_after = 1;
        else
            rec->cancel_stage = stage;
        scn_result_poison(&r);
        CHECK_MSG(kissm_register(m, &s, &t, &r) == KISSM_ERR_CANCELLED, "register, stage %d", stage);
        CHECK_EQ_INT(rec->cancels_returned, 1);
        CHECK(scn_result_is_reset(&r));
        CHECK(strstr(kissm_last_error_message(), "cancel") != NULL);
        /* stopped promptly: at most one more progress call after the one that asked to stop */
        {
            int i, asked = -1;
            for (i = 0; i < rec->calls && i < MAX_EVENTS; ++i)
                if (stage != 0 && rec->stage[i] == stage) {
                    asked = i;
                    break;
                }
            if (stage == 0) asked = 0;
            CHECK_MSG(rec->calls == asked + 1, "register, stage %d: %d progress calls after cancelling", stage,
                      rec->calls - asked - 1);
        }
        memset(rec, 0, sizeof(*rec));
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
        CHECK_MSG(scn_result_equal(&r, &plain), "after a cancel at stage %d", stage);
    }
    kissm_destroy(m);
    free(rec);
}

/* ---------------------------------------------------------------------------------------------- */
/* kissm_cancel                                                                                     */
/* ---------------------------------------------------------------------------------------------- */

static void test_cancel_idle(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_features *fs = NULL, *ft = NULL;
    kissm_result r, ref;
    kissm_cancel(NULL); /* no-op */
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(&ref);
    CHECK_EQ_INT(kissm_register(m, &s, &t, &ref), KISSM_OK);
    CHECK_EQ_INT(ref.valid, 1);

    /* a cancel made while no call runs is cleared when the next call starts */
    kissm_cancel(m);
    kissm_cancel(m);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
    CHECK(scn_result_equal(&ref, &r));
    kissm_cancel(m);
    CHECK_EQ_INT(kissm_features_compute(m, &s, &fs), KISSM_OK);
    kissm_cancel(m);
    CHECK_EQ_INT(kissm_features_compute(m, &t, &ft), KISSM_OK);
    kissm_cancel(m);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register_features(m, fs, ft, &r), KISSM_OK);
    CHECK(scn_result_equal(&ref, &r));
    /* a cancel after a failed call, too */
    {
        kissm_points empty = s;
        empty.count = 0;
        CHECK_EQ_INT(kissm_register(m, &empty, &t, &r), KISSM_ERR_EMPTY_INPUT);
        kissm_cancel(m);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
        CHECK(scn_result_equal(&ref, &r));
    }
    /* cancelling another matcher does not touch this one */
    {
        kissm_matcher *other = NULL;
        REQUIRE(kissm_create(&c, &other) == KISSM_OK);
        kissm_cancel(other);
        kissm_destroy(other);
    }
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_destroy(m);
}

/* Thread A registers; thread B cancels. */
typedef struct cancel_shared {
    pthread_mutex_t lock;
    int running;       /* set by A's progress callback once trigger_stage is under way */
    int trigger_stage; /* KISSM_STAGE_* that arms a single cancel (modes 0 and 2) */
    int done;          /* set by A when kissm_register returned */
    double cancel_at;  /* when B first called kissm_cancel (scn_now) */
    int cancels;       /* how many times B called it */
    int mode;          /* 0: B cancels once, after A reported the features stage; 1: B cancels in a loop;
                        * 2: B cancels once, after A reported the matching stage */
    kissm_matcher *m;
} cancel_shared;

static int32_t on_progress_running(void *user, int32_t stage, double fraction) {
    cancel_shared *sh = (cancel_shared *)user;
    (void)fraction;
    pthread_mutex_lock(&sh->lock);
    if (stage >= sh->trigger_stage) sh->running = 1;
    pthread_mutex_unlock(&sh->lock);
    return 0;
}

static void *canceller(void *arg) {
    cancel_shared *sh = (cancel_shared *)arg;
    for (;;) {
        int running, done;
        pthread_mutex_lock(&sh->lock);
        running = sh->running;
        done = sh->done;
        pthread_mutex_unlock(&sh->lock);
        if (done) break;
        if (sh->mode == 1 || running) {
            const double now = scn_now();
            kissm_cancel(sh->m);
            pthread_mutex_lock(&sh->lock);
            if (sh->cancels == 0) sh->cancel_at = now;
            sh->cancels++;
            pthread_mutex_unlock(&sh->lock);
            if (sh->mode != 1) break;
        }
        sleep_ms(0.5);
    }
    return NULL;
}

static void test_cancel_from_thread(void) {
    /* Bigger and bigger clouds until a cancellation is observed in both modes. */
    const double densities[] = {40.0, 80.0, 160.0};
    const double voxels[] = {0.3, 0.25, 0.2};
    int observed[3] = {0, 0, 0};
    size_t k;
    for (k = 0; k < 3 && !(observed[0] && observed[1] && observed[2]); ++k) {
        scn_pair big;
        kissm_points s, t;
        kissm_config c = scn_config(voxels[k]);
        kissm_matcher *m = NULL;
        kissm_result full, r;
        double t0, full_ms;
        cancel_shared sh;
        int mode;
        scn_make_pair(&big, 1, densities[k], 0.01);
        s = scn_points(&big.source);
        t = scn_points(&big.target);
        memset(&sh, 0, sizeof(sh));
        pthread_mutex_init(&sh.lock, NULL);
        sh.trigger_stage = KISSM_STAGE_SOLVER + 1; /* never, during the reference run */
        c.num_threads = 2;
        c.progress_fn = on_progress_running;
        c.progress_user_data = &sh;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        sh.m = m;

        /* the full, uncancelled run: time and reference result */
        scn_result_poison(&full);
        t0 = scn_now();
        CHECK_EQ_INT(kissm_register(m, &s, &t, &full), KISSM_OK);
        full_ms = 1e3 * (scn_now() - t0);
        CHECK_EQ_INT(full.valid, 1);
        fprintf(stderr, "  %lu + %lu points, voxel %.2f: %.1f ms uncancelled\n", (unsigned long)big.source.count,
                (unsigned long)big.target.count, voxels[k], full_ms);

        for (mode = 0; mode < 3; ++mode) {
            pthread_t b;
            int32_t st;
            double returned_at, started_at;
            if (observed[mode]) continue;
            pthread_mutex_lock(&sh.lock);
            sh.trigger_stage = mode == 2 ? KISSM_STAGE_MATCHING : KISSM_STAGE_FEATURES;
            pthread_mutex_unlock(&sh.lock);
            sh.running = sh.done = sh.cancels = 0;
            sh.cancel_at = 0.0;
            sh.mode = mode;
            REQUIRE(pthread_create(&b, NULL, canceller, &sh) == 0);
            scn_result_poison(&r);
            started_at = scn_now();
            st = kissm_register(m, &s, &t, &r);
            returned_at = scn_now();
            pthread_mutex_lock(&sh.lock);
            sh.done = 1;
            pthread_mutex_unlock(&sh.lock);
            pthread_join(b, NULL);

            if (st == KISSM_OK) {
                /* finished before the cancel landed: allowed; the result is the full one */
                CHECK(scn_result_equal(&full, &r));
                fprintf(stderr, "  mode %d: finished before the cancel landed (%.1f ms)\n", mode,
                        1e3 * (returned_at - started_at));
                continue;
            }
            CHECK_MSG(st == KISSM_ERR_CANCELLED, "mode %d: status %d (%s)", mode, (int)st, kissm_last_error_message());
            CHECK(scn_result_is_reset(&r));
            CHECK(sh.cancels > 0);
            observed[mode] = 1;
            {
                const double latency_ms = 1e3 * (returned_at - sh.cancel_at);
                const double call_ms = 1e3 * (returned_at - started_at);
                fprintf(stderr, "  mode %d: cancelled after %.1f ms, %.1f ms after the first kissm_cancel\n", mode,
                        call_ms, latency_ms);
                /* promptly: well before the call would have finished */
                if (mode != 2)
                    CHECK_MSG(call_ms < 0.75 * full_ms + 20.0, "mode %d: took %.1f ms of a %.1f ms call", mode, call_ms,
                              full_ms);
                if (mode != 1)
                    CHECK_MSG(latency_ms < 0.5 * full_ms + 20.0, "cancel latency %.1f ms (full call %.1f ms)",
                              latency_ms, full_ms);
            }
            /* the matcher works again, and gives the same result as before */
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
            CHECK(scn_result_equal(&full, &r));
        }
        kissm_destroy(m);
        pthread_mutex_destroy(&sh.lock);
        scn_pair_free(&big);
    }
    CHECK_MSG(observed[0], "a single kissm_cancel from another thread never stopped a running call");
    CHECK_MSG(observed[1], "repeated kissm_cancel from another thread never stopped a running call");
    CHECK_MSG(observed[2], "kissm_cancel during matching never stopped a running call");
}

/* ---------------------------------------------------------------------------------------------- */
/* Progress and cancellation with refinement                                                       */
/* ---------------------------------------------------------------------------------------------- */

/* Which stages were reported (bit per stage), and whether the last call was (stage, 1.0). */
static int stages_seen(const progress_record *rec) {
    int i, seen = 0;
    for (i = 0; i < rec->calls && i < MAX_EVENTS; ++i) seen |= 1 << rec->stage[i];
    return seen;
}

static int ends_with(const progress_record *rec, int32_t stage) {
    const int n = rec->calls < MAX_EVENTS ? rec->calls : MAX_EVENTS;
    return n > 0 && rec->stage[n - 1] == stage && rec->fraction[n - 1] == 1.0;
}

/* One of the three calls that refine: 0 kissm_register with refine_mode set, 1 kissm_refine,
 * 2 kissm_refine_features. */
static int32_t refine_call(int which, kissm_matcher *m, kissm_features *fs, kissm_features *ft, const double *initial,
                           kissm_result *r) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    scn_result_poison(r);
    if (which == 0) return kissm_register(m, &s, &t, r);
    if (which == 1) return kissm_refine(m, &s, &t, initial, r);
    return kissm_refine_features(m, fs, ft, initial, r);
}

static void test_progress_and_cancel_with_refine(void) {
    static const char *const names[3] = {"register + GICP", "kissm_refine", "kissm_refine_features"};
    /* the stages each call reports: all six; voxelise, features and refine; refine only */
    const int expected_stages[3] = {
        0x7E, (1 << KISSM_STAGE_VOXELIZE) | (1 << KISSM_STAGE_FEATURES) | (1 << KISSM_STAGE_REFINE),
        1 << KISSM_STAGE_REFINE};
    const int32_t first_stage[3] = {KISSM_STAGE_VOXELIZE, KISSM_STAGE_VOXELIZE, KISSM_STAGE_REFINE};
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    progress_record *rec = (progress_record *)calloc(1, sizeof(progress_record));
    kissm_features *fs = NULL, *ft = NULL;
    kissm_result reference[3], r;
    double initial[16];
    int which;
    REQUIRE(rec != NULL);
    scn_pose_to_matrix(&g_pair.truth, initial);
    initial[3] += 0.2; /* a prior 20 cm off: refinement has work to do */
    c.refine_mode = KISSM_REFINE_GICP;
    c.progress_fn = on_progress;
    c.progress_user_data = rec;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);

    for (which = 0; which < 3; ++which) {
        int stage, k;
        memset(rec, 0, sizeof(*rec));
        CHECK_MSG(refine_call(which, m, fs, ft, initial, &reference[which]) == KISSM_OK, "%s: %s", names[which],
                  kissm_last_error_message());
        CHECK_EQ_INT(reference[which].valid, 1);
        CHECK(reference[which].refine_iterations >= 1);
        check_events(names[which], rec, first_stage[which], KISSM_STAGE_REFINE);
        CHECK_MSG(stages_seen(rec) == expected_stages[which], "%s: stages 0x%x", names[which], stages_seen(rec));
        CHECK_MSG(ends_with(rec, KISSM_STAGE_REFINE), "%s: the last progress call is not (REFINE, 1.0)", names[which]);
        if (!ends_with(rec, KISSM_STAGE_REFINE) || stages_seen(rec) != expected_stages[which]) print_events(rec);

        /* cancelled at each stage it reports, on its first progress call, and on its second call at the refine
         * stage (inside the iterations) */
        for (stage = 0; stage <= KISSM_STAGE_REFINE + 1; ++stage) {
            const int in_iterations = stage == KISSM_STAGE_REFINE + 1;
            int asked = -1, i;
            if (stage != 0 && !in_iterations && !(expected_stages[which] & (1 << stage))) continue;
            memset(rec, 0, sizeof(*rec));
            if (stage == 0) {
                rec->cancel_after = 1;
            } else if (!in_iterations) {
                rec->cancel_stage = stage;
            } else {
                /* where that call is, from an uncancelled run of the same call with the same config */
                progress_record *probe = (progress_record *)calloc(1, sizeof(progress_record));
                kissm_matcher *pm = NULL;
                kissm_result pr;
                int seen = 0;
                REQUIRE(probe != NULL);
                c.progress_user_data = probe;
                REQUIRE(kissm_create(&c, &pm) == KISSM_OK);
                c.progress_user_data = rec;
                CHECK_EQ_INT(refine_call(which, pm, fs, ft, initial, &pr), KISSM_OK);
                kissm_destroy(pm);
                for (i = 0; i < probe->calls && i < MAX_EVENTS; ++i)
                    if (probe->stage[i] == KISSM_STAGE_REFINE && ++seen == 2) break;
                free(probe);
                REQUIRE(seen == 2);
                rec->cancel_after = i + 1;
                asked = i;
            }
            CHECK_MSG(refine_call(which, m, fs, ft, initial, &r) == KISSM_ERR_CANCELLED, "%s, cancel at stage %d",
                      names[which], stage);
            CHECK_EQ_INT(rec->cancels_returned, 1);
            CHECK_MSG(scn_result_is_reset(&r), "%s, cancel at stage %d", names[which], stage);
            CHECK(strstr(kissm_last_error_message(), "cancel") != NULL);
            /* stopped promptly: no progress call after the one that asked to stop */
            if (stage == 0) asked = 0;
            for (i = 0; asked < 0 && i < rec->calls && i < MAX_EVENTS; ++i)
                if (rec->stage[i] == stage) asked = i;
            CHECK_MSG(asked >= 0 && rec->calls == asked + 1, "%s, stage %d: %d calls after cancelling", names[which],
                      stage, rec->calls - asked - 1);
            /* the next call gives the reference result */
            memset(rec, 0, sizeof(*rec));
            CHECK_EQ_INT(refine_call(which, m, fs, ft, initial, &r), KISSM_OK);
            CHECK_MSG(scn_result_equal(&reference[which], &r), "%s after a cancel at stage %d", names[which], stage);
        }
        /* a kissm_cancel made between calls does not cancel the next one */
        for (k = 0; k < 2; ++k) kissm_cancel(m);
        memset(rec, 0, sizeof(*rec));
        CHECK_EQ_INT(refine_call(which, m, fs, ft, initial, &r), KISSM_OK);
        CHECK(scn_result_equal(&reference[which], &r));
    }
    /* the callback changes nothing: the same calls without it */
    {
        kissm_config q = scn_config(VOXEL);
        kissm_matcher *qm = NULL;
        q.refine_mode = KISSM_REFINE_GICP;
        REQUIRE(kissm_create(&q, &qm) == KISSM_OK);
        for (which = 0; which < 3; ++which) {
            CHECK_EQ_INT(refine_call(which, qm, fs, ft, initial, &r), KISSM_OK);
            CHECK_MSG(scn_result_equal(&reference[which], &r), "%s without a callback", names[which]);
        }
        kissm_destroy(qm);
    }
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_destroy(m);
    free(rec);
}

int main(void) {
    g_main_thread = pthread_self();
    scn_make_pair(&g_pair, 9, 15.0, 0.01);
    RUN_TEST(test_log);
    RUN_TEST(test_progress);
    RUN_TEST(test_progress_and_cancel_with_refine);
    RUN_TEST(test_cancel_idle);
    RUN_TEST(test_cancel_from_thread);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
