/* SPDX-License-Identifier: MIT */
/* abi_static_clash: a C program that links libkissm.a statically and defines, as its own global functions
 * and variables, names a point cloud program plausibly has and that kissm uses internally (voxelize,
 * compute_fpfh, match_descriptors, radius_neighbors, ...), plus its own C++ kissm::detail code
 * (static_clash_host.cpp). It must link (the build fails otherwise) and both sides must keep their own
 * behaviour: the host's functions return the host's values, and kissm's internal failures keep their
 * status codes and messages (a host symbol silently replacing one of kissm's would change them).
 * check_static_symbols.cmake checks the other half: libkissm.a defines no global symbol outside kissm_*
 * and kissm's versioned C++ namespace. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "splitmix64.h"

int host_cpp_self_test(void);

/* The host's own globals, named like kissm's internals and options. */
int num_threads = 3;
double voxel_size = 0.25;

int voxelize(const double *xyz, int n, double size);
int voxelize(const double *xyz, int n, double size) { return xyz != NULL && size > 0.0 ? n / 2 : -1; }
int radius_neighbors(int point, double radius);
int radius_neighbors(int point, double radius) { return point + (int)radius; }
int estimate_normals(int n);
int estimate_normals(int n) { return 3 * n; }
int compute_fpfh(int n);
int compute_fpfh(int n) { return 33 * n; }
int match_descriptors(int a, int b);
int match_descriptors(int a, int b) { return a < b ? a : b; }
int max_kcore(int n);
int max_kcore(int n) { return n - 1; }
int core_numbers(int n);
int core_numbers(int n) { return n + 1; }
int solve_pose(double *pose);
int solve_pose(double *pose) {
    pose[0] = 42.0;
    return 7;
}
int check_validity(int inliers);
int check_validity(int inliers) { return inliers >= 15; }
int parse_ply(const char *path);
int parse_ply(const char *path) { return (int)strlen(path); }
int read_file_bytes(const char *path);
int read_file_bytes(const char *path) { return -(int)strlen(path); }
int register_described(int a);
int register_described(int a) { return a * 2; }

static void test_host_functions_are_the_hosts(void) {
    double xyz[6] = {0, 0, 0, 1, 1, 1};
    double pose = 0.0;
    CHECK_EQ_INT(voxelize(xyz, 10, voxel_size), 5);
    CHECK_EQ_INT(radius_neighbors(4, 2.0), 6);
    CHECK_EQ_INT(estimate_normals(2), 6);
    CHECK_EQ_INT(compute_fpfh(2), 66);
    CHECK_EQ_INT(match_descriptors(3, 9), 3);
    CHECK_EQ_INT(max_kcore(5), 4);
    CHECK_EQ_INT(core_numbers(5), 6);
    CHECK_EQ_INT(solve_pose(&pose), 7);
    CHECK(pose == 42.0);
    CHECK_EQ_INT(check_validity(20), 1);
    CHECK_EQ_INT(parse_ply("abc"), 3);
    CHECK_EQ_INT(read_file_bytes("abcd"), -4);
    CHECK_EQ_INT(register_described(21), 42);
    CHECK_EQ_INT(num_threads, 3);
    CHECK_EQ_INT(host_cpp_self_test(), 0);
}

/* A small scene: three orthogonal walls of a 4 m box corner, with a few bumps so that it has features. */
#define SIDE 24
static double g_source[3 * SIDE * SIDE * 3], g_target[3 * SIDE * SIDE * 3];

static size_t make_scene(void) {
    uint64_t state = 12345;
    size_t n = 0;
    int wall, i, j;
    const double c = cos(0.3), s = sin(0.3);
    for (wall = 0; wall < 3; ++wall)
        for (i = 0; i < SIDE; ++i)
            for (j = 0; j < SIDE; ++j) {
                const double u = 0.17 * i, v = 0.17 * j;
                const double bump = 0.3 * sin(1.3 * u + 0.4 * wall) * cos(0.9 * v);
                const double noise = 0.002 * (splitmix64_uniform(&state) - 0.5);
                double *p = &g_source[3 * n], *q = &g_target[3 * n];
                if (wall == 0)
                    p[0] = u, p[1] = v, p[2] = bump + noise;
                else if (wall == 1)
                    p[0] = u, p[1] = bump + noise, p[2] = v;
                else
                    p[0] = bump + noise, p[1] = u, p[2] = v;
                /* target = Rz(0.3) p + (0.5, -0.2, 0.1) */
                q[0] = c * p[0] - s * p[1] + 0.5;
                q[1] = s * p[0] + c * p[1] - 0.2;
                q[2] = p[2] + 0.1;
                ++n;
            }
    return n;
}

static kissm_points view(const double *xyz, size_t n) {
    kissm_points p;
    p.data = xyz;
    p.count = n;
    p.stride_bytes = 0;
    p.scalar_type = KISSM_SCALAR_FLOAT64;
    p.reserved = 0;
    return p;
}

static void test_library_still_works(void) {
    const size_t n = make_scene();
    const kissm_points source = view(g_source, n), target = view(g_target, n);
    kissm_config config;
    kissm_matcher *m = NULL;
    kissm_result r;
    kissm_cloud *cloud = NULL;

    REQUIRE(kissm_config_init(&config, (uint32_t)sizeof config) == KISSM_OK);
    config.voxel_size = 0.2;
    config.num_threads = 2;
    REQUIRE(kissm_create(&config, &m) == KISSM_OK);
    r.struct_size = (uint32_t)sizeof r;
    CHECK_EQ_INT(kissm_register(m, &source, &target, &r), KISSM_OK);
    CHECK(r.num_source_voxels > 0 && r.num_source_keypoints > 0);

    /* Internal failures thrown and caught inside the library keep their status codes and kissm's own messages
     * (a host symbol that replaced one of kissm's, such as its inline fail(), would show up here). */
    CHECK_EQ_INT(kissm_read_points("/nonexistent/kissm/abi/cloud.ply", KISSM_FORMAT_AUTO, &cloud), KISSM_ERR_IO);
    CHECK_MSG(strstr(kissm_last_error_message(), "host:") == NULL, "message: %s", kissm_last_error_message());
    CHECK(cloud == NULL);
    r.struct_size = (uint32_t)sizeof r;
    CHECK_EQ_INT(kissm_register(m, &source, NULL, &r), KISSM_ERR_NULL_ARGUMENT);
    config.voxel_size = -1.0;
    CHECK_EQ_INT(kissm_config_validate(&config), KISSM_ERR_INVALID_ARGUMENT);
    {
        kissm_points tiny = view(g_source, 2);
        CHECK_EQ_INT(kissm_register(m, &tiny, &target, &r), KISSM_ERR_TOO_FEW_POINTS);
    }
    kissm_destroy(m);
}

int main(void) {
    RUN_TEST(test_host_functions_are_the_hosts);
    RUN_TEST(test_library_still_works);
    return TEST_SUMMARY();
}
