/* SPDX-License-Identifier: MIT */
/* The pose graph through the C API: a loop of poses on a circle (odometry edges trusted, loop closures robust)
 * recovered exactly from consistent edges; wrong loop closures rejected without moving the map; unplaced nodes;
 * the solution's lifetime (none before kissm_pose_graph_optimize, forgotten by the next edge); bitwise
 * repeatability; a cancel request made before the call is dropped. C99. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"

#define N 24
#define PI 3.14159265358979323846

/* Row-major 4x4 rigid transforms. */
static void rot_axis_angle(double ax, double ay, double az, double m[16]) {
    double angle = sqrt(ax * ax + ay * ay + az * az), c, s, x, y, z, C;
    memset(m, 0, 16 * sizeof(double));
    m[15] = 1.0;
    if (angle < 1e-300) {
        m[0] = m[5] = m[10] = 1.0;
        return;
    }
    x = ax / angle, y = ay / angle, z = az / angle, c = cos(angle), s = sin(angle), C = 1.0 - c;
    m[0] = c + x * x * C, m[1] = x * y * C - z * s, m[2] = x * z * C + y * s;
    m[4] = y * x * C + z * s, m[5] = c + y * y * C, m[6] = y * z * C - x * s;
    m[8] = z * x * C - y * s, m[9] = z * y * C + x * s, m[10] = c + z * z * C;
}

static void mul(const double a[16], const double b[16], double out[16]) {
    double r[16];
    int i, j, k;
    for (i = 0; i < 4; ++i)
        for (j = 0; j < 4; ++j) {
            r[4 * i + j] = 0.0;
            for (k = 0; k < 4; ++k) r[4 * i + j] += a[4 * i + k] * b[4 * k + j];
        }
    memcpy(out, r, sizeof(r));
}

static void inv(const double a[16], double out[16]) {
    double r[16] = {0};
    int i, j;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) r[4 * i + j] = a[4 * j + i];
        r[4 * i + 3] = -(a[i] * a[3] + a[4 + i] * a[7] + a[8 + i] * a[11]);
    }
    r[15] = 1.0;
    memcpy(out, r, sizeof(r));
}

static double g_truth[N][16];
static const double k_info_diag[6] = {1e4, 1e4, 1e4, 1e2, 1e2, 1e2};

static void make_truth(void) {
    int i;
    for (i = 0; i < N; ++i) {
        double a = 2.0 * PI * i / N;
        rot_axis_angle(0.03 * sin(2.0 * a), 0.02, a, g_truth[i]);
        g_truth[i][3] = 15.0 * cos(a), g_truth[i][7] = 15.0 * sin(a), g_truth[i][11] = 0.3 * sin(3.0 * a);
    }
}

/* inv(X_t) X_s */
static void relative(int s, int t, double out[16]) {
    double it[16];
    inv(g_truth[t], it);
    mul(it, g_truth[s], out);
}

static void information(double info[36]) {
    int k;
    memset(info, 0, 36 * sizeof(double));
    for (k = 0; k < 6; ++k) info[7 * k] = k_info_diag[k];
}

/* Odometry i+1 -> i (trusted) and loop closures i -> i+4 every 2 (robust), N-1 -> 0 closing the loop. Returns the
 * number of edges; wrong[e] = 1 for the loop closures replaced by a far pose when `corrupt`. */
static int build(kissm_pose_graph *g, int corrupt, int wrong[64]) {
    double T[16], info[36];
    int i, e = 0, robust = 0;
    uint64_t id;
    information(info);
    for (i = 0; i + 1 < N; ++i) {
        relative(i + 1, i, T);
        CHECK_EQ_INT(kissm_pose_graph_add_edge(g, (uint64_t)(i + 1), (uint64_t)i, T, info, 0, &id), KISSM_OK);
        CHECK(id == (uint64_t)e);
        wrong[e++] = 0;
    }
    for (i = 0; i <= N; i += 2) {
        int s = i % N, t = (i + 4) % N;
        if (i == N) s = N - 1, t = 0;
        relative(s, t, T);
        wrong[e] = 0;
        if (corrupt && robust++ % 3 == 0) { /* a third of the loop closures: 40 degrees and 12 m off */
            double off[16];
            rot_axis_angle(0.3, -0.5, 0.4, off);
            off[3] = 7.0, off[7] = -9.0, off[11] = 3.0;
            mul(T, off, T);
            wrong[e] = 1;
        }
        CHECK_EQ_INT(kissm_pose_graph_add_edge(g, (uint64_t)s, (uint64_t)t, T, info, 1, NULL), KISSM_OK);
        ++e;
    }
    return e;
}

static void test_consistent_loop(void) {
    kissm_pose_graph *g = NULL;
    double poses[16 * N], expected[16], ia[16];
    uint8_t placed[N], accepted[64];
    uint64_t comp[N];
    double residuals[64];
    int wrong[64], m, i, k;
    REQUIRE(kissm_pose_graph_create(N, &g) == KISSM_OK);
    m = build(g, 0, wrong);
    CHECK(kissm_pose_graph_num_nodes(g) == N && kissm_pose_graph_num_edges(g) == (uint64_t)m);
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, KISSM_POSE_GRAPH_DEFAULT_BOUND), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_poses(g, poses, placed, comp), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_edges(g, accepted, residuals), KISSM_OK);
    inv(g_truth[0], ia);
    for (i = 0; i < N; ++i) {
        mul(ia, g_truth[i], expected);
        CHECK(placed[i] == 1 && comp[i] == 0);
        for (k = 0; k < 16; ++k) CHECK_NEAR(poses[16 * i + k], expected[k], 1e-9);
    }
    for (i = 0; i < m; ++i) CHECK(accepted[i] == 1 && residuals[i] < 1e-12);
    /* the anchor elsewhere: the same poses seen from node 5 */
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 5, KISSM_POSE_GRAPH_DEFAULT_BOUND), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_poses(g, poses, NULL, NULL), KISSM_OK);
    inv(g_truth[5], ia);
    for (i = 0; i < N; ++i) {
        mul(ia, g_truth[i], expected);
        for (k = 0; k < 16; ++k) CHECK_NEAR(poses[16 * i + k], expected[k], 1e-9);
    }
    kissm_pose_graph_destroy(g);
}

static void test_wrong_loop_closures(void) {
    kissm_pose_graph *g = NULL;
    double poses[16 * N], expected[16], ia[16], residuals[64];
    uint8_t placed[N], accepted[64];
    int wrong[64], m, i, k, num_wrong = 0;
    REQUIRE(kissm_pose_graph_create(N, &g) == KISSM_OK);
    m = build(g, 1, wrong);
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, KISSM_POSE_GRAPH_DEFAULT_BOUND), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_poses(g, poses, placed, NULL), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_edges(g, accepted, residuals), KISSM_OK);
    for (i = 0; i < m; ++i) {
        num_wrong += wrong[i];
        CHECK_MSG(accepted[i] == !wrong[i], "edge %d (wrong %d): accepted %d, residual %g", i, wrong[i], accepted[i],
                  residuals[i]);
        CHECK(wrong[i] ? residuals[i] > KISSM_POSE_GRAPH_DEFAULT_BOUND : residuals[i] < 1e-12);
    }
    CHECK(num_wrong >= 4);
    inv(g_truth[0], ia);
    for (i = 0; i < N; ++i) { /* the right edges are consistent: the map is exact */
        mul(ia, g_truth[i], expected);
        CHECK(placed[i] == 1);
        for (k = 0; k < 16; ++k) CHECK_NEAR(poses[16 * i + k], expected[k], 1e-9);
    }
    kissm_pose_graph_destroy(g);
}

static void test_unplaced_and_lifetime(void) {
    kissm_pose_graph *g = NULL;
    double T[16], info[36], poses[16 * 4];
    uint8_t placed[4], accepted[2];
    uint64_t comp[4];
    double residuals[2];
    int k;
    information(info);
    rot_axis_angle(0.1, 0.0, 0.0, T);
    REQUIRE(kissm_pose_graph_create(4, &g) == KISSM_OK);
    /* no solution yet */
    CHECK_EQ_INT(kissm_pose_graph_poses(g, poses, NULL, NULL), KISSM_ERR_INVALID_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "graph") != NULL);
    CHECK_EQ_INT(kissm_pose_graph_add_edge(g, 1, 0, T, info, 1, NULL), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_add_edge(g, 3, 2, T, info, 0, NULL), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, KISSM_POSE_GRAPH_DEFAULT_BOUND), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_poses(g, poses, placed, comp), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_edges(g, accepted, residuals), KISSM_OK);
    CHECK(placed[0] == 1 && placed[1] == 1 && placed[2] == 0 && placed[3] == 0);
    CHECK(comp[0] == 0 && comp[1] == 0 && comp[2] == 2 && comp[3] == 2);
    for (k = 0; k < 16; ++k) CHECK(isnan(poses[32 + k]) && isnan(poses[48 + k]));
    for (k = 0; k < 16; ++k) CHECK_NEAR(poses[16 + k], T[k], 1e-12); /* X_1 = X_0 T */
    CHECK(accepted[0] == 1 && accepted[1] == 0 && isnan(residuals[1]));
    /* a new edge forgets the solution */
    CHECK_EQ_INT(kissm_pose_graph_add_edge(g, 2, 1, T, info, 1, NULL), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_edges(g, accepted, NULL), KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(kissm_pose_graph_optimize(g, 0, KISSM_POSE_GRAPH_DEFAULT_BOUND), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_poses(g, NULL, placed, NULL), KISSM_OK);
    CHECK(placed[2] == 1 && placed[3] == 1);
    kissm_pose_graph_destroy(g);
}

static void test_repeatable_and_cancel_dropped(void) {
    kissm_pose_graph *a = NULL, *b = NULL;
    double pa[16 * N], pb[16 * N], ra[64], rb[64];
    int wrong[64], m;
    REQUIRE(kissm_pose_graph_create(N, &a) == KISSM_OK && kissm_pose_graph_create(N, &b) == KISSM_OK);
    m = build(a, 1, wrong);
    build(b, 1, wrong);
    kissm_pose_graph_cancel(b); /* before the call: dropped */
    CHECK_EQ_INT(kissm_pose_graph_optimize(a, 2, 10.0), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_optimize(b, 2, 10.0), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_poses(a, pa, NULL, NULL), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_poses(b, pb, NULL, NULL), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_edges(a, NULL, ra), KISSM_OK);
    CHECK_EQ_INT(kissm_pose_graph_edges(b, NULL, rb), KISSM_OK);
    CHECK(memcmp(pa, pb, sizeof(pa)) == 0 && memcmp(ra, rb, (size_t)m * sizeof(double)) == 0);
    kissm_pose_graph_cancel(NULL); /* harmless */
    kissm_pose_graph_destroy(a);
    kissm_pose_graph_destroy(b);
    kissm_pose_graph_destroy(NULL);
    CHECK(kissm_pose_graph_num_nodes(NULL) == 0 && kissm_pose_graph_num_edges(NULL) == 0);
}

int main(void) {
    make_truth();
    RUN_TEST(test_consistent_loop);
    RUN_TEST(test_wrong_loop_closures);
    RUN_TEST(test_unplaced_and_lifetime);
    RUN_TEST(test_repeatable_and_cancel_dropped);
    return TEST_SUMMARY();
}
