/* SPDX-License-Identifier: MIT */
/* The ground-vehicle options through the C API: kissm_ground_mask (labels, bad input, determinism, another up),
 * kissm_config_preset, suppression in registration (counts, features mismatch, a wrong up never gives a wrong
 * valid pose) and rotation_dof = 1 (a rotation exactly about up; a tilted pair is never valid). C99. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.3
#define GROUND_Z (-1.7) /* the yard scene's ground (scenes.c) */
#define PI 3.14159265358979323846

static scn_cloud g_scene;

static int msg_has(const char *word) { return strstr(kissm_last_error_message(), word) != NULL; }

/* Setup that cannot go on after a failure: the test program stops. */
static void must(int ok, const char *what) {
    if (ok) return;
    fprintf(stderr, "setup failed: %s: %s\n", what, kissm_last_error_message());
    exit(1);
}

static kissm_matcher *make_matcher(kissm_config c) {
    kissm_matcher *m = NULL;
    must(kissm_create(&c, &m) == KISSM_OK, "kissm_create");
    return m;
}

static uint8_t *mask_of(kissm_config c, const scn_cloud *cloud) {
    kissm_matcher *m = make_matcher(c);
    kissm_points p = scn_points(cloud);
    uint8_t *mask = (uint8_t *)malloc(cloud->count);
    must(mask != NULL, "malloc");
    CHECK_EQ_INT(kissm_ground_mask(m, &p, mask), KISSM_OK);
    kissm_destroy(m);
    return mask;
}

/* Ground points (on the plane, 3-12 m from the sensor) found, and raised points (box tops, walls above 0.5 m)
 * not called ground. `up` is the scene's up direction as the cloud sees it. */
static void check_labels(const char *label, const scn_cloud *cloud, const uint8_t *mask, const scn_cloud *world) {
    size_t i, ground = 0, found = 0, raised = 0, wrong = 0;
    for (i = 0; i < cloud->count; ++i) {
        const double *w = world->xyz + 3 * i; /* the same point in the scene's frame */
        const double range = sqrt(w[0] * w[0] + w[1] * w[1]);
        CHECK(mask[i] == 0 || mask[i] == 1);
        if (fabs(w[2] - GROUND_Z) < 0.05 && range > 3.0 && range < 12.0) {
            ++ground;
            found += mask[i];
        } else if (w[2] > GROUND_Z + 0.5) {
            ++raised;
            wrong += mask[i];
        }
    }
    REQUIRE(ground > 1000 && raised > 1000);
    CHECK_MSG((double)found >= 0.9 * (double)ground, "%s: %zu of %zu ground points found", label, found, ground);
    CHECK_MSG((double)wrong <= 0.02 * (double)raised, "%s: %zu of %zu raised points called ground", label, wrong,
              raised);
}

static void test_mask_labels_and_threads(void) {
    kissm_config c = scn_config(VOXEL);
    uint8_t *one, *two;
    c.num_threads = 1;
    one = mask_of(c, &g_scene);
    c.num_threads = 2;
    two = mask_of(c, &g_scene);
    check_labels("scene", &g_scene, one, &g_scene);
    CHECK(memcmp(one, two, g_scene.count) == 0);
    /* The mask does not depend on config.suppression. */
    c.suppression = KISSM_SUPPRESS_GROUND;
    free(two);
    two = mask_of(c, &g_scene);
    CHECK(memcmp(one, two, g_scene.count) == 0);
    free(one);
    free(two);
}

/* The scene turned so that its up is +x, with config.up = +x: the same points are ground. */
static void test_mask_other_up(void) {
    const double axis[3] = {0.0, 1.0, 0.0}, zero[3] = {0.0, 0.0, 0.0};
    scn_pose turn;
    scn_cloud turned;
    kissm_config c = scn_config(VOXEL);
    uint8_t *mask;
    scn_cloud_init(&turned);
    scn_cloud_copy(&turned, &g_scene);
    scn_pose_axis_angle(&turn, axis, PI / 2.0, zero); /* +z -> +x */
    scn_cloud_apply(&turned, &turn);
    c.up[0] = 2.0, c.up[1] = 0.0, c.up[2] = 0.0; /* any length */
    mask = mask_of(c, &turned);
    check_labels("up = +x", &turned, mask, &g_scene);
    free(mask);
    /* With the default up (+z) for that cloud, the "ground" the model finds is wrong but the call works. */
    c.up[0] = 0.0, c.up[2] = 1.0;
    mask = mask_of(c, &turned);
    free(mask);
    scn_cloud_free(&turned);
}

static void test_mask_bad_input(void) {
    kissm_config c = scn_config(VOXEL);
    kissm_matcher *m = make_matcher(c);
    kissm_points p = scn_points(&g_scene);
    uint8_t *mask = (uint8_t *)malloc(g_scene.count), *fill = (uint8_t *)malloc(g_scene.count);
    scn_cloud few, nan_cloud;
    REQUIRE(mask != NULL && fill != NULL);
    memset(fill, 0xAB, g_scene.count);
    memcpy(mask, fill, g_scene.count);
    CHECK_EQ_INT(kissm_ground_mask(NULL, &p, mask), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("matcher"));
    CHECK_EQ_INT(kissm_ground_mask(m, NULL, mask), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("points"));
    CHECK_EQ_INT(kissm_ground_mask(m, &p, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(msg_has("out_mask"));
    p.scalar_type = 7;
    CHECK_EQ_INT(kissm_ground_mask(m, &p, mask), KISSM_ERR_INVALID_ARGUMENT);
    p = scn_points(&g_scene);
    CHECK(memcmp(mask, fill, g_scene.count) == 0);

    scn_cloud_init(&few);
    scn_make_duplicates(&few, 3, 1.0, 2.0, 3.0);
    p = scn_points(&few);
    CHECK_EQ_INT(kissm_ground_mask(m, &p, mask), KISSM_ERR_TOO_FEW_POINTS);
    CHECK(memcmp(mask, fill, g_scene.count) == 0);

    /* A NaN point: refused under REJECT (mask unchanged), labelled 0 under DROP. */
    scn_cloud_init(&nan_cloud);
    scn_cloud_copy(&nan_cloud, &g_scene);
    nan_cloud.xyz[3 * 10 + 2] = NAN;
    p = scn_points(&nan_cloud);
    CHECK_EQ_INT(kissm_ground_mask(m, &p, mask), KISSM_ERR_NONFINITE);
    CHECK(memcmp(mask, fill, g_scene.count) == 0);
    kissm_destroy(m);
    c.nonfinite_policy = KISSM_NONFINITE_DROP;
    m = make_matcher(c);
    CHECK_EQ_INT(kissm_ground_mask(m, &p, mask), KISSM_OK);
    CHECK(mask[10] == 0);
    {
        size_t i, ground = 0;
        for (i = 0; i < g_scene.count; ++i) ground += mask[i];
        CHECK(ground > 1000);
    }
    /* A cloud without ground (one small blob high above the sensor): all zeros, not an error. */
    {
        const double centre[3] = {0.0, 0.0, 30.0};
        scn_cloud blob;
        scn_cloud_init(&blob);
        scn_make_blob(&blob, 3, 2000, centre, 1.0);
        p = scn_points(&blob);
        memset(mask, 1, blob.count);
        CHECK_EQ_INT(kissm_ground_mask(m, &p, mask), KISSM_OK);
        {
            size_t i, ground = 0;
            for (i = 0; i < blob.count; ++i) ground += mask[i];
            CHECK_MSG(ground == 0, "%zu blob points called ground", ground);
        }
        scn_cloud_free(&blob);
    }
    kissm_destroy(m);
    scn_cloud_free(&few);
    scn_cloud_free(&nan_cloud);
    free(mask);
    free(fill);
}

static void test_preset(void) {
    const int32_t presets[] = {KISSM_PRESET_LIDAR_VEHICLE, KISSM_PRESET_LIDAR_HANDHELD, KISSM_PRESET_INDOOR_RGBD,
                               KISSM_PRESET_OBJECT};
    const int32_t bad[] = {0, -1, 5, 1000};
    kissm_config c, before;
    size_t i;
    CHECK_EQ_INT(kissm_config_preset(NULL, KISSM_PRESET_OBJECT), KISSM_ERR_NULL_ARGUMENT);
    REQUIRE(kissm_config_init(&c, (uint32_t)sizeof c) == KISSM_OK);
    c.num_threads = 2;
    c.min_inliers = 20;
    before = c;
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        CHECK_EQ_INT(kissm_config_preset(&c, bad[i]), KISSM_ERR_INVALID_ARGUMENT);
        CHECK(msg_has("preset"));
        CHECK(memcmp(&c, &before, sizeof c) == 0);
    }
    c.struct_size = 8;
    CHECK_EQ_INT(kissm_config_preset(&c, KISSM_PRESET_OBJECT), KISSM_ERR_STRUCT_SIZE);
    c = before;
    REQUIRE(kissm_config_preset(&c, KISSM_PRESET_LIDAR_VEHICLE) == KISSM_OK);
    CHECK(c.voxel_size == 0.3);
    CHECK_EQ_INT(c.suppression, KISSM_SUPPRESS_GROUND);
    CHECK_EQ_INT(c.num_threads, 2); /* the caller's settings stay */
    CHECK_EQ_INT(c.min_inliers, 20);
    for (i = 0; i < sizeof presets / sizeof presets[0]; ++i) {
        kissm_config p = before;
        CHECK_EQ_INT(kissm_config_preset(&p, presets[i]), KISSM_OK);
        CHECK_MSG(kissm_config_validate(&p) == KISSM_OK, "preset %d: %s", (int)presets[i], kissm_last_error_message());
        CHECK(p.voxel_size > 0.0);
    }
    {
        kissm_config p = before;
        REQUIRE(kissm_config_preset(&p, KISSM_PRESET_INDOOR_RGBD) == KISSM_OK);
        CHECK(p.voxel_size == 0.05);
        CHECK_EQ_INT(p.suppression, KISSM_SUPPRESS_NONE);
    }
}

/* The standard scene seen by a second sensor at (4, 3, 0), turned by yaw_deg about z and tilt_deg about x:
 * p_target = truth (p_source). */
static void make_pair(scn_pair *pair, double yaw_deg, double tilt_deg) {
    const double z[3] = {0.0, 0.0, 1.0}, x[3] = {1.0, 0.0, 0.0}, at[3] = {4.0, 3.0, 0.0}, zero[3] = {0.0, 0.0, 0.0};
    const double keep_west[3] = {1.0, 0.0, 0.0}, keep_east[3] = {-1.0, 0.0, 0.0};
    scn_pose yaw, tilt, sensor;
    scn_cloud_init(&pair->source);
    scn_cloud_init(&pair->target);
    scn_make_scene(&pair->source, 5, 11, 25.0, 0.01);
    scn_make_scene(&pair->target, 5, 12, 25.0, 0.01);
    scn_cloud_crop(&pair->source, keep_west, 6.0);
    scn_cloud_crop(&pair->target, keep_east, 6.0);
    scn_pose_axis_angle(&yaw, z, yaw_deg * PI / 180.0, at);
    scn_pose_axis_angle(&tilt, x, tilt_deg * PI / 180.0, zero);
    scn_pose_compose(&yaw, &tilt, &sensor);
    scn_pose_inverse(&sensor, &pair->truth);
    scn_cloud_apply(&pair->target, &pair->truth);
}

static int right(const kissm_result *r, const scn_pose *truth) {
    return scn_rotation_error_deg(r->rotation, truth->R) < 2.0 && scn_translation_error(r->translation, truth->t) < 0.6;
}

static void run(kissm_config c, const scn_pair *pair, kissm_result *r) {
    kissm_matcher *m = make_matcher(c);
    kissm_points s = scn_points(&pair->source), t = scn_points(&pair->target);
    REQUIRE(kissm_result_init(r, (uint32_t)sizeof *r) == KISSM_OK);
    CHECK_EQ_INT(kissm_register(m, &s, &t, r), KISSM_OK);
    kissm_destroy(m);
}

static void test_suppression_registration(void) {
    scn_pair pair;
    kissm_config c = scn_config(VOXEL);
    kissm_result plain, suppressed, again;
    make_pair(&pair, 150.0, 0.0);
    run(c, &pair, &plain);
    CHECK(plain.num_source_suppressed == 0 && plain.num_target_suppressed == 0);
    CHECK(plain.time_suppression_ms == 0.0);
    CHECK(isnan(plain.tilt));
    c.suppression = KISSM_SUPPRESS_GROUND;
    c.num_threads = 1;
    run(c, &pair, &suppressed);
    CHECK_MSG(suppressed.valid == 1 && right(&suppressed, &pair.truth), "suppressed: valid %d reason %d",
              (int)suppressed.valid, (int)suppressed.reason);
    CHECK(suppressed.num_source_suppressed > 100 && suppressed.num_target_suppressed > 100);
    CHECK(suppressed.num_source_suppressed < suppressed.num_source_voxels);
    CHECK(suppressed.num_source_keypoints < plain.num_source_keypoints);
    CHECK(suppressed.time_suppression_ms > 0.0 && suppressed.time_suppression_ms <= suppressed.time_features_ms);
    c.num_threads = 2;
    run(c, &pair, &again);
    CHECK(memcmp(suppressed.transform, again.transform, sizeof again.transform) == 0);
    CHECK(suppressed.num_source_suppressed == again.num_source_suppressed);

    /* Features of another suppression do not match. */
    {
        kissm_config off = scn_config(VOXEL);
        kissm_matcher *m_off = make_matcher(off), *m_on = make_matcher(c);
        kissm_points s = scn_points(&pair.source), t = scn_points(&pair.target);
        kissm_features *fs = NULL, *ft = NULL;
        kissm_result r;
        REQUIRE(kissm_features_compute(m_off, &s, &fs) == KISSM_OK);
        REQUIRE(kissm_features_compute(m_on, &t, &ft) == KISSM_OK);
        REQUIRE(kissm_result_init(&r, (uint32_t)sizeof r) == KISSM_OK);
        CHECK_EQ_INT(kissm_register_features(m_on, fs, ft, &r), KISSM_ERR_FEATURES_MISMATCH);
        kissm_features_destroy(fs);
        REQUIRE(kissm_features_compute(m_on, &s, &fs) == KISSM_OK);
        CHECK_EQ_INT(kissm_register_features(m_on, fs, ft, &r), KISSM_OK);
        CHECK(memcmp(r.transform, suppressed.transform, sizeof r.transform) == 0);
        CHECK(r.num_source_suppressed == suppressed.num_source_suppressed);
        kissm_features_destroy(fs);
        kissm_features_destroy(ft);
        kissm_destroy(m_off);
        kissm_destroy(m_on);
    }
    scn_pair_free(&pair);

    /* A wrong up for the target (its sensor tilted by 40 degrees): suppression then misses or mislabels its
     * ground; the answer is right or not valid, never a wrong valid pose. */
    make_pair(&pair, 150.0, 40.0);
    run(c, &pair, &suppressed);
    CHECK_MSG(!suppressed.valid || right(&suppressed, &pair.truth), "wrong up: a wrong pose reported valid");
    scn_pair_free(&pair);
}

/* Clouds that are all ground: every voxel suppressed, so no keypoint and valid = 0 with a reason. */
static void test_all_ground(void) {
    scn_pair pair;
    kissm_config c = scn_config(VOXEL);
    kissm_result r;
    size_t i;
    c.suppression = KISSM_SUPPRESS_GROUND;
    scn_cloud_init(&pair.source);
    scn_cloud_init(&pair.target);
    for (i = 0; i < 40000; ++i) {
        const double x = -15.0 + 30.0 * (double)(i % 200) / 200.0, y = -15.0 + 30.0 * (double)(i / 200) / 200.0;
        scn_cloud_push(&pair.source, x, y, GROUND_Z + 0.01 * sin(7.0 * x + 3.0 * y));
        scn_cloud_push(&pair.target, y, -x, GROUND_Z + 0.01 * cos(5.0 * x - 2.0 * y));
    }
    scn_pose_identity(&pair.truth);
    run(c, &pair, &r);
    CHECK_EQ_INT(r.valid, 0);
    CHECK_MSG(r.reason == KISSM_REASON_TOO_FEW_FEATURES || r.reason == KISSM_REASON_TOO_FEW_CORRESPONDENCES,
              "reason %d", (int)r.reason);
    CHECK_MSG((double)r.num_source_suppressed > 0.8 * (double)r.num_source_voxels, "%llu of %llu suppressed",
              (unsigned long long)r.num_source_suppressed, (unsigned long long)r.num_source_voxels);
    scn_pair_free(&pair);
}

static void test_yaw_only(void) {
    scn_pair pair;
    kissm_config c = scn_config(VOXEL);
    kissm_result r, again;
    int i;
    c.rotation_dof = 1;
    c.num_threads = 1;
    make_pair(&pair, -120.0, 0.0);
    run(c, &pair, &r);
    CHECK_MSG(r.valid == 1 && right(&r, &pair.truth), "yaw: valid %d reason %d", (int)r.valid, (int)r.reason);
    /* Exactly about up: the third row and column are (0, 0, 1) to rounding. */
    for (i = 0; i < 2; ++i) {
        CHECK_MSG(fabs(r.rotation[3 * i + 2]) < 1e-12, "R[%d][2] = %g", i, r.rotation[3 * i + 2]);
        CHECK_MSG(fabs(r.rotation[6 + i]) < 1e-12, "R[2][%d] = %g", i, r.rotation[6 + i]);
    }
    CHECK(fabs(r.rotation[8] - 1.0) < 1e-12);
    CHECK_MSG(isfinite(r.tilt) && r.tilt < 0.01, "tilt %g", r.tilt);
    c.num_threads = 2;
    run(c, &pair, &again);
    CHECK(memcmp(r.transform, again.transform, sizeof r.transform) == 0);
    CHECK(memcmp(&r.tilt, &again.tilt, sizeof r.tilt) == 0);
    scn_pair_free(&pair);

    /* Clearly tilted pairs: yaw only cannot be right, so never valid; the tilt shows why. */
    {
        const double tilts[] = {5.0, 15.0, 40.0};
        for (i = 0; i < 3; ++i) {
            make_pair(&pair, -120.0, tilts[i]);
            run(c, &pair, &r);
            CHECK_MSG(r.valid == 0, "tilt %g: valid with rotation error %.2f deg", tilts[i],
                      scn_rotation_error_deg(r.rotation, pair.truth.R));
            if (r.reason == KISSM_REASON_TILTED) CHECK(r.tilt > c.max_rotation_uncertainty);
            scn_pair_free(&pair);
        }
    }
}

int main(void) {
    scn_cloud_init(&g_scene);
    scn_make_scene(&g_scene, 5, 11, 25.0, 0.01);
    RUN_TEST(test_mask_labels_and_threads);
    RUN_TEST(test_mask_other_up);
    RUN_TEST(test_mask_bad_input);
    RUN_TEST(test_preset);
    RUN_TEST(test_suppression_registration);
    RUN_TEST(test_all_ground);
    RUN_TEST(test_yaw_only);
    scn_cloud_free(&g_scene);
    return TEST_SUMMARY();
}
