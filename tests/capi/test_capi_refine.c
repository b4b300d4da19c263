/* SPDX-License-Identifier: MIT */
/* Fine registration through the C API: kissm_refine and kissm_refine_features from a perturbed ground truth
 * (both costs; features give the same bits), kissm_register with refine_mode set (refined closer to the truth
 * than the solver's pose, coarse_transform the plain registration's bit for bit), every new result field's
 * range, validity following the documented rule from the reported numbers, time_total_ms with
 * time_refine_ms, min_overlap, clouds that do not overlap at the initial pose, a corridor, a plane and a pipe
 * (valid = 0 with a reason, the information's free directions in the caller's source frame), priors near the
 * truth (valid and right) and far from it, and an older caller's 152-byte config and 440-byte result. C99. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.4
#define OLD_CONFIG_SIZE 152u /* kissm 0.1.0's published sizes (docs/abi-policy.md) */
#define OLD_RESULT_SIZE 440u

static scn_pair g_pair;

/* What a refinement from near the truth must reach on these scenes (noise 1 cm, voxel 0.4 m): GICP well
 * within a tenth of a voxel; point-to-plane, whose cost leaves more to the normals, within a quarter. */
static const double k_max_rot_deg[3] = {0.1, 0.1, 0.25};
static const double k_max_trans[3] = {0.03, 0.03, 0.1};

static const int32_t k_modes[3] = {KISSM_REFINE_NONE, KISSM_REFINE_GICP, KISSM_REFINE_POINT_TO_PLANE};
static const char *const k_mode_names[3] = {"none", "GICP", "point-to-plane"};

static kissm_matcher *make_matcher(int32_t refine_mode, double voxel, int32_t threads) {
    kissm_config c = scn_config(voxel);
    kissm_matcher *m = NULL;
    c.refine_mode = refine_mode;
    c.num_threads = threads;
    if (kissm_create(&c, &m) != KISSM_OK) {
        fprintf(stderr, "create: %s\n", kissm_last_error_message());
        return NULL;
    }
    return m;
}

/* truth o exp(perturbation): the perturbation turns by `deg` about `axis` and shifts by `shift`, both in the
 * source frame. */
static void perturbed(const scn_pose *truth, const double axis[3], double deg, const double shift[3], double m[16]) {
    scn_pose p, out;
    scn_pose_axis_angle(&p, axis, deg * 3.14159265358979323846 / 180.0, shift);
    scn_pose_compose(truth, &p, &out);
    scn_pose_to_matrix(&out, m);
}

static double rot_err(const kissm_result *r, const scn_pose *truth) {
    return scn_rotation_error_deg(r->rotation, truth->R);
}
static double trans_err(const kissm_result *r, const scn_pose *truth) {
    return scn_translation_error(r->translation, truth->t);
}
static double matrix_rot_err(const double m[16], const scn_pose *truth) {
    scn_pose p;
    scn_pose_from_matrix(m, &p);
    return scn_rotation_error_deg(p.R, truth->R);
}
static double matrix_trans_err(const double m[16], const scn_pose *truth) {
    scn_pose p;
    scn_pose_from_matrix(m, &p);
    return scn_translation_error(p.t, truth->t);
}

/* Cholesky of a symmetric 6x6 (row-major): 1 when positive definite. */
static int positive_definite6(const double a[36]) {
    double L[36];
    int i, j, k;
    memset(L, 0, sizeof(L));
    for (i = 0; i < 6; ++i)
        for (j = 0; j <= i; ++j) {
            double s = a[6 * i + j];
            for (k = 0; k < j; ++k) s -= L[6 * i + k] * L[6 * j + k];
            if (i == j) {
                if (!(s > 0.0)) return 0;
                L[6 * i + i] = sqrt(s);
            } else {
                L[6 * i + j] = s / L[6 * j + j];
            }
        }
    return 1;
}

/* u^T I u / (|u|^2 trace I): how much information the direction u carries, relative to all of it. */
static double information_share(const double info[36], const double u[6]) {
    double q = 0.0, uu = 0.0, tr = 0.0;
    int i, j;
    for (i = 0; i < 6; ++i) {
        for (j = 0; j < 6; ++j) q += u[i] * info[6 * i + j] * u[j];
        uu += u[i] * u[i];
        tr += info[6 * i + i];
    }
    return q / (uu * tr);
}

/* What every result of a refinement that ran must hold (whatever its validity). */
static void check_refined_fields(const char *label, const kissm_result *r, int32_t max_iterations) {
    int i, j, finite = 1, symmetric = 1;
    double sum;
    for (i = 0; i < 36; ++i) finite &= isfinite(r->information[i]) != 0;
    for (i = 0; i < 6; ++i)
        for (j = 0; j < 6; ++j) symmetric &= r->information[6 * i + j] == r->information[6 * j + i];
    CHECK_MSG(finite && symmetric, "%s: information finite %d, symmetric %d", label, finite, symmetric);
    for (i = 0; i < 6; ++i) CHECK_MSG(r->information[6 * i + i] >= 0.0, "%s: information[%d][%d] < 0", label, i, i);
    CHECK_MSG(r->overlap >= 0.0 && r->overlap <= 1.0, "%s: overlap %g", label, r->overlap);
    CHECK_MSG(r->refine_condition >= 0.0 && r->refine_condition <= 1.0, "%s: condition %g", label, r->refine_condition);
    CHECK_MSG(r->refine_iterations >= 0 && r->refine_iterations <= max_iterations, "%s: %d iterations", label,
              (int)r->refine_iterations);
    CHECK(r->refine_converged == 0 || r->refine_converged == 1);
    CHECK(r->num_refine_correspondences <= r->num_source_voxels);
    if (r->num_refine_correspondences > 0)
        CHECK_MSG(r->refine_rmse >= 0.0 && isfinite(r->refine_rmse), "%s: refine_rmse %g", label, r->refine_rmse);
    else
        CHECK_MSG(isnan(r->refine_rmse), "%s: refine_rmse %g without correspondences", label, r->refine_rmse);
    CHECK(r->time_refine_ms >= 0.0);
    sum = r->time_voxelize_ms + r->time_features_ms + r->time_matching_ms + r->time_pruning_ms + r->time_solver_ms +
          r->time_refine_ms;
    CHECK_MSG(fabs(r->time_total_ms - sum) <= 1e-9 * (sum > 1.0 ? sum : 1.0), "%s: total %.17g, sum %.17g", label,
              r->time_total_ms, sum);
    /* the pose: finite, [R t; 0 0 0 1], R a rotation */
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) CHECK(r->transform[4 * i + j] == r->rotation[3 * i + j]);
        CHECK(r->transform[4 * i + 3] == r->translation[i]);
    }
    CHECK(r->transform[12] == 0.0 && r->transform[13] == 0.0 && r->transform[14] == 0.0 && r->transform[15] == 1.0);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double dot = r->rotation[3 * i + 0] * r->rotation[3 * j + 0] +
                         r->rotation[3 * i + 1] * r->rotation[3 * j + 1] +
                         r->rotation[3 * i + 2] * r->rotation[3 * j + 2];
            CHECK_MSG(fabs(dot - (i == j)) < 1e-12, "%s: R R^T (%d %d) %.17g", label, i, j, dot);
        }
    CHECK(r->coarse_transform[12] == 0.0 && r->coarse_transform[13] == 0.0 && r->coarse_transform[14] == 0.0 &&
          r->coarse_transform[15] == 1.0);
    CHECK(scn_result_poison_left(r) == 0);
    CHECK_EQ_INT(r->reserved0, 0);
}

/* The refined rotation's 1-sigma about its worst axis that an information states (radians): the largest
 * eigenvalue of the rotation block of its inverse (Gauss-Jordan, then power iteration on the 3x3 block), square
 * rooted; infinite when the information is not positive definite. */
static double information_rotation_sigma(const double info[36]) {
    double a[6][12], v[3] = {1.0, 0.7, 0.3}, lambda = 0.0;
    int i, j, k, it;
    if (!positive_definite6(info)) return INFINITY;
    for (i = 0; i < 6; ++i)
        for (j = 0; j < 12; ++j) a[i][j] = j < 6 ? info[6 * i + j] : (j - 6 == i ? 1.0 : 0.0);
    for (i = 0; i < 6; ++i) { /* no pivoting needed: positive definite */
        const double d = a[i][i];
        for (j = 0; j < 12; ++j) a[i][j] /= d;
        for (k = 0; k < 6; ++k) {
            const double f = a[k][i];
            if (k == i) continue;
            for (j = 0; j < 12; ++j) a[k][j] -= f * a[i][j];
        }
    }
    for (it = 0; it < 500; ++it) {
        double w[3] = {0.0, 0.0, 0.0}, n = 0.0;
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j) w[i] += 0.5 * (a[i][6 + j] + a[j][6 + i]) * v[j];
        for (i = 0; i < 3; ++i) n += w[i] * w[i];
        n = sqrt(n);
        if (!(n > 0.0)) return 0.0;
        for (i = 0; i < 3; ++i) v[i] = w[i] / n;
        lambda = n;
    }
    return sqrt(lambda);
}

/* kissm_refine's rule, from the numbers it reports (docs/refinement.md): at least 6 correspondences and
 * overlap >= min_overlap, else LOW_OVERLAP; refine_condition >= min_refine_condition, else UNCONSTRAINED;
 * converged, else NOT_CONVERGED; refine_rmse <= max_refine_rmse_gain * voxel_size, else LOOSE_ALIGNMENT; not
 * refine_rmse > 0.37 voxel with refine_condition < 0.09 (a condition that is not a number counts as weak), else
 * LOOSE_AND_WEAK; 2 times
 * the information's rotation sigma <= max_rotation_uncertainty, else UNCERTAIN_ROTATION; the config's values,
 * whatever the defaults are. */
static void check_prior_rule(const char *label, const kissm_result *r, const kissm_config *c) {
    int32_t expected = KISSM_REASON_NONE;
    if (r->num_refine_correspondences < 6 || !(r->overlap >= c->min_overlap))
        expected = KISSM_REASON_LOW_OVERLAP;
    else if (!c->allow_degenerate && !(r->refine_condition >= c->min_refine_condition))
        expected = KISSM_REASON_UNCONSTRAINED;
    else if (!r->refine_converged)
        expected = KISSM_REASON_NOT_CONVERGED;
    else if (!(r->refine_rmse <= c->max_refine_rmse_gain * c->voxel_size))
        expected = KISSM_REASON_LOOSE_ALIGNMENT;
    else if (r->refine_rmse > 0.37 * c->voxel_size && !(r->refine_condition >= 0.09))
        expected = KISSM_REASON_LOOSE_AND_WEAK;
    else if (!(c->allow_degenerate && r->degenerate) &&
             !(2.0 * information_rotation_sigma(r->information) <= c->max_rotation_uncertainty))
        expected = KISSM_REASON_UNCERTAIN_ROTATION;
    CHECK_MSG(r->reason == expected && r->valid == (expected == KISSM_REASON_NONE),
              "%s: valid %d reason %d, the rule gives reason %d", label, (int)r->valid, (int)r->reason, (int)expected);
    CHECK(isnan(r->rotation_uncertainty) && isnan(r->inlier_coverage)); /* no solver ran */
}

/* A valid refinement: also positive definite, well conditioned, converged within the cap. */
static void check_valid_refinement(const char *label, const kissm_result *r, int32_t max_iterations) {
    check_refined_fields(label, r, max_iterations);
    CHECK_MSG(r->valid == 1 && r->reason == KISSM_REASON_NONE, "%s: valid %d reason %d", label, (int)r->valid,
              (int)r->reason);
    CHECK_MSG(positive_definite6(r->information), "%s: information not positive definite", label);
    CHECK_MSG(r->refine_condition >= scn_config(VOXEL).min_refine_condition, "%s: condition %g", label,
              r->refine_condition);
    CHECK(r->refine_converged == 1);
    CHECK_MSG(r->refine_iterations >= 1, "%s: %d iterations", label, (int)r->refine_iterations);
    CHECK_MSG(r->num_refine_correspondences >= 100, "%s: %llu correspondences", label,
              (unsigned long long)r->num_refine_correspondences);
    CHECK_MSG(r->overlap > 0.3, "%s: overlap %g", label, r->overlap);
    CHECK_MSG(r->refine_rmse < VOXEL, "%s: rmse %g", label, r->refine_rmse);
}

/* ---------------------------------------------------------------------------------------------- */
/* kissm_refine and kissm_refine_features                                                          */
/* ---------------------------------------------------------------------------------------------- */

static void test_refine_from_perturbed_truth(void) {
    const double axes[3][3] = {{1.0, 2.0, 3.0}, {0.0, 0.0, 1.0}, {-1.0, 0.5, 0.2}};
    const double degs[3] = {3.0, -5.0, 1.0};
    const double shifts[3][3] = {{0.3, -0.2, 0.1}, {0.5, 0.3, 0.0}, {-0.1, 0.0, -0.4}};
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_result first_none;
    int mode, k;
    for (mode = 0; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], VOXEL, 2);
        REQUIRE(m != NULL);
        for (k = 0; k < 3; ++k) {
            double initial[16], start_rot, start_trans;
            kissm_result r;
            char label[96];
            int32_t st;
            int i;
            perturbed(&g_pair.truth, axes[k], degs[k], shifts[k], initial);
            start_rot = matrix_rot_err(initial, &g_pair.truth);
            start_trans = matrix_trans_err(initial, &g_pair.truth);
            sprintf(label, "refine %s from %.0f deg, %.2f m", k_mode_names[mode], start_rot, start_trans);
            scn_result_poison(&r);
            st = kissm_refine(m, &s, &t, initial, &r);
            CHECK_MSG(st == KISSM_OK, "%s: %d %s", label, (int)st, kissm_last_error_message());
            check_valid_refinement(label, &r, scn_config(VOXEL).refine_max_iterations);
            {
                const kissm_config c = scn_config(VOXEL);
                check_prior_rule(label, &r, &c);
            }
            CHECK_MSG(rot_err(&r, &g_pair.truth) < k_max_rot_deg[mode] &&
                          trans_err(&r, &g_pair.truth) < k_max_trans[mode],
                      "%s: %.4f deg, %.4f m off", label, rot_err(&r, &g_pair.truth), trans_err(&r, &g_pair.truth));
            /* coarse_transform is the initial transform with its rotation made exactly rigid: for one already
             * orthonormal, the same to the last bits or within rounding */
            for (i = 0; i < 16; ++i) CHECK_NEAR(r.coarse_transform[i], initial[i], 1e-14);
            /* a refinement from a prior: no descriptor stage ran */
            CHECK_EQ_INT(r.num_source_keypoints, 0);
            CHECK_EQ_INT(r.num_initial_correspondences, 0);
            CHECK_EQ_INT(r.num_final_inliers, 0);
            CHECK(r.time_matching_ms == 0.0 && r.time_pruning_ms == 0.0 && r.time_solver_ms == 0.0);
            CHECK(r.time_voxelize_ms > 0.0 && r.time_features_ms > 0.0);
            CHECK_EQ_INT(r.num_source_points, g_pair.source.count);
            CHECK_EQ_INT(r.num_target_points, g_pair.target.count);
            CHECK(r.num_source_voxels > 100 && r.num_target_voxels > 100);
            if (mode == 0 && k == 0) first_none = r;
            /* refine_mode NONE means GICP for kissm_refine */
            if (mode == 1 && k == 0) CHECK_MSG(scn_result_equal(&first_none, &r), "NONE differs from GICP");
            if (!(r.valid == 1)) scn_result_print(label, &r);
        }
        kissm_destroy(m);
    }
}

/* A rotation block within the documented 1e-3 of orthonormal is accepted and made exactly rigid. */
static void test_nearly_rigid_initial_accepted(void) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_matcher *m = make_matcher(KISSM_REFINE_GICP, VOXEL, 1);
    double initial[16];
    kissm_result r, ref;
    int i, j;
    REQUIRE(m != NULL);
    scn_pose_to_matrix(&g_pair.truth, initial);
    scn_result_poison(&ref);
    CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &ref), KISSM_OK);
    /* rounded to float, as ground-truth files often are, and off by a few 1e-4 */
    for (i = 0; i < 12; ++i) initial[i] = (double)(float)initial[i];
    initial[1] += 3e-4;
    initial[6] -= 2e-4;
    scn_result_poison(&r);
    CHECK_MSG(kissm_refine(m, &s, &t, initial, &r) == KISSM_OK, "%s", kissm_last_error_message());
    CHECK_EQ_INT(r.valid, 1);
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            const double *c = r.coarse_transform;
            const double dot = c[4 * i] * c[4 * j] + c[4 * i + 1] * c[4 * j + 1] + c[4 * i + 2] * c[4 * j + 2];
            CHECK_MSG(fabs(dot - (i == j)) < 1e-12, "coarse rotation not orthonormal: %.17g", dot);
        }
    for (i = 0; i < 3; ++i) CHECK(r.coarse_transform[4 * i + 3] == initial[4 * i + 3]);
    CHECK(rot_err(&r, &g_pair.truth) < k_max_rot_deg[1] && trans_err(&r, &g_pair.truth) < k_max_trans[1]);
    kissm_destroy(m);
}

static void test_refine_features(void) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    const double axis[3] = {0.0, 1.0, 1.0}, shift[3] = {0.2, 0.2, -0.1};
    double initial[16];
    int mode;
    perturbed(&g_pair.truth, axis, 2.5, shift, initial);
    for (mode = 0; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], VOXEL, 2);
        kissm_matcher *other = make_matcher(k_modes[(mode + 1) % 3], VOXEL, 1);
        kissm_features *fs = NULL, *ft = NULL, *gs = NULL, *gt = NULL;
        kissm_result direct, via, via_other;
        REQUIRE(m != NULL && other != NULL);
        REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
        REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
        /* features from a matcher with another refine_mode (with or without the index): same descriptor
         * settings, so accepted, and the same refined pose */
        REQUIRE(kissm_features_compute(other, &s, &gs) == KISSM_OK);
        REQUIRE(kissm_features_compute(other, &t, &gt) == KISSM_OK);
        scn_result_poison(&direct);
        scn_result_poison(&via);
        scn_result_poison(&via_other);
        CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &direct), KISSM_OK);
        CHECK_EQ_INT(kissm_refine_features(m, fs, ft, initial, &via), KISSM_OK);
        CHECK_EQ_INT(kissm_refine_features(m, gs, gt, initial, &via_other), KISSM_OK);
        check_valid_refinement("refine_features", &via, scn_config(VOXEL).refine_max_iterations);
        CHECK_MSG(scn_result_equal(&direct, &via), "%s: refine_features differs from refine", k_mode_names[mode]);
        CHECK_MSG(scn_result_equal(&via, &via_other), "%s: features of another refine_mode differ", k_mode_names[mode]);
        if (!scn_result_equal(&direct, &via)) {
            scn_result_print("refine", &direct);
            scn_result_print("refine_features", &via);
        }
        /* refinement uses no descriptor: keypoint counts 0 as for kissm_refine, though the features have them */
        CHECK(kissm_features_num_keypoints(fs) > 0);
        CHECK_EQ_INT(via.num_source_keypoints, 0);
        CHECK_EQ_INT(via.num_target_keypoints, 0);
        CHECK(via.time_voxelize_ms == 0.0 && via.time_features_ms == 0.0);
        CHECK(via.time_refine_ms > 0.0 && via.time_total_ms == via.time_refine_ms);
        /* the swapped pair from the inverse prior gives the inverse pose */
        {
            scn_pose init, inv;
            double inv_m[16];
            kissm_result back;
            scn_pose_from_matrix(initial, &init);
            scn_pose_inverse(&init, &inv);
            scn_pose_to_matrix(&inv, inv_m);
            scn_result_poison(&back);
            CHECK_EQ_INT(kissm_refine_features(m, ft, fs, inv_m, &back), KISSM_OK);
            CHECK_EQ_INT(back.valid, 1);
            scn_pose_inverse(&g_pair.truth, &inv);
            CHECK_MSG(rot_err(&back, &inv) < k_max_rot_deg[mode] && trans_err(&back, &inv) < k_max_trans[mode],
                      "%s, swapped: %.4f deg %.4f m", k_mode_names[mode], rot_err(&back, &inv), trans_err(&back, &inv));
        }
        kissm_features_destroy(fs);
        kissm_features_destroy(ft);
        kissm_features_destroy(gs);
        kissm_features_destroy(gt);
        kissm_destroy(m);
        kissm_destroy(other);
    }
}

/* Georeferenced coordinates: both clouds shifted by 1e7 m (on a 2^-20 m grid, so the shifted coordinates are
 * exact) and the prior moved with them give the same relative pose: refinement works in recentred frames. */
static void test_georeferenced_shift(void) {
    const double shift[3] = {1e7, -1e7 + 12345.0, 250.0};
    const double axis[3] = {1.0, 0.0, 1.0}, pert[3] = {0.2, -0.1, 0.1};
    scn_cloud s0, t0, s1, t1;
    scn_pose start, shifted_start;
    double initial[16], shifted_initial[16];
    kissm_result base, moved;
    kissm_matcher *m = make_matcher(KISSM_REFINE_GICP, VOXEL, 2);
    int i;
    REQUIRE(m != NULL);
    scn_shifted_copies(&g_pair.source, &g_pair.target, shift, &s0, &t0, &s1, &t1);
    perturbed(&g_pair.truth, axis, 2.0, pert, initial);
    scn_pose_from_matrix(initial, &start);
    /* p_t + s = R (p_s + s - s) + t + s: the prior in the shifted frames has t' = t + s - R s */
    shifted_start = start;
    for (i = 0; i < 3; ++i)
        shifted_start.t[i] =
            start.t[i] + shift[i] -
            (start.R[3 * i] * shift[0] + start.R[3 * i + 1] * shift[1] + start.R[3 * i + 2] * shift[2]);
    scn_pose_to_matrix(&shifted_start, shifted_initial);
    {
        const kissm_points a = scn_points(&s0), b = scn_points(&t0), a1 = scn_points(&s1), b1 = scn_points(&t1);
        scn_result_poison(&base);
        scn_result_poison(&moved);
        CHECK_EQ_INT(kissm_refine(m, &a, &b, initial, &base), KISSM_OK);
        CHECK_EQ_INT(kissm_refine(m, &a1, &b1, shifted_initial, &moved), KISSM_OK);
    }
    CHECK_EQ_INT(base.valid, 1);
    CHECK_EQ_INT(moved.valid, 1);
    check_refined_fields("georeferenced", &moved, scn_config(VOXEL).refine_max_iterations);
    CHECK(rot_err(&base, &g_pair.truth) < k_max_rot_deg[1] && trans_err(&base, &g_pair.truth) < k_max_trans[1]);
    CHECK_MSG(scn_rotation_error_deg(base.rotation, moved.rotation) < 1e-5, "rotation differs by %.3g deg",
              scn_rotation_error_deg(base.rotation, moved.rotation));
    {
        double expected_t[3];
        for (i = 0; i < 3; ++i)
            expected_t[i] = base.translation[i] + shift[i] -
                            (moved.rotation[3 * i] * shift[0] + moved.rotation[3 * i + 1] * shift[1] +
                             moved.rotation[3 * i + 2] * shift[2]);
        CHECK_MSG(scn_translation_error(expected_t, moved.translation) < 1e-3, "shifted translation off by %.3g m",
                  scn_translation_error(expected_t, moved.translation));
    }
    CHECK_EQ_INT(base.num_refine_correspondences, moved.num_refine_correspondences);
    CHECK_NEAR(base.overlap, moved.overlap, 1e-12);
    CHECK_NEAR(base.refine_condition, moved.refine_condition, 1e-6);
    /* the information's translation block does not depend on where the frame's origin is */
    for (i = 3; i < 6; ++i) {
        int j;
        for (j = 3; j < 6; ++j)
            CHECK_NEAR(moved.information[6 * i + j], base.information[6 * i + j],
                       1e-4 * fabs(base.information[6 * i + i]));
    }
    kissm_destroy(m);
    scn_cloud_free(&s0), scn_cloud_free(&t0), scn_cloud_free(&s1), scn_cloud_free(&t1);
}

/* ---------------------------------------------------------------------------------------------- */
/* kissm_register with refinement                                                                  */
/* ---------------------------------------------------------------------------------------------- */

static void test_register_with_refine(void) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_matcher *plain_m = make_matcher(KISSM_REFINE_NONE, VOXEL, 2);
    kissm_result plain;
    int mode, i;
    REQUIRE(plain_m != NULL);
    scn_result_poison(&plain);
    REQUIRE(kissm_register(plain_m, &s, &t, &plain) == KISSM_OK);
    REQUIRE(plain.valid == 1);
    /* without refinement: coarse_transform is transform, the refinement's fields are "not run" */
    CHECK(memcmp(plain.coarse_transform, plain.transform, sizeof(plain.transform)) == 0);
    for (i = 0; i < 36; ++i) CHECK(isnan(plain.information[i]));
    CHECK(isnan(plain.overlap) && isnan(plain.refine_rmse) && isnan(plain.refine_condition));
    CHECK(plain.time_refine_ms == 0.0);
    CHECK_EQ_INT(plain.num_refine_correspondences, 0);
    CHECK_EQ_INT(plain.refine_iterations, 0);
    CHECK_EQ_INT(plain.refine_converged, 0);
    fprintf(stderr, "  solver alone: %.4f deg, %.4f m\n", rot_err(&plain, &g_pair.truth),
            trans_err(&plain, &g_pair.truth));

    for (mode = 1; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], VOXEL, 2);
        kissm_features *fs = NULL, *ft = NULL;
        kissm_result r, via, coarse_part;
        char label[64];
        REQUIRE(m != NULL);
        sprintf(label, "register + %s", k_mode_names[mode]);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
        check_valid_refinement(label, &r, scn_config(VOXEL).refine_max_iterations);
        fprintf(stderr, "  %s: %.4f deg, %.4f m\n", label, rot_err(&r, &g_pair.truth), trans_err(&r, &g_pair.truth));
        /* the solver's pose is the plain registration's, bit for bit, and so is everything it counted */
        CHECK_MSG(memcmp(r.coarse_transform, plain.transform, sizeof(plain.transform)) == 0,
                  "%s: coarse_transform differs from the plain registration", label);
        coarse_part = r;
        memcpy(coarse_part.transform, plain.transform, sizeof(plain.transform));
        memcpy(coarse_part.rotation, plain.rotation, sizeof(plain.rotation));
        memcpy(coarse_part.translation, plain.translation, sizeof(plain.translation));
        memcpy(coarse_part.information, plain.information, sizeof(plain.information));
        coarse_part.overlap = plain.overlap;
        coarse_part.refine_rmse = plain.refine_rmse;
        coarse_part.refine_condition = plain.refine_condition;
        coarse_part.inlier_coverage = plain.inlier_coverage;
        coarse_part.confidence = plain.confidence; /* the refined model reads the overlap */
        coarse_part.num_refine_correspondences = 0;
        coarse_part.refine_iterations = 0;
        coarse_part.refine_converged = 0;
        CHECK_MSG(scn_result_equal(&coarse_part, &plain), "%s: a coarse field differs from the plain registration",
                  label);
        /* valid by the refined rule's numbers (docs/refinement.md) */
        {
            const kissm_config d = scn_config(VOXEL);
            CHECK(r.num_final_inliers >= (uint64_t)d.refine_min_inliers);
            CHECK_MSG(r.inlier_coverage >= d.min_inlier_coverage, "%s: inlier_coverage %g", label, r.inlier_coverage);
            CHECK(r.overlap >= d.min_overlap && r.refine_condition >= d.min_refine_condition && r.refine_converged);
            CHECK(r.rotation_uncertainty == plain.rotation_uncertainty);
        }
        /* refined closer to the truth than the solver's pose */
        CHECK_MSG(trans_err(&r, &g_pair.truth) < trans_err(&plain, &g_pair.truth),
                  "%s: translation %.4f m, solver %.4f m", label, trans_err(&r, &g_pair.truth),
                  trans_err(&plain, &g_pair.truth));
        CHECK_MSG(rot_err(&r, &g_pair.truth) < rot_err(&plain, &g_pair.truth), "%s: rotation %.4f deg, solver %.4f deg",
                  label, rot_err(&r, &g_pair.truth), rot_err(&plain, &g_pair.truth));
        CHECK(rot_err(&r, &g_pair.truth) < k_max_rot_deg[mode] && trans_err(&r, &g_pair.truth) < k_max_trans[mode]);
        /* time_total_ms includes the refinement */
        CHECK(r.time_refine_ms > 0.0);
        CHECK(r.time_total_ms >= r.time_refine_ms + r.time_solver_ms);
        /* from features: the same */
        REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
        REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
        scn_result_poison(&via);
        CHECK_EQ_INT(kissm_register_features(m, fs, ft, &via), KISSM_OK);
        CHECK_MSG(scn_result_equal(&r, &via), "%s: register_features differs", label);
        kissm_features_destroy(fs);
        kissm_features_destroy(ft);
        kissm_destroy(m);
    }
    kissm_destroy(plain_m);
}

/* min_overlap: the pair overlaps partially; demanding all of it makes the refined pose LOW_OVERLAP (kept for
 * inspection), demanding nothing does not. */
static void test_min_overlap(void) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    kissm_result r, open;
    double initial[16];
    scn_pose_to_matrix(&g_pair.truth, initial);
    c.refine_mode = KISSM_REFINE_GICP;
    c.min_overlap = 0.0;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(&open);
    CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &open), KISSM_OK);
    CHECK_EQ_INT(open.valid, 1);
    CHECK(open.overlap > 0.3 && open.overlap < 1.0);
    kissm_destroy(m);

    c.min_overlap = 1.0;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
    CHECK_EQ_INT(r.valid, 0);
    CHECK_EQ_INT(r.reason, KISSM_REASON_LOW_OVERLAP);
    CHECK(memcmp(r.transform, open.transform, sizeof(r.transform)) == 0); /* the same pose, only judged */
    check_refined_fields("min_overlap 1", &r, c.refine_max_iterations);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_register(m, &s, &t, &r), KISSM_OK);
    CHECK_EQ_INT(r.valid, 0);
    CHECK_EQ_INT(r.reason, KISSM_REASON_LOW_OVERLAP);
    CHECK(rot_err(&r, &g_pair.truth) < k_max_rot_deg[1]); /* the refined pose, kept for inspection */
    kissm_destroy(m);

    /* just below and just above the measured overlap */
    c.min_overlap = open.overlap;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
    CHECK_EQ_INT(r.valid, 1); /* >= min_overlap */
    kissm_destroy(m);
    c.min_overlap = nextafter(open.overlap, 2.0);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
    CHECK_EQ_INT(r.reason, KISSM_REASON_LOW_OVERLAP);
    kissm_destroy(m);
}

/* ---------------------------------------------------------------------------------------------- */
/* Refinement that cannot succeed                                                                  */
/* ---------------------------------------------------------------------------------------------- */

static void test_no_overlap_at_initial_pose(void) {
    scn_cloud far;
    kissm_points s = scn_points(&g_pair.source), t;
    double initial[16];
    int mode, i;
    scn_cloud_init(&far);
    scn_cloud_copy(&far, &g_pair.target);
    scn_cloud_translate(&far, 1000.0, 0.0, 0.0); /* the target 1 km away; the prior does not know */
    t = scn_points(&far);
    scn_pose_to_matrix(&g_pair.truth, initial);
    for (mode = 0; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], VOXEL, 2);
        kissm_result r;
        REQUIRE(m != NULL);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
        CHECK_EQ_INT(r.valid, 0);
        CHECK_EQ_INT(r.reason, KISSM_REASON_LOW_OVERLAP);
        CHECK_EQ_INT(r.num_refine_correspondences, 0);
        CHECK_EQ_INT(r.refine_iterations, 0);
        CHECK(r.overlap == 0.0);
        CHECK(isnan(r.refine_rmse));
        check_refined_fields("1 km apart", &r, 30);
        /* nothing was measured: no information in any direction */
        for (i = 0; i < 36; ++i) CHECK(r.information[i] == 0.0);
        /* the prior comes back as the pose */
        for (i = 0; i < 16; ++i) CHECK_NEAR(r.transform[i], initial[i], 1e-12);
        kissm_destroy(m);
    }
    scn_cloud_free(&far);
}

/* The angle (degrees) between v and the span of the first k rows of `rows` (6 numbers each), by Gram-Schmidt. */
static double angle_to_span_deg(const double v[6], const double *rows, int k) {
    double basis[6][6], proj = 0.0, norm = 0.0;
    int i, j, l;
    for (i = 0; i < k; ++i) {
        double len = 0.0;
        for (j = 0; j < 6; ++j) basis[i][j] = rows[6 * i + j];
        for (l = 0; l < i; ++l) {
            double d = 0.0;
            for (j = 0; j < 6; ++j) d += basis[i][j] * basis[l][j];
            for (j = 0; j < 6; ++j) basis[i][j] -= d * basis[l][j];
        }
        for (j = 0; j < 6; ++j) len += basis[i][j] * basis[i][j];
        len = sqrt(len);
        for (j = 0; j < 6; ++j) basis[i][j] /= len;
    }
    for (i = 0; i < k; ++i) {
        double d = 0.0;
        for (j = 0; j < 6; ++j) d += v[j] * basis[i][j];
        proj += d * d;
    }
    for (j = 0; j < 6; ++j) norm += v[j] * v[j];
    return acos(fmin(1.0, sqrt(proj / norm))) * 180.0 / 3.14159265358979323846;
}

/* Degeneracy as the result reports it: degenerate, `count` weak directions (unit rows, the rest NaN), each
 * true free direction within 10 degrees of their span; then the same call with allow_degenerate = 1 is valid
 * (the scenes converge and align well) with the same weak directions, bit for bit. */
static void check_degenerate(const char *label, const kissm_result *r, const double (*free_dirs)[6], int count,
                             int32_t refine_mode, double voxel, const kissm_points *s, const kissm_points *t,
                             const double initial[16]) {
    int i, j;
    CHECK_MSG(r->degenerate == 1 && r->num_weak_directions == count, "%s: degenerate %d with %d weak directions", label,
              (int)r->degenerate, (int)r->num_weak_directions);
    if (r->num_weak_directions != count) return;
    for (i = 0; i < 6; ++i) {
        double n2 = 0.0;
        for (j = 0; j < 6; ++j) n2 += r->weak_directions[6 * i + j] * r->weak_directions[6 * i + j];
        if (i < count)
            CHECK_MSG(fabs(n2 - 1.0) < 1e-12, "%s: weak direction %d has length^2 %g", label, i, n2);
        else
            CHECK_MSG(isnan(n2), "%s: row %d beyond the weak directions is not NaN", label, i);
    }
    for (i = 0; i < count; ++i) {
        const double a = angle_to_span_deg(free_dirs[i], r->weak_directions, count);
        fprintf(stderr, "  %s: free direction %d is %.3f deg off the reported ones\n", label, i, a);
        CHECK_MSG(a < 10.0, "%s: free direction %d is %.2f deg off the reported ones", label, i, a);
    }
    {
        kissm_config c = scn_config(voxel);
        kissm_matcher *m = NULL;
        kissm_result allowed;
        c.refine_mode = refine_mode;
        c.num_threads = 2;
        c.allow_degenerate = 1;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        scn_result_poison(&allowed);
        CHECK_EQ_INT(kissm_refine(m, s, t, initial, &allowed), KISSM_OK);
        CHECK_MSG(allowed.valid == 1 && allowed.degenerate == 1, "%s, allowed: valid %d (reason %d), degenerate %d",
                  label, (int)allowed.valid, (int)allowed.reason, (int)allowed.degenerate);
        CHECK(memcmp(allowed.weak_directions, r->weak_directions, sizeof r->weak_directions) == 0);
        CHECK(memcmp(allowed.transform, r->transform, sizeof r->transform) == 0);
        kissm_destroy(m);
    }
}

/* A corridor along the source's x axis: the pose slides along it. Refinement from the truth: valid 0,
 * UNCONSTRAINED, a small condition, and the information's free direction is the slide in the source frame,
 * (0, 0, 0, 1, 0, 0), not the target frame's (0, R x). */
static void test_corridor(void) {
    scn_cloud a, b;
    scn_pose pose;
    const double axis[3] = {1.0, -2.0, 3.0}, shift[3] = {4.0, 3.0, 0.5};
    double initial[16];
    int mode;
    scn_cloud_init(&a);
    scn_cloud_init(&b);
    scn_make_corridor(&a, 3, 40.0, 0.01);
    scn_make_corridor(&b, 4, 40.0, 0.01);
    scn_pose_axis_angle(&pose, axis, 2.0, shift);
    scn_cloud_apply(&b, &pose);
    scn_pose_to_matrix(&pose, initial);
    for (mode = 0; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], 0.25, 2);
        const kissm_points s = scn_points(&a), t = scn_points(&b);
        const double slide[6] = {0, 0, 0, 1, 0, 0}, across[6] = {0, 0, 0, 0, 1, 0};
        double slide_in_target[6] = {0, 0, 0, 0, 0, 0};
        kissm_result r;
        int i;
        for (i = 0; i < 3; ++i) slide_in_target[3 + i] = pose.R[3 * i + 0];
        REQUIRE(m != NULL);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
        check_refined_fields("corridor", &r, 30);
        CHECK_EQ_INT(r.valid, 0);
        CHECK_MSG(r.reason == KISSM_REASON_UNCONSTRAINED, "corridor, %s: reason %d", k_mode_names[mode], (int)r.reason);
        CHECK_MSG(r.refine_condition < scn_config(0.25).min_refine_condition, "corridor: condition %g",
                  r.refine_condition);
        {
            const kissm_config c = scn_config(0.25);
            const double free_dirs[1][6] = {{0, 0, 0, 1, 0, 0}};
            check_prior_rule("corridor", &r, &c);
            if (k_modes[mode] != KISSM_REFINE_NONE)
                check_degenerate("corridor", &r, free_dirs, 1, k_modes[mode], 0.25, &s, &t, initial);
        }
        /* the weakest direction is the slide in the source frame: far less information than across the
         * corridor, or than the slide expressed in the target frame would have */
        fprintf(stderr, "  corridor, %s: condition %.3g, information share of slide %.3g, across %.3g, R x %.3g\n",
                k_mode_names[mode], r.refine_condition, information_share(r.information, slide),
                information_share(r.information, across), information_share(r.information, slide_in_target));
        CHECK_MSG(information_share(r.information, slide) < 0.01 * information_share(r.information, across),
                  "corridor, %s: slide carries %g, across %g", k_mode_names[mode],
                  information_share(r.information, slide), information_share(r.information, across));
        CHECK_MSG(information_share(r.information, slide) < 0.01 * information_share(r.information, slide_in_target),
                  "corridor, %s: slide carries %g, R x %g", k_mode_names[mode], information_share(r.information, slide),
                  information_share(r.information, slide_in_target));
        /* kissm_register with refinement on a corridor: invalid with a reason, never a crash */
        {
            kissm_config c = scn_config(0.25);
            kissm_matcher *rm = NULL;
            kissm_result rr;
            c.refine_mode = k_modes[mode] == KISSM_REFINE_NONE ? KISSM_REFINE_GICP : k_modes[mode];
            REQUIRE(kissm_create(&c, &rm) == KISSM_OK);
            scn_result_poison(&rr);
            CHECK_EQ_INT(kissm_register(rm, &s, &t, &rr), KISSM_OK);
            CHECK_MSG(rr.valid == 0 && rr.reason != KISSM_REASON_NONE, "register corridor: valid %d", (int)rr.valid);
            CHECK(scn_result_poison_left(&rr) == 0);
            kissm_destroy(rm);
        }
        kissm_destroy(m);
    }
    scn_cloud_free(&a);
    scn_cloud_free(&b);
}

/* A plane leaves three directions free; a pipe two, one of which, the turn about its axis, depends on where
 * the axis is: far from the origin, (d, c x d) is free in the caller's source frame and (d, 0) is not. */
static void test_plane_and_pipe(void) {
    scn_cloud a, b;
    scn_pose pose;
    const double axis[3] = {0.3, 1.0, -0.2}, shift[3] = {1.0, -2.0, 0.5};
    double initial[16];
    int mode;
    scn_cloud_init(&a);
    scn_cloud_init(&b);
    scn_pose_axis_angle(&pose, axis, 1.2, shift);
    scn_pose_to_matrix(&pose, initial);

    scn_make_plane(&a, 21, 12000, 0.01);
    scn_make_plane(&b, 22, 12000, 0.01);
    scn_cloud_apply(&b, &pose);
    for (mode = 1; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], 0.3, 1);
        const kissm_points s = scn_points(&a), t = scn_points(&b);
        kissm_result r;
        REQUIRE(m != NULL);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
        check_refined_fields("plane", &r, 30);
        CHECK_EQ_INT(r.valid, 0);
        CHECK_MSG(r.reason == KISSM_REASON_UNCONSTRAINED, "plane, %s: reason %d", k_mode_names[mode], (int)r.reason);
        CHECK(r.refine_condition < scn_config(0.3).min_refine_condition);
        CHECK_MSG(r.degenerate == 1 && r.num_weak_directions == 3, "plane, %s: degenerate %d, %d weak directions",
                  k_mode_names[mode], (int)r.degenerate, (int)r.num_weak_directions);
        kissm_destroy(m);
    }

    {
        const double centre[3] = {60.0, -40.0, 8.0}, dir[3] = {1.0, 1.0, 0.2};
        const double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        const double d[3] = {dir[0] / len, dir[1] / len, dir[2] / len};
        double slide[6], turn[6], turn_at_origin[6], across[6];
        scn_make_pipe(&a, 31, 30000, centre, dir, 2.0, 25.0, 0.005);
        scn_make_pipe(&b, 32, 30000, centre, dir, 2.0, 25.0, 0.005);
        scn_cloud_apply(&b, &pose);
        /* free: slide (0, d) and turn about the axis through centre c, (d, c x d); not free: (d, 0), a turn
         * about a parallel axis through the origin, and a shift across */
        slide[0] = slide[1] = slide[2] = 0.0;
        memcpy(slide + 3, d, sizeof(d));
        memcpy(turn, d, sizeof(d));
        turn[3] = centre[1] * d[2] - centre[2] * d[1];
        turn[4] = centre[2] * d[0] - centre[0] * d[2];
        turn[5] = centre[0] * d[1] - centre[1] * d[0];
        memcpy(turn_at_origin, d, sizeof(d));
        turn_at_origin[3] = turn_at_origin[4] = turn_at_origin[5] = 0.0;
        across[0] = across[1] = across[2] = 0.0;
        across[3] = 0.0, across[4] = 0.0, across[5] = 1.0;
        for (mode = 1; mode < 3; ++mode) {
            kissm_matcher *m = make_matcher(k_modes[mode], 0.25, 2);
            const kissm_points s = scn_points(&a), t = scn_points(&b);
            kissm_result r;
            REQUIRE(m != NULL);
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
            check_refined_fields("pipe", &r, 30);
            CHECK_EQ_INT(r.valid, 0);
            CHECK_MSG(r.reason == KISSM_REASON_UNCONSTRAINED, "pipe, %s: reason %d", k_mode_names[mode], (int)r.reason);
            {
                double free_dirs[2][6];
                memcpy(free_dirs[0], slide, sizeof slide);
                memcpy(free_dirs[1], turn, sizeof turn);
                check_degenerate("pipe", &r, (const double(*)[6])free_dirs, 2, k_modes[mode], 0.25, &s, &t, initial);
            }
            {
                const double s_slide = information_share(r.information, slide);
                const double s_turn = information_share(r.information, turn);
                const double s_origin = information_share(r.information, turn_at_origin);
                const double s_across = information_share(r.information, across);
                fprintf(stderr,
                        "  pipe, %s: condition %.3g, information share of slide %.3g, turn %.3g, turn about "
                        "the origin %.3g, across %.3g\n",
                        k_mode_names[mode], r.refine_condition, s_slide, s_turn, s_origin, s_across);
                CHECK_MSG(s_slide < 0.01 * s_across, "pipe, %s: slide %g, across %g", k_mode_names[mode], s_slide,
                          s_across);
                CHECK_MSG(s_turn < 0.01 * s_across, "pipe, %s: turn about its axis %g, across %g", k_mode_names[mode],
                          s_turn, s_across);
                CHECK_MSG(s_turn < 0.01 * s_origin, "pipe, %s: turn about its axis %g, about the origin %g",
                          k_mode_names[mode], s_turn, s_origin);
            }
            kissm_destroy(m);
        }
    }
    scn_cloud_free(&a);
    scn_cloud_free(&b);
}

/* The refined rotation rule: 2 times the rotation sigma the information states, against max_rotation_uncertainty.
 * A bound 4 % above it keeps the pose valid, 4 % below refuses it (UNCERTAIN_ROTATION) with the same pose. */
static void test_refined_rotation_rule(void) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    double initial[16], sigma;
    kissm_result base, r;
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = NULL;
    int k;
    scn_pose_to_matrix(&g_pair.truth, initial);
    c.refine_mode = KISSM_REFINE_GICP;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(&base);
    CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &base), KISSM_OK);
    kissm_destroy(m);
    CHECK_MSG(base.valid == 1, "reason %d", (int)base.reason);
    sigma = information_rotation_sigma(base.information);
    CHECK_MSG(sigma > 0.0 && 2.0 * sigma < c.max_rotation_uncertainty, "sigma %g", sigma);
    for (k = 0; k < 2; ++k) {
        c.max_rotation_uncertainty = (k == 0 ? 2.08 : 1.92) * sigma;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        scn_result_poison(&r);
        CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
        check_prior_rule(k == 0 ? "rotation bound above 2 sigma" : "rotation bound below 2 sigma", &r, &c);
        CHECK_EQ_INT(r.valid, k == 0);
        if (k == 1) CHECK_EQ_INT(r.reason, KISSM_REASON_UNCERTAIN_ROTATION);
        CHECK(memcmp(r.transform, base.transform, sizeof r.transform) == 0);
        kissm_destroy(m);
    }
}

/* Priors within 10 degrees and 3 voxels of the truth (docs/refinement.md: kissm_refine converges to the right
 * pose from these): every one valid and right, in both costs. */
static void test_near_priors_valid_and_right(void) {
    const double axes[4][3] = {{0.0, 0.0, 1.0}, {1.0, 2.0, 3.0}, {0.0, 1.0, 0.0}, {1.0, 0.0, 0.0}};
    const double degs[3] = {4.0, 7.0, 10.0};
    const double shifts[3][3] = {{0.6, 0.0, 0.0}, {0.8, -0.6, 0.0}, {0.0, 1.0, 0.5}};
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    const kissm_config c = scn_config(VOXEL);
    int mode, k, right = 0, total = 0;
    for (mode = 1; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], VOXEL, 2);
        REQUIRE(m != NULL);
        for (k = 0; k < 12; ++k) {
            double initial[16];
            kissm_result r;
            char label[96];
            perturbed(&g_pair.truth, axes[k % 4], degs[k % 3], shifts[(k / 4) % 3], initial);
            sprintf(label, "%s from %.0f deg, %.2f m", k_mode_names[mode], matrix_rot_err(initial, &g_pair.truth),
                    matrix_trans_err(initial, &g_pair.truth));
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
            check_refined_fields(label, &r, c.refine_max_iterations);
            check_prior_rule(label, &r, &c);
            ++total;
            right += r.valid == 1 && rot_err(&r, &g_pair.truth) < k_max_rot_deg[mode] &&
                     trans_err(&r, &g_pair.truth) < k_max_trans[mode];
            CHECK_MSG(r.valid == 1, "%s: valid 0, reason %d", label, (int)r.reason);
            CHECK_MSG(rot_err(&r, &g_pair.truth) < k_max_rot_deg[mode] &&
                          trans_err(&r, &g_pair.truth) < k_max_trans[mode],
                      "%s: %.3f deg / %.3f m off", label, rot_err(&r, &g_pair.truth), trans_err(&r, &g_pair.truth));
        }
        kissm_destroy(m);
    }
    CHECK_EQ_INT(right, total);
}

/* Priors 45 and 90 degrees and metres off: outside the basin. The result follows the rule from the numbers it
 * reports, and no wrong local optimum is valid: the residual test refuses the ones that pass the others. */
static void test_far_priors(void) {
    const double axes[4][3] = {{0.0, 0.0, 1.0}, {0.0, 0.0, 1.0}, {1.0, 2.0, 3.0}, {1.0, 0.0, 0.0}};
    const double degs[4] = {45.0, 90.0, 45.0, 90.0};
    const double shifts[4][3] = {{1.0, 0.0, 0.0}, {2.0, -1.0, 0.0}, {0.0, 3.0, 0.5}, {2.0, -1.0, 0.0}};
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    const kissm_config c = scn_config(VOXEL);
    int mode, k, wrong_valid = 0, refused = 0;
    for (mode = 1; mode < 3; ++mode) {
        kissm_matcher *m = make_matcher(k_modes[mode], VOXEL, 2);
        REQUIRE(m != NULL);
        for (k = 0; k < 4; ++k) {
            double initial[16];
            kissm_result r;
            perturbed(&g_pair.truth, axes[k], degs[k], shifts[k], initial);
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_refine(m, &s, &t, initial, &r), KISSM_OK);
            check_refined_fields("far prior", &r, c.refine_max_iterations);
            check_prior_rule("far prior", &r, &c);
            refused += r.valid == 0;
            if (r.valid && !(rot_err(&r, &g_pair.truth) < 2.0 && trans_err(&r, &g_pair.truth) < 0.5)) {
                ++wrong_valid;
                fprintf(stderr,
                        "  note: %s from %.0f deg off ended valid %.2f deg / %.2f m off (condition %.3g, "
                        "overlap %.3f, %d iterations)\n",
                        k_mode_names[mode], degs[k], rot_err(&r, &g_pair.truth), trans_err(&r, &g_pair.truth),
                        r.refine_condition, r.overlap, (int)r.refine_iterations);
            }
        }
        kissm_destroy(m);
    }
    fprintf(stderr, "  far priors: %d of 8 refused, %d valid with a wrong pose\n", refused, wrong_valid);
    CHECK_EQ_INT(wrong_valid, 0);
}

/* ---------------------------------------------------------------------------------------------- */
/* An older caller's structs                                                                        */
/* ---------------------------------------------------------------------------------------------- */

/* The first OLD_RESULT_SIZE bytes of a and b, timings aside, are the same. */
static int old_part_equal(const kissm_result *a, const kissm_result *b) {
    kissm_result x, y;
    memset(&x, 0, sizeof(x));
    memset(&y, 0, sizeof(y));
    memcpy(&x, a, OLD_RESULT_SIZE);
    memcpy(&y, b, OLD_RESULT_SIZE);
    x.struct_size = y.struct_size = 0;
    return scn_result_equal(&x, &y);
}

static int tail_untouched(const kissm_result *r) {
    const unsigned char *bytes = (const unsigned char *)r;
    size_t k;
    for (k = OLD_RESULT_SIZE; k < sizeof(*r); ++k)
        if (bytes[k] != 0x5A) return 0;
    return 1;
}

static void old_result(kissm_result *r) {
    memset(r, 0x5A, sizeof(*r));
    r->struct_size = OLD_RESULT_SIZE;
}

static void test_older_callers(void) {
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    double initial[16];
    kissm_config old_c, back;
    kissm_matcher *old_m = NULL, *new_m = make_matcher(KISSM_REFINE_NONE, VOXEL, 0), *gicp = NULL;
    kissm_features *fs = NULL, *ft = NULL;
    kissm_result full, r;
    const unsigned char *cbytes = (const unsigned char *)&old_c;
    size_t k;
    int tail_ok = 1;
    REQUIRE(offsetof(kissm_config, refine_mode) == OLD_CONFIG_SIZE);
    REQUIRE(offsetof(kissm_result, coarse_transform) == OLD_RESULT_SIZE);
    REQUIRE(new_m != NULL);
    scn_pose_to_matrix(&g_pair.truth, initial);

    /* a 152-byte config: initialised, validated and used without a byte past 152 read or written */
    memset(&old_c, 0x5A, sizeof(old_c));
    CHECK_EQ_INT(kissm_config_init(&old_c, OLD_CONFIG_SIZE), KISSM_OK);
    for (k = OLD_CONFIG_SIZE; k < sizeof(old_c); ++k) tail_ok &= cbytes[k] == 0x5A;
    CHECK_MSG(tail_ok, "kissm_config_init wrote past 152 bytes");
    CHECK_EQ_INT(old_c.struct_size, OLD_CONFIG_SIZE);
    old_c.voxel_size = VOXEL;
    CHECK_EQ_INT(kissm_config_validate(&old_c), KISSM_OK);
    CHECK_MSG(kissm_create(&old_c, &old_m) == KISSM_OK, "%s", kissm_last_error_message());
    REQUIRE(old_m != NULL);
    /* the fields it lacks read back as the defaults */
    {
        const kissm_config d = scn_config(VOXEL);
        memset(&back, 0, sizeof(back));
        back.struct_size = sizeof(back);
        CHECK_EQ_INT(kissm_get_config(old_m, &back), KISSM_OK);
        CHECK_EQ_INT(back.refine_mode, d.refine_mode);
        CHECK_EQ_INT(back.refine_max_iterations, d.refine_max_iterations);
        CHECK(back.refine_max_distance_gain == d.refine_max_distance_gain);
        CHECK(back.refine_kernel_gain == d.refine_kernel_gain);
        CHECK(back.refine_rotation_epsilon == d.refine_rotation_epsilon);
        CHECK(back.refine_translation_epsilon_gain == d.refine_translation_epsilon_gain);
        CHECK(back.min_overlap == d.min_overlap);
        CHECK(back.max_rotation_uncertainty == d.max_rotation_uncertainty);
        CHECK(back.min_inlier_coverage == d.min_inlier_coverage);
        CHECK_EQ_INT(back.refine_min_inliers, d.refine_min_inliers);
        CHECK_EQ_INT(back.reserved1, 0);
        CHECK(back.min_refine_condition == d.min_refine_condition);
        /* and read back into an old struct: nothing past 152 written */
        memset(&back, 0x5A, sizeof(back));
        back.struct_size = OLD_CONFIG_SIZE;
        CHECK_EQ_INT(kissm_get_config(old_m, &back), KISSM_OK);
        cbytes = (const unsigned char *)&back;
        tail_ok = 1;
        for (k = OLD_CONFIG_SIZE; k < sizeof(back); ++k) tail_ok &= cbytes[k] == 0x5A;
        CHECK_MSG(tail_ok, "kissm_get_config wrote past 152 bytes");
    }

    /* the new entry points with an old config: the same results as the default config's */
    scn_result_poison(&full);
    CHECK_EQ_INT(kissm_refine(new_m, &s, &t, initial, &full), KISSM_OK);
    CHECK_EQ_INT(full.valid, 1);
    scn_result_poison(&r);
    CHECK_EQ_INT(kissm_refine(old_m, &s, &t, initial, &r), KISSM_OK);
    CHECK(scn_result_equal(&full, &r));

    /* a 440-byte result: the fields it has, nothing past them */
    old_result(&r);
    CHECK_EQ_INT(kissm_refine(old_m, &s, &t, initial, &r), KISSM_OK);
    CHECK_EQ_INT(r.struct_size, OLD_RESULT_SIZE);
    CHECK(old_part_equal(&full, &r));
    CHECK_MSG(tail_untouched(&r), "kissm_refine wrote past 440 bytes");
    REQUIRE(kissm_features_compute(old_m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(old_m, &t, &ft) == KISSM_OK);
    old_result(&r);
    CHECK_EQ_INT(kissm_refine_features(old_m, fs, ft, initial, &r), KISSM_OK);
    CHECK_EQ_INT(r.valid, 1);
    CHECK(memcmp(r.transform, full.transform, sizeof(full.transform)) == 0);
    CHECK_MSG(tail_untouched(&r), "kissm_refine_features wrote past 440 bytes");
    /* kissm_register with refinement into an old result */
    gicp = make_matcher(KISSM_REFINE_GICP, VOXEL, 2);
    REQUIRE(gicp != NULL);
    scn_result_poison(&full);
    CHECK_EQ_INT(kissm_register(gicp, &s, &t, &full), KISSM_OK);
    old_result(&r);
    CHECK_EQ_INT(kissm_register(gicp, &s, &t, &r), KISSM_OK);
    CHECK(old_part_equal(&full, &r));
    CHECK_MSG(tail_untouched(&r), "kissm_register with refinement wrote past 440 bytes");
    /* failing calls reset only the old part */
    {
        double bad[16];
        memcpy(bad, initial, sizeof(bad));
        bad[5] = NAN;
        old_result(&r);
        CHECK_EQ_INT(kissm_refine(old_m, &s, &t, bad, &r), KISSM_ERR_INVALID_ARGUMENT);
        CHECK_EQ_INT(r.valid, 0);
        CHECK(isnan(r.transform[0]));
        CHECK_MSG(tail_untouched(&r), "a failed kissm_refine wrote past 440 bytes");
        old_result(&r);
        CHECK_EQ_INT(kissm_refine_features(old_m, fs, ft, NULL, &r), KISSM_ERR_NULL_ARGUMENT);
        CHECK(tail_untouched(&r));
        /* result_init of an old result */
        old_result(&r);
        CHECK_EQ_INT(kissm_result_init(&r, OLD_RESULT_SIZE), KISSM_OK);
        CHECK(isnan(r.transform[0]) && r.valid == 0);
        CHECK(tail_untouched(&r));
    }
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_destroy(old_m);
    kissm_destroy(new_m);
    kissm_destroy(gicp);
}

int main(void) {
    scn_make_pair(&g_pair, 3, 15.0, 0.01);
    RUN_TEST(test_refine_from_perturbed_truth);
    RUN_TEST(test_nearly_rigid_initial_accepted);
    RUN_TEST(test_refine_features);
    RUN_TEST(test_georeferenced_shift);
    RUN_TEST(test_register_with_refine);
    RUN_TEST(test_min_overlap);
    RUN_TEST(test_no_overlap_at_initial_pose);
    RUN_TEST(test_corridor);
    RUN_TEST(test_plane_and_pipe);
    RUN_TEST(test_near_priors_valid_and_right);
    RUN_TEST(test_far_priors);
    RUN_TEST(test_refined_rotation_rule);
    RUN_TEST(test_older_callers);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
