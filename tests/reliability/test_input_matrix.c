/* SPDX-License-Identifier: MIT */
/* The input-validation matrix: every entry point that takes a cloud (kissm_register and kissm_refine as source
 * and as target, kissm_features_compute, kissm_register_features, kissm_refine_features) x cloud contents (NULL, empty,
 * 1-3 points, NaN, Inf, duplicates, collinear, planar, 1e7 m extents, a scene 1e7 m from the origin) x voxel sizes
 * (1e-9, 0.5, 1e9). Every cell must return the status the documentation gives for that combination, or KISSM_OK with
 * valid = 0 and a reason, and the handle must give the identical result on a good pair afterwards.
 * Bad configs (voxel 0, negative, NaN, absurd fields) and wrong struct sizes are covered cell by cell in
 * tests/capi/test_capi_bad_input.c. C99. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "capi/scenes.h"
#include "harness.h"
#include "kissm.h"

enum content {
    C_NULL,
    C_EMPTY,
    C_ONE,
    C_TWO,
    C_THREE,
    C_NAN,
    C_INF,
    C_DUPLICATES,
    C_COLLINEAR,
    C_PLANAR,
    C_HUGE_EXTENT,
    C_FAR_SCENE,
    C_COUNT
};
static const char *const k_content_names[C_COUNT] = {"NULL",      "empty",  "1 point",      "2 points",
                                                     "3 points",  "a NaN",  "an Inf",       "5000 duplicates",
                                                     "collinear", "planar", "1e7 m extent", "scene 1e7 m away"};

enum voxel { V_TINY, V_GOOD, V_HUGE, V_COUNT };
static const double k_voxels[V_COUNT] = {1e-9, 0.5, 1e9};

/* What a cell may return: one status, or OK with any validity (only where a real registration may work). */
#define ANY_VALIDITY 1
typedef struct outcome {
    int32_t status;
    int32_t reason; /* for status OK: the reason required when invalid; -1 = any non-zero reason */
    int may_be_valid;
} outcome;

enum role { R_SOURCE, R_TARGET, R_FEATURES };

/* The documented order of checks: arguments (NULL, counts) at the boundary; then the source is read
 * (non-finite points) and voxelised (voxel range), then the target; then the pipeline's reasons. The other
 * cloud of a registration is the good scene, which itself is out of range at 1e-9 m voxels. */
static outcome expected(enum content c, enum voxel v, enum role role) {
    outcome o = {KISSM_OK, -1, 0};
    switch (c) {
    case C_NULL: o.status = KISSM_ERR_NULL_ARGUMENT; return o;
    case C_EMPTY: o.status = KISSM_ERR_EMPTY_INPUT; return o;
    case C_ONE:
    case C_TWO:
    case C_THREE: o.status = KISSM_ERR_TOO_FEW_POINTS; return o;
    default: break;
    }
    if (v == V_TINY && role == R_TARGET) { /* the good source fails first */
        o.status = KISSM_ERR_VOXEL_RANGE;
        return o;
    }
    if (c == C_NAN || c == C_INF) {
        o.status = KISSM_ERR_NONFINITE;
        return o;
    }
    if (c == C_DUPLICATES) {                                                   /* zero extent: one voxel at any size */
        if (v == V_TINY && role == R_SOURCE) o.status = KISSM_ERR_VOXEL_RANGE; /* the good target's turn */
        o.reason = KISSM_REASON_TOO_FEW_VOXELS;
        return o;
    }
    if (v == V_HUGE) {
        o.reason = KISSM_REASON_TOO_FEW_VOXELS; /* everything falls into one voxel */
        return o;
    }
    if (v == V_TINY || c == C_HUGE_EXTENT) { /* more than 2^21 voxels along an axis */
        o.status = KISSM_ERR_VOXEL_RANGE;
        return o;
    }
    if (c == C_FAR_SCENE) o.may_be_valid = ANY_VALIDITY; /* the same scene: it may register */
    return o;
}

/* kissm_refine (from the good pair's true pose) and kissm_refine_features check and voxelise as kissm_register
 * does, so their statuses are the same; then refinement judges the pose: clouds without normals (duplicates,
 * a line, one huge voxel) or out of reach (1e7 m away) give nothing to match, LOW_OVERLAP; a plane against
 * the scene is never valid (LOW_OVERLAP or UNCONSTRAINED); nothing here may be valid. */
static outcome expected_refine(enum content c, enum voxel v, enum role role) {
    outcome o = expected(c, v, role);
    if (o.status != KISSM_OK) return o;
    o.may_be_valid = 0;
    o.reason = c == C_PLANAR ? -1 : KISSM_REASON_LOW_OVERLAP;
    return o;
}

static scn_pair g_pair;
static scn_cloud g_clouds[C_COUNT];
static double g_truth[16];

static void make_contents(void) {
    int i;
    for (i = 0; i < C_COUNT; ++i) scn_cloud_init(&g_clouds[i]);
    scn_cloud_push(&g_clouds[C_ONE], 1, 2, 3);
    scn_cloud_push(&g_clouds[C_TWO], 1, 2, 3), scn_cloud_push(&g_clouds[C_TWO], 4, 5, 6);
    scn_cloud_copy(&g_clouds[C_THREE], &g_clouds[C_TWO]), scn_cloud_push(&g_clouds[C_THREE], -1, 0, 2);
    scn_cloud_copy(&g_clouds[C_NAN], &g_pair.source);
    g_clouds[C_NAN].xyz[3 * 100 + 1] = NAN;
    scn_cloud_copy(&g_clouds[C_INF], &g_pair.source);
    g_clouds[C_INF].xyz[3 * 200 + 2] = -INFINITY;
    scn_make_duplicates(&g_clouds[C_DUPLICATES], 5000, 3.0, -2.0, 1.0);
    scn_make_line(&g_clouds[C_COLLINEAR], 5, 4000, 0.003);
    scn_make_plane(&g_clouds[C_PLANAR], 6, 8000, 0.01);
    {
        const double c[3] = {0, 0, 0};
        scn_make_blob(&g_clouds[C_HUGE_EXTENT], 7, 2000, c, 5e6);
    }
    scn_cloud_copy(&g_clouds[C_FAR_SCENE], &g_pair.source);
    scn_cloud_translate(&g_clouds[C_FAR_SCENE], 1e7, -1e7, 30.0);
}

static kissm_points view(enum content c) {
    kissm_points p = scn_points(&g_clouds[c]);
    if (c == C_NULL) p.data = NULL, p.count = 100;
    return p;
}

/* The handle still works: the good pair gives exactly the reference results (or the reference statuses) of
 * kissm_register and kissm_refine. */
static int usable(kissm_matcher *m, const int32_t ref_status[2], const kissm_result ref[2]) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_result r;
    int32_t st;
    int ok;
    scn_result_poison(&r);
    st = kissm_register(m, &s, &t, &r);
    ok = st == ref_status[0] && (st != KISSM_OK || scn_result_equal(&ref[0], &r));
    scn_result_poison(&r);
    st = kissm_refine(m, &s, &t, g_truth, &r);
    return ok && st == ref_status[1] && (st != KISSM_OK || scn_result_equal(&ref[1], &r));
}

static int cell_ok(const char *where, enum role role, enum content c, enum voxel v, int refine, int32_t st,
                   const kissm_result *r) {
    const outcome o = refine ? expected_refine(c, v, role) : expected(c, v, role);
    if (st != o.status) {
        fprintf(stderr, "  %s, %s, voxel %g: status %d, expected %d (%s)\n", where, k_content_names[c], k_voxels[v],
                (int)st, (int)o.status, kissm_last_error_message());
        return 0;
    }
    if (r == NULL || st != KISSM_OK) return r == NULL || (r->valid == 0 && r->reason == KISSM_REASON_NONE);
    if (r->valid) {
        if (o.may_be_valid) return 1;
        fprintf(stderr, "  %s, %s, voxel %g: reported valid\n", where, k_content_names[c], k_voxels[v]);
        return 0;
    }
    if (r->reason == KISSM_REASON_NONE || (o.reason >= 0 && r->reason != o.reason)) {
        fprintf(stderr, "  %s, %s, voxel %g: invalid with reason %d, expected %d\n", where, k_content_names[c],
                k_voxels[v], (int)r->reason, (int)o.reason);
        return 0;
    }
    return 1;
}

/* The matrix under one viewpoint mode (the frame-free modes read offsets between points only, so the far and
 * huge clouds meet other arithmetic there). */
static void run_matrix(int32_t viewpoint_mode) {
    int v, c, cells = 0, good_cells = 0, still_usable = 0;
    for (v = 0; v < V_COUNT; ++v) {
        kissm_config config = scn_config(k_voxels[v]);
        config.viewpoint_mode = viewpoint_mode;
        kissm_matcher *m = NULL;
        const kissm_points good_s = scn_points(&g_pair.source), good_t = scn_points(&g_pair.target);
        kissm_features *good_f = NULL;
        kissm_result ref[2];
        int32_t ref_status[2];
        REQUIRE(kissm_create(&config, &m) == KISSM_OK);
        scn_result_poison(&ref[0]);
        ref_status[0] = kissm_register(m, &good_s, &good_t, &ref[0]);
        scn_result_poison(&ref[1]);
        ref_status[1] = kissm_refine(m, &good_s, &good_t, g_truth, &ref[1]);
        if (v == V_GOOD) CHECK(ref_status[0] == KISSM_OK && ref[0].valid == 1); /* the good pair is good */
        if (v == V_GOOD) CHECK(ref_status[1] == KISSM_OK && ref[1].valid == 1);
        if (kissm_features_compute(m, &good_t, &good_f) != KISSM_OK) good_f = NULL;
        for (c = 0; c < C_COUNT; ++c) {
            const kissm_points p = view((enum content)c);
            kissm_result r;
            kissm_features *f = NULL;
            int32_t st;
            int ok = 1;

            scn_result_poison(&r);
            st = kissm_register(m, &p, &good_t, &r);
            ok &= cell_ok("source", R_SOURCE, (enum content)c, (enum voxel)v, 0, st, &r);
            scn_result_poison(&r);
            st = kissm_register(m, &good_s, &p, &r);
            ok &= cell_ok("target", R_TARGET, (enum content)c, (enum voxel)v, 0, st, &r);
            scn_result_poison(&r);
            st = kissm_refine(m, &p, &good_t, g_truth, &r);
            ok &= cell_ok("refine source", R_SOURCE, (enum content)c, (enum voxel)v, 1, st, &r);
            scn_result_poison(&r);
            st = kissm_refine(m, &good_s, &p, g_truth, &r);
            ok &= cell_ok("refine target", R_TARGET, (enum content)c, (enum voxel)v, 1, st, &r);
            st = kissm_features_compute(m, &p, &f);
            ok &= cell_ok("features", R_FEATURES, (enum content)c, (enum voxel)v, 0, st, NULL);
            ok &= (st == KISSM_OK) == (f != NULL);
            if (f != NULL && good_f != NULL) { /* from features: same rules as the direct calls */
                scn_result_poison(&r);
                st = kissm_register_features(m, f, good_f, &r);
                ok &= cell_ok("source features", R_SOURCE, (enum content)c, (enum voxel)v, 0, st, &r);
                scn_result_poison(&r);
                st = kissm_refine_features(m, f, good_f, g_truth, &r);
                ok &= cell_ok("refine source features", R_SOURCE, (enum content)c, (enum voxel)v, 1, st, &r);
            }
            kissm_features_destroy(f);
            cells++;
            good_cells += ok;
            if (usable(m, ref_status, ref))
                still_usable++;
            else
                fprintf(stderr, "  after %s at voxel %g the handle changed\n", k_content_names[c], k_voxels[v]);
        }
        kissm_features_destroy(good_f);
        kissm_destroy(m);
    }
    CHECK_EQ_INT(cells, C_COUNT * V_COUNT);
    CHECK_MSG(good_cells == cells, "viewpoint mode %d: %d of %d cells as documented", (int)viewpoint_mode, good_cells,
              cells);
    CHECK_EQ_INT(still_usable, cells);
}

static void test_matrix(void) {
    const int32_t modes[] = {KISSM_VIEWPOINT_FIXED, KISSM_VIEWPOINT_CLOUD_CENTER, KISSM_VIEWPOINT_SIGN_FREE,
                             KISSM_VIEWPOINT_LOCAL};
    size_t i;
    for (i = 0; i < sizeof modes / sizeof modes[0]; ++i) run_matrix(modes[i]);
}

int main(void) {
    int i;
    scn_make_pair(&g_pair, 11, 6.0, 0.01);
    scn_pose_to_matrix(&g_pair.truth, g_truth);
    make_contents();
    RUN_TEST(test_matrix);
    for (i = 0; i < C_COUNT; ++i) scn_cloud_free(&g_clouds[i]);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
