/* SPDX-License-Identifier: MIT */
/* kissm_register on a synthetic scene moved by a large known transform: accuracy, result consistency,
 * input representations (float32, float64, strided), georeferenced coordinates and the inverse pair; with the
 * default refine_mode the refinement's fields read "not run" (refinement itself: test_capi_refine.c). C99. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.4

static scn_pair g_pair;

static double det3(const double R[9]) {
    return R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
}

static void check_accuracy(const char *label, const kissm_result *r, const scn_pose *truth, double voxel) {
    const double rot_err = scn_rotation_error_deg(r->rotation, truth->R);
    const double trans_err = scn_translation_error(r->translation, truth->t);
    CHECK_MSG(r->valid == 1, "%s: valid %d reason %d", label, (int)r->valid, (int)r->reason);
    CHECK_MSG(rot_err < 2.0, "%s: rotation error %.3f deg", label, rot_err);
    CHECK_MSG(trans_err < 2.0 * voxel, "%s: translation error %.4f m", label, trans_err);
    if (!(r->valid == 1 && rot_err < 2.0 && trans_err < 2.0 * voxel)) scn_result_print(label, r);
}

/* Everything that must hold for any valid result (registered at voxel size voxel). */
static void check_consistency(const char *label, const kissm_result *r, double voxel) {
    int i, j, k;
    double sum;
    /* R orthonormal with det +1 */
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double dot = 0.0;
            for (k = 0; k < 3; ++k) dot += r->rotation[3 * i + k] * r->rotation[3 * j + k];
            CHECK_MSG(fabs(dot - (i == j ? 1.0 : 0.0)) < 1e-9, "%s: R R^T (%d,%d) = %.17g", label, i, j, dot);
        }
    CHECK_MSG(fabs(det3(r->rotation) - 1.0) < 1e-9, "%s: det %.17g", label, det3(r->rotation));
    /* transform = [R t; 0 0 0 1] exactly */
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) CHECK(r->transform[4 * i + j] == r->rotation[3 * i + j]);
        CHECK(r->transform[4 * i + 3] == r->translation[i]);
    }
    CHECK(r->transform[12] == 0.0 && r->transform[13] == 0.0 && r->transform[14] == 0.0 && r->transform[15] == 1.0);
    CHECK_EQ_INT(r->reason, KISSM_REASON_NONE);
    CHECK_EQ_INT(r->reserved0, 0);
    /* counts are monotone along the pipeline */
    CHECK(r->num_source_nonfinite <= r->num_source_points);
    CHECK(r->num_source_voxels <= r->num_source_points - r->num_source_nonfinite);
    CHECK(r->num_target_voxels <= r->num_target_points - r->num_target_nonfinite);
    CHECK(r->num_source_keypoints <= r->num_source_voxels);
    CHECK(r->num_target_keypoints <= r->num_target_voxels);
    CHECK(r->num_initial_correspondences <= r->num_source_keypoints);
    CHECK(r->num_initial_correspondences <= r->num_target_keypoints);
    CHECK(r->num_pruned_correspondences <= r->num_initial_correspondences);
    CHECK(r->num_rotation_inliers <= r->num_pruned_correspondences);
    CHECK(r->num_final_inliers <= r->num_pruned_correspondences);
    CHECK(r->max_core_number < r->num_pruned_correspondences);
    CHECK(r->num_final_inliers >= (uint64_t)scn_config(VOXEL).min_inliers); /* valid needs min_inliers */
    CHECK(r->num_source_voxels > 100 && r->num_target_voxels > 100);
    CHECK_NEAR(r->inlier_ratio, (double)r->num_final_inliers / (double)r->num_initial_correspondences, 1e-12);
    CHECK(r->residual_rms >= 0.0 && r->residual_rms <= r->noise_bound);
    CHECK(r->noise_bound > 0.0);
    CHECK(r->inlier_extent[0] >= r->inlier_extent[1] && r->inlier_extent[1] >= r->inlier_extent[2] &&
          r->inlier_extent[2] > 0.0);
    /* a scene with one answer, registered right: no competitor near the pose's support, and a confidence that a
     * loop closure could take (the documented threshold 0.95) */
    CHECK_MSG(r->ambiguity >= 0.0 && r->ambiguity < 0.5, "%s: ambiguity %g", label, r->ambiguity);
    CHECK_MSG(r->confidence >= 0.95 && r->confidence <= 1.0, "%s: confidence %g", label, r->confidence);
    /* times: non-negative, total = sum of the stages (refinement's is 0 when it did not run) */
    CHECK(r->time_voxelize_ms >= 0.0 && r->time_features_ms >= 0.0 && r->time_matching_ms >= 0.0 &&
          r->time_pruning_ms >= 0.0 && r->time_solver_ms >= 0.0 && r->time_refine_ms >= 0.0);
    sum = r->time_voxelize_ms + r->time_features_ms + r->time_matching_ms + r->time_pruning_ms + r->time_solver_ms +
          r->time_refine_ms;
    CHECK_MSG(fabs(r->time_total_ms - sum) <= 1e-9 * (sum > 1.0 ? sum : 1.0), "%s: total %.17g sum %.17g", label,
              r->time_total_ms, sum);
    CHECK(r->time_total_ms > 0.0);
    /* No refinement asked for (refine_mode defaults to NONE). A pose whose rotation the inliers pin down to
     * max_rotation_uncertainty at one sigma but not at two is confirmed by refinement (validity.hpp,
     * kCoarseConfirmSigmas): reported refined, with the refined confidence (confidence.hpp) */
    if (!(2.0 * r->rotation_uncertainty <= scn_config(VOXEL).max_rotation_uncertainty)) {
        CHECK_MSG(r->refine_iterations > 0 && r->time_refine_ms > 0.0, "%s: not confirmed by refinement", label);
        for (i = 0; i < 36; ++i) CHECK(isfinite(r->information[i]));
        CHECK(r->overlap > 0.0 && r->refine_rmse > 0.0 && r->num_refine_correspondences > 0);
        CHECK_NEAR(r->confidence,
                   1.0 / (1.0 + exp(-(-5.656 + 1.76257 * log1p((double)r->num_final_inliers) + 8.02222 * r->overlap -
                                      4.89573 * fmin(r->refine_rmse / voxel, 10.0)))),
                   1e-12);
        return;
    }
    /* otherwise the solver's pose is the pose, the refinement's fields say "not run", and the confidence is the
     * documented function of the inliers (an ambiguity below 0.6 leaves it whole) */
    CHECK_NEAR(r->confidence, 1.0 / (1.0 + exp(-(-3.93451 + 2.65136 * log1p((double)r->num_final_inliers)))), 1e-12);
    CHECK(memcmp(r->coarse_transform, r->transform, sizeof(r->transform)) == 0);
    for (i = 0; i < 36; ++i) CHECK(isnan(r->information[i]));
    CHECK(isnan(r->overlap) && isnan(r->refine_rmse) && isnan(r->refine_condition));
    CHECK(r->time_refine_ms == 0.0);
    CHECK_EQ_INT(r->num_refine_correspondences, 0);
    CHECK_EQ_INT(r->refine_iterations, 0);
    CHECK_EQ_INT(r->refine_converged, 0);
}

static void register_pair(kissm_matcher *m, const kissm_points *s, const kissm_points *t, kissm_result *r) {
    int32_t st;
    scn_result_poison(r);
    st = kissm_register(m, s, t, r);
    CHECK_MSG(st == KISSM_OK, "status %d: %s", (int)st, kissm_last_error_message());
    CHECK(scn_result_poison_left(r) == 0);
}

static void test_register_float64(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_result r;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    register_pair(m, &s, &t, &r);
    check_accuracy("float64", &r, &g_pair.truth, VOXEL);
    check_consistency("float64", &r, VOXEL);
    CHECK_EQ_INT(r.num_source_points, g_pair.source.count);
    CHECK_EQ_INT(r.num_target_points, g_pair.target.count);
    CHECK_EQ_INT(r.num_source_nonfinite, 0);
    CHECK_EQ_INT(r.num_target_nonfinite, 0);
    CHECK_NEAR(r.noise_bound, 0.75 * VOXEL, 1e-12); /* solver_noise_bound_gain * voxel, uncapped */
    kissm_destroy(m);
}

static void test_register_float32(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    float *s32 = scn_cloud_to_float(&g_pair.source), *t32 = scn_cloud_to_float(&g_pair.target);
    kissm_points s = scn_points_f32(s32, g_pair.source.count), t = scn_points_f32(t32, g_pair.target.count);
    kissm_points s64 = scn_points(&g_pair.source);
    kissm_result r;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    register_pair(m, &s, &t, &r);
    check_accuracy("float32", &r, &g_pair.truth, VOXEL);
    check_consistency("float32", &r, VOXEL);
    /* mixed: float64 source, float32 target */
    register_pair(m, &s64, &t, &r);
    check_accuracy("float64/float32", &r, &g_pair.truth, VOXEL);
    check_consistency("float64/float32", &r, VOXEL);
    kissm_destroy(m);
    free(s32);
    free(t32);
}

/* Points inside a struct of five doubles (stride 40) give bitwise the result of packed input. */
typedef struct padded_point {
    double intensity;
    double xyz[3];
    double ring;
} padded_point;

static void test_strided(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    const size_t ns = g_pair.source.count, nt = g_pair.target.count;
    padded_point *ps = (padded_point *)malloc(ns * sizeof(padded_point));
    padded_point *pt = (padded_point *)malloc(nt * sizeof(padded_point));
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target), ss, st;
    kissm_result packed, strided, mixed;
    size_t i;
    REQUIRE(ps != NULL && pt != NULL);
    REQUIRE(sizeof(padded_point) == 40);
    for (i = 0; i < ns; ++i) {
        ps[i].intensity = NAN; /* must never be read as a coordinate */
        memcpy(ps[i].xyz, g_pair.source.xyz + 3 * i, 3 * sizeof(double));
        ps[i].ring = INFINITY;
    }
    for (i = 0; i < nt; ++i) {
        pt[i].intensity = -INFINITY;
        memcpy(pt[i].xyz, g_pair.target.xyz + 3 * i, 3 * sizeof(double));
        pt[i].ring = NAN;
    }
    ss = s;
    ss.data = ps[0].xyz;
    ss.stride_bytes = sizeof(padded_point);
    st = t;
    st.data = pt[0].xyz;
    st.stride_bytes = sizeof(padded_point);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    register_pair(m, &s, &t, &packed);
    register_pair(m, &ss, &st, &strided);
    register_pair(m, &s, &st, &mixed);
    CHECK(packed.valid == 1);
    CHECK(scn_result_equal(&packed, &strided));
    CHECK(scn_result_equal(&packed, &mixed));
    CHECK_EQ_INT(strided.num_source_nonfinite, 0);

    /* float32 strided (x y z intensity, 16 bytes) equals float32 packed */
    {
        float *s32 = scn_cloud_to_float(&g_pair.source);
        float *s32i = (float *)malloc(ns * 4 * sizeof(float));
        kissm_points p32 = scn_points_f32(s32, ns), p32i;
        kissm_result a, b;
        REQUIRE(s32i != NULL);
        for (i = 0; i < ns; ++i) {
            memcpy(s32i + 4 * i, s32 + 3 * i, 3 * sizeof(float));
            s32i[4 * i + 3] = NAN;
        }
        p32i = scn_points_f32(s32i, ns);
        p32i.stride_bytes = 16;
        register_pair(m, &p32, &t, &a);
        register_pair(m, &p32i, &t, &b);
        CHECK(a.valid == 1);
        CHECK(scn_result_equal(&a, &b));
        free(s32);
        free(s32i);
    }
    kissm_destroy(m);
    free(ps);
    free(pt);
}

/* Both clouds shifted by georeferenced offsets, float64, CLOUD_CENTER viewpoints: the same relative pose.
 * The clouds are first snapped to a 2^-20 m grid so that the shifted coordinates are exact: the
 * recentred clouds the library sees are then identical and only its own arithmetic can differ. */
static void test_georeferenced_shift(void) {
    const double shift[3] = {1e7, 1e7 - 12345.0, 250.0};
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    scn_cloud s0, t0, s1, t1;
    kissm_points p;
    kissm_result base, shifted, fixed_vp;
    double expected_t[3];
    int i;
    scn_shifted_copies(&g_pair.source, &g_pair.target, shift, &s0, &t0, &s1, &t1);

    c.viewpoint_mode = KISSM_VIEWPOINT_CLOUD_CENTER;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    {
        kissm_points a = scn_points(&s0), b = scn_points(&t0);
        register_pair(m, &a, &b, &base);
    }
    {
        kissm_points a = scn_points(&s1), b = scn_points(&t1);
        register_pair(m, &a, &b, &shifted);
    }
    check_accuracy("unshifted, cloud-centre viewpoint", &base, &g_pair.truth, VOXEL);
    check_consistency("unshifted", &base, VOXEL);
    check_consistency("shifted", &shifted, VOXEL);
    CHECK_EQ_INT(shifted.valid, 1);
    /* The same rotation... */
    CHECK_MSG(scn_rotation_error_deg(base.rotation, shifted.rotation) * 3.14159265358979 / 180.0 < 1e-6,
              "rotation differs by %.3g deg", scn_rotation_error_deg(base.rotation, shifted.rotation));
    for (i = 0; i < 9; ++i) CHECK_NEAR(base.rotation[i], shifted.rotation[i], 1e-6);
    /* ...and t' = t + s - R s (p_t + s = R (p_s + s - s) + t + s). */
    for (i = 0; i < 3; ++i)
        expected_t[i] = base.translation[i] + shift[i] -
                        (shifted.rotation[3 * i + 0] * shift[0] + shifted.rotation[3 * i + 1] * shift[1] +
                         shifted.rotation[3 * i + 2] * shift[2]);
    CHECK_MSG(scn_translation_error(expected_t, shifted.translation) < 1e-4, "shifted translation off by %.3g m",
              scn_translation_error(expected_t, shifted.translation));
    /* The counts of the two runs are the same: no point was lost or merged differently. */
    CHECK_EQ_INT(base.num_source_voxels, shifted.num_source_voxels);
    CHECK_EQ_INT(base.num_target_voxels, shifted.num_target_voxels);
    CHECK_EQ_INT(base.num_source_keypoints, shifted.num_source_keypoints);
    CHECK_EQ_INT(base.num_initial_correspondences, shifted.num_initial_correspondences);
    CHECK_EQ_INT(base.num_final_inliers, shifted.num_final_inliers);
    CHECK_NEAR(base.residual_rms, shifted.residual_rms, 1e-6);
    /* A shifted point maps where the unshifted one does (up to the shift). */
    {
        double q[3], q_base[3], q_shift[3];
        const double *x = s0.xyz + 3 * (s0.count / 3);
        scn_pose pb, ps;
        memcpy(pb.R, base.rotation, sizeof(pb.R));
        memcpy(pb.t, base.translation, sizeof(pb.t));
        memcpy(ps.R, shifted.rotation, sizeof(ps.R));
        memcpy(ps.t, shifted.translation, sizeof(ps.t));
        scn_pose_apply_point(&pb, x, q_base);
        for (i = 0; i < 3; ++i) q[i] = x[i] + shift[i];
        scn_pose_apply_point(&ps, q, q_shift);
        for (i = 0; i < 3; ++i) CHECK_NEAR(q_shift[i] - shift[i], q_base[i], 1e-4);
    }
    kissm_destroy(m);

    /* The default (fixed viewpoint) config on the unshifted pair is also accurate. */
    c.viewpoint_mode = KISSM_VIEWPOINT_FIXED;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    p = scn_points(&s0);
    {
        kissm_points b = scn_points(&t0);
        register_pair(m, &p, &b, &fixed_vp);
    }
    check_accuracy("unshifted, fixed viewpoint", &fixed_vp, &g_pair.truth, VOXEL);
    kissm_destroy(m);

    scn_cloud_free(&s0);
    scn_cloud_free(&t0);
    scn_cloud_free(&s1);
    scn_cloud_free(&t1);
}

/* Swapping source and target gives (approximately) the inverse transform. */
static void test_swapped(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_result fwd, bwd;
    scn_pose inv_truth, f, b, fb;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    register_pair(m, &s, &t, &fwd);
    register_pair(m, &t, &s, &bwd);
    scn_pose_inverse(&g_pair.truth, &inv_truth);
    check_accuracy("swapped", &bwd, &inv_truth, VOXEL);
    check_consistency("swapped", &bwd, VOXEL);
    CHECK_EQ_INT(bwd.num_source_points, fwd.num_target_points);
    CHECK_EQ_INT(bwd.num_source_voxels, fwd.num_target_voxels);
    CHECK_EQ_INT(bwd.num_target_keypoints, fwd.num_source_keypoints);
    /* fwd o bwd is close to the identity */
    memcpy(f.R, fwd.rotation, sizeof(f.R));
    memcpy(f.t, fwd.translation, sizeof(f.t));
    memcpy(b.R, bwd.rotation, sizeof(b.R));
    memcpy(b.t, bwd.translation, sizeof(b.t));
    scn_pose_compose(&f, &b, &fb);
    {
        const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zero[3] = {0, 0, 0};
        CHECK_MSG(scn_rotation_error_deg(fb.R, I) < 2.0, "fwd o bwd rotation %.3f deg",
                  scn_rotation_error_deg(fb.R, I));
        CHECK_MSG(scn_translation_error(fb.t, zero) < 2.0 * VOXEL, "fwd o bwd translation %.3f m",
                  scn_translation_error(fb.t, zero));
    }
    kissm_destroy(m);
}

/* Other scenes, registered by one reused matcher: a second layout as scanned (fixed viewpoints at the
 * sensors), and the same target moved again into an arbitrary frame, where the sensor is no longer at the
 * origin, so the normals are oriented with KISSM_VIEWPOINT_CLOUD_CENTER. */
static void test_other_scene(void) {
    kissm_config c = scn_config(0.5);
    kissm_matcher *m = NULL;
    scn_pair p;
    const double axis[3] = {-0.2, 0.1, 1.0}, t[3] = {-3.0, 7.5, 0.4};
    scn_pose extra, truth;
    kissm_points s, tt;
    kissm_result r;
    scn_make_pair(&p, 23, 15.0, 0.015);
    s = scn_points(&p.source);
    tt = scn_points(&p.target);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    register_pair(m, &s, &tt, &r);
    check_accuracy("scene 23", &r, &p.truth, 0.5);
    check_consistency("scene 23", &r, 0.5);
    kissm_destroy(m);

    /* truth = extra o p.truth */
    scn_pose_axis_angle(&extra, axis, -2.5, t);
    scn_cloud_apply(&p.target, &extra);
    scn_pose_compose(&extra, &p.truth, &truth);
    c.viewpoint_mode = KISSM_VIEWPOINT_CLOUD_CENTER;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    register_pair(m, &s, &tt, &r);
    check_accuracy("scene 23 moved", &r, &truth, 0.5);
    check_consistency("scene 23 moved", &r, 0.5);
    register_pair(m, &s, &tt, &r);
    check_accuracy("scene 23 moved, again", &r, &truth, 0.5);
    kissm_destroy(m);
    scn_pair_free(&p);
}

/* The viewpoint-free modes: each cloud in a frame of its own, far from its sensor and turned, registers as in
 * the sensor frames; and both clouds shifted by exact georeferenced offsets give bitwise the same rotation and
 * counts (the recentred clouds are identical, and nothing else reads the frame). */
static void test_frame_free_modes(void) {
    const int32_t modes[2] = {KISSM_VIEWPOINT_SIGN_FREE, KISSM_VIEWPOINT_LOCAL};
    const double axis_s[3] = {0.7, -0.2, 0.4}, move_s[3] = {45.0, -60.0, 12.0};
    const double axis_t[3] = {-0.3, 0.9, 0.1}, move_t[3] = {-70.0, 20.0, -35.0};
    const double shift[3] = {1e7, -3e6 + 0.25, 250.0};
    int k, i;
    for (k = 0; k < 2; ++k) {
        kissm_config c = scn_config(VOXEL);
        kissm_matcher *m = NULL;
        scn_cloud s, t, s0, t0, s1, t1;
        scn_pose fs, ft, fs_inv, tmp, truth;
        kissm_result sensor, moved, base, shifted;
        char label[64];
        c.viewpoint_mode = modes[k];
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        {
            kissm_points a = scn_points(&g_pair.source), b = scn_points(&g_pair.target);
            register_pair(m, &a, &b, &sensor);
        }
        sprintf(label, "viewpoint mode %d, sensor frames", (int)modes[k]);
        check_accuracy(label, &sensor, &g_pair.truth, VOXEL);
        /* truth' = ft o truth o fs^-1 */
        scn_cloud_init(&s);
        scn_cloud_init(&t);
        scn_cloud_copy(&s, &g_pair.source);
        scn_cloud_copy(&t, &g_pair.target);
        scn_pose_axis_angle(&fs, axis_s, 2.2, move_s);
        scn_pose_axis_angle(&ft, axis_t, -1.4, move_t);
        scn_cloud_apply(&s, &fs);
        scn_cloud_apply(&t, &ft);
        scn_pose_inverse(&fs, &fs_inv);
        scn_pose_compose(&g_pair.truth, &fs_inv, &tmp);
        scn_pose_compose(&ft, &tmp, &truth);
        {
            kissm_points a = scn_points(&s), b = scn_points(&t);
            register_pair(m, &a, &b, &moved);
        }
        sprintf(label, "viewpoint mode %d, moved frames", (int)modes[k]);
        check_accuracy(label, &moved, &truth, VOXEL);
        CHECK_MSG(moved.num_final_inliers * 10 >= sensor.num_final_inliers * 7,
                  "%s: %d inliers, %d in the sensor frames", label, (int)moved.num_final_inliers,
                  (int)sensor.num_final_inliers);

        scn_shifted_copies(&s, &t, shift, &s0, &t0, &s1, &t1);
        {
            kissm_points a = scn_points(&s0), b = scn_points(&t0);
            register_pair(m, &a, &b, &base);
        }
        {
            kissm_points a = scn_points(&s1), b = scn_points(&t1);
            register_pair(m, &a, &b, &shifted);
        }
        CHECK_EQ_INT(base.valid, 1);
        CHECK_EQ_INT(shifted.valid, 1);
        for (i = 0; i < 9; ++i)
            CHECK_MSG(base.rotation[i] == shifted.rotation[i], "%s: rotation[%d] differs", label, i);
        CHECK_EQ_INT(base.num_source_keypoints, shifted.num_source_keypoints);
        CHECK_EQ_INT(base.num_initial_correspondences, shifted.num_initial_correspondences);
        CHECK_EQ_INT(base.num_final_inliers, shifted.num_final_inliers);
        scn_cloud_free(&s);
        scn_cloud_free(&t);
        scn_cloud_free(&s0);
        scn_cloud_free(&t0);
        scn_cloud_free(&s1);
        scn_cloud_free(&t1);
        kissm_destroy(m);
    }
}

int main(void) {
    scn_make_pair(&g_pair, 1, 25.0, 0.01);
    RUN_TEST(test_register_float64);
    RUN_TEST(test_register_float32);
    RUN_TEST(test_strided);
    RUN_TEST(test_georeferenced_shift);
    RUN_TEST(test_swapped);
    RUN_TEST(test_other_scene);
    RUN_TEST(test_frame_free_modes);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
