/* SPDX-License-Identifier: MIT */
/* The library never writes to stdout or stderr: file descriptors 1 and 2 are pointed at a temporary file
 * while good calls, failing calls and multi-threaded calls run (no log callback set), and the file must
 * stay empty. POSIX (dup2). C99. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "capi/scenes.h"
#include "harness.h"
#include "kissm.h"

static void exercise(const scn_pair *pair) {
    kissm_config c = scn_config(0.5), bad = scn_config(-1.0);
    kissm_matcher *m = NULL, *m2 = NULL;
    kissm_points s = scn_points(&pair->source), t = scn_points(&pair->target), nothing = s;
    kissm_features *f = NULL;
    kissm_cloud *cloud = NULL;
    kissm_result r;
    r.struct_size = sizeof r;
    nothing.count = 0;
    (void)kissm_create(&bad, &m);   /* invalid config */
    (void)kissm_create(&bad, NULL); /* NULL output */
    c.num_threads = 4;
    if (kissm_create(&c, &m) != KISSM_OK) return;
    (void)kissm_register(m, &s, &t, &r);       /* good, 4 threads */
    (void)kissm_register(m, &nothing, &t, &r); /* empty */
    (void)kissm_register(m, &s, &t, NULL);     /* NULL result */
    r.struct_size = 3;
    (void)kissm_register(m, &s, &t, &r); /* bad struct size */
    r.struct_size = sizeof r;
    ((double *)pair->source.xyz)[7] = NAN;
    (void)kissm_register(m, &s, &t, &r); /* non-finite */
    (void)kissm_features_compute(m, &t, &f);
    c.voxel_size = 0.7;
    if (kissm_create(&c, &m2) == KISSM_OK) {
        kissm_features *g = NULL;
        (void)kissm_features_compute(m2, &t, &g);
        (void)kissm_register_features(m, f, g, &r); /* features mismatch */
        kissm_features_destroy(g);
    }
    /* refinement: good (4 threads, from the truth), registered with refinement, a transform that is not
     * rigid, a prior far off, from features (one of another voxel size: a mismatch) */
    {
        kissm_config rc = scn_config(0.5);
        kissm_matcher *rm = NULL;
        double initial[16];
        scn_pose_to_matrix(&pair->truth, initial);
        ((double *)pair->source.xyz)[7] = 1.0;
        rc.num_threads = 4;
        rc.refine_mode = KISSM_REFINE_GICP;
        if (kissm_create(&rc, &rm) == KISSM_OK) {
            kissm_features *g = NULL;
            (void)kissm_refine(rm, &s, &t, initial, &r);
            (void)kissm_register(rm, &s, &t, &r);
            (void)kissm_refine(rm, &s, &t, NULL, &r);
            initial[15] = 2.0;
            (void)kissm_refine(rm, &s, &t, initial, &r);
            initial[15] = 1.0;
            initial[3] += 1e4;
            (void)kissm_refine(rm, &s, &t, initial, &r);
            initial[3] -= 1e4;
            if (kissm_features_compute(rm, &t, &g) == KISSM_OK) {
                (void)kissm_refine_features(rm, g, g, initial, &r);
                (void)kissm_refine_features(m, f, g, initial, &r); /* features mismatch */
            }
            kissm_features_destroy(g);
        }
        kissm_destroy(rm);
    }
    (void)kissm_read_points("/nonexistent/kissm/cloud.ply", KISSM_FORMAT_AUTO, &cloud); /* I/O error */
    (void)kissm_read_points("/dev/null", KISSM_FORMAT_PLY, &cloud);                     /* parse error */
    kissm_cancel(m);
    kissm_features_destroy(f);
    kissm_destroy(m2);
    kissm_destroy(m);
}

static void test_nothing_printed(void) {
    scn_pair pair;
    FILE *capture = tmpfile();
    int saved_out, saved_err;
    long written;
    REQUIRE(capture != NULL);
    scn_make_pair(&pair, 23, 4.0, 0.01);
    fflush(NULL);
    saved_out = dup(1), saved_err = dup(2);
    REQUIRE(saved_out >= 0 && saved_err >= 0);
    REQUIRE(dup2(fileno(capture), 1) >= 0 && dup2(fileno(capture), 2) >= 0);
    exercise(&pair);
    fflush(NULL);
    dup2(saved_out, 1), dup2(saved_err, 2);
    close(saved_out), close(saved_err);
    fseek(capture, 0, SEEK_END);
    written = ftell(capture);
    CHECK_MSG(written == 0, "the library wrote %ld bytes to stdout/stderr", written);
    fclose(capture);
    scn_pair_free(&pair);
}

int main(void) {
    RUN_TEST(test_nothing_printed);
    return TEST_SUMMARY();
}
