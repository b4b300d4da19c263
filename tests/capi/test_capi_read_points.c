/* SPDX-License-Identifier: MIT */
/* kissm_read_points and the kissm_cloud accessors on files written by the test (PLY, xyz text, KITTI
 * .bin, raw float32 xyz, LAS with withheld points), error statuses, and registering clouds read through the
 * API. C99 + POSIX. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define SENTINEL_CLOUD ((kissm_cloud *)(uintptr_t)0x2468)

static char g_dir[512];
static char g_paths[32][600];
static int g_num_paths = 0;

/* Writes bytes to g_dir/name and returns the full path (remembered for clean-up). */
static const char *write_file(const char *name, const void *bytes, size_t size) {
    char *path;
    FILE *f;
    if (g_num_paths >= 32) return NULL;
    path = g_paths[g_num_paths++];
    snprintf(path, 600, "%s/%s", g_dir, name);
    f = fopen(path, "wb");
    if (f == NULL) return NULL;
    if (size > 0 && fwrite(bytes, 1, size, f) != size) {
        fclose(f);
        return NULL;
    }
    fclose(f);
    return path;
}

static const char *write_text(const char *name, const char *text) { return write_file(name, text, strlen(text)); }

static int msg_has(const char *word) {
    const char *msg = kissm_last_error_message();
    if (msg != NULL && strstr(msg, word) != NULL) return 1;
    fprintf(stderr, "  message \"%s\" does not name \"%s\"\n", msg ? msg : "(null)", word);
    return 0;
}

/* Reads path and checks that it holds exactly the n points of expected (NaN compares equal to NaN). */
static void check_read(const char *what, const char *path, int32_t format, const double *expected, size_t n) {
    kissm_cloud *cloud = NULL;
    kissm_points view;
    const double *data;
    int32_t st;
    size_t i;
    if (path == NULL) {
        CHECK_MSG(0, "%s: could not write the file", what);
        return;
    }
    st = kissm_read_points(path, format, &cloud);
    CHECK_MSG(st == KISSM_OK, "%s: status %d (%s)", what, (int)st, kissm_last_error_message());
    if (st != KISSM_OK) return;
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
    CHECK_MSG(kissm_cloud_count(cloud) == n, "%s: %llu points, expected %lu", what,
              (unsigned long long)kissm_cloud_count(cloud), (unsigned long)n);
    data = kissm_cloud_data(cloud);
    CHECK(data != NULL);
    if (data != NULL && kissm_cloud_count(cloud) == n) {
        for (i = 0; i < 3 * n; ++i) {
            const int same = (isnan(expected[i]) && isnan(data[i])) || data[i] == expected[i];
            CHECK_MSG(same, "%s: coordinate %lu is %.17g, expected %.17g", what, (unsigned long)i, data[i],
                      expected[i]);
        }
    }
    memset(&view, 0x3C, sizeof(view));
    CHECK_EQ_INT(kissm_cloud_points(cloud, &view), KISSM_OK);
    CHECK(view.data == (const void *)data);
    CHECK_EQ_INT(view.count, n);
    CHECK_EQ_INT(view.scalar_type, KISSM_SCALAR_FLOAT64);
    CHECK(view.stride_bytes == 0 || view.stride_bytes == 3 * sizeof(double));
    CHECK_EQ_INT(view.reserved, 0);
    kissm_cloud_destroy(cloud);
}

static void expect_failure(const char *what, const char *path, int32_t format, int32_t status, const char *word) {
    kissm_cloud *cloud = SENTINEL_CLOUD;
    int32_t st;
    if (path == NULL) {
        CHECK_MSG(0, "%s: could not write the file", what);
        return;
    }
    st = kissm_read_points(path, format, &cloud);
    CHECK_MSG(st == status, "%s: status %d, expected %d (%s)", what, (int)st, (int)status, kissm_last_error_message());
    CHECK_MSG(cloud == SENTINEL_CLOUD, "%s: output written on failure", what);
    if (word != NULL) CHECK_MSG(msg_has(word), "%s", what);
    if (st == KISSM_OK && cloud != SENTINEL_CLOUD) kissm_cloud_destroy(cloud);
}

static void test_ply(void) {
    const char *ply_double = "ply\n"
                             "format ascii 1.0\n"
                             "comment written by test_capi_read_points\n"
                             "element vertex 4\n"
                             "property double x\n"
                             "property double y\n"
                             "property double z\n"
                             "property uchar red\n"
                             "end_header\n"
                             "0.1 -2.25 300 1\n"
                             "1e-3 123456.789 -0.5 2\n"
                             "-7 8 9.75 3\n"
                             "3.141592653589793 2.718281828459045 -1.4142135623730951 4\n";
    const char *ply_float = "ply\n"
                            "format ascii 1.0\n"
                            "element vertex 3\n"
                            "property float x\n"
                            "property float y\n"
                            "property float z\n"
                            "property float intensity\n"
                            "end_header\n"
                            "1.5 -2.25 0.125 7\n"
                            "-1024 0.5 65536 8\n"
                            "0 -0 3 9\n";
    const double f_expected[9] = {1.5, -2.25, 0.125, -1024, 0.5, 65536, 0, -0.0, 3};
    const double d_expected[12] = {0.1,
                                   -2.25,
                                   300,
                                   1e-3,
                                   123456.789,
                                   -0.5,
                                   -7,
                                   8,
                                   9.75,
                                   3.141592653589793,
                                   2.718281828459045,
                                   -1.4142135623730951};
    check_read("ascii PLY (double)", write_text("d.ply", ply_double), KISSM_FORMAT_AUTO, d_expected, 4);
    check_read("ascii PLY (float)", write_text("f.ply", ply_float), KISSM_FORMAT_AUTO, f_expected, 3);
    check_read("ascii PLY, explicit format", write_text("f2.ply", ply_float), KISSM_FORMAT_PLY, f_expected, 3);
    /* unknown extension: recognised by content */
    check_read("ascii PLY, .scan extension", write_text("f.scan", ply_float), KISSM_FORMAT_AUTO, f_expected, 3);
    /* binary little-endian PLY with float x y z */
    {
        const char *header = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
                             "property float y\nproperty float z\nend_header\n";
        unsigned char buf[256];
        const float v[6] = {1.25f, -3.5f, 100.0f, 0.0f, 2.0f, -0.0625f};
        const double e[6] = {1.25, -3.5, 100.0, 0.0, 2.0, -0.0625};
        const unsigned one = 1;
        size_t hl = strlen(header);
        memcpy(buf, header, hl);
        memcpy(buf + hl, v, sizeof(v));
        if (*(const unsigned char *)&one == 1) /* this test writes native floats: little-endian hosts only */
            check_read("binary PLY", write_file("b.ply", buf, hl + sizeof(v)), KISSM_FORMAT_AUTO, e, 2);
    }
}

static void test_xyz_text(void) {
    const char *text = "# x y z intensity\n"
                       "1 2 3\n"
                       "  -4.5\t5.25   -6e2  99\n"
                       "7,8,9\n"
                       "\n"
                       "nan 1 inf\n"
                       "0.30000000000000004 -1e-300 1.7976931348623157e308\n";
    const double expected[15] = {
        1, 2, 3, -4.5, 5.25, -600, 7, 8, 9, NAN, 1, INFINITY, 0.30000000000000004, -1e-300, 1.7976931348623157e308};
    check_read("xyz text", write_text("a.xyz", text), KISSM_FORMAT_AUTO, expected, 5);
    check_read("txt", write_text("a.txt", text), KISSM_FORMAT_AUTO, expected, 5);
    /* explicit format overrides an unknown extension */
    check_read("xyz in .dat, explicit", write_text("a.dat", text), KISSM_FORMAT_XYZ, expected, 5);
    expect_failure("xyz in .dat, auto", write_text("b.dat", text), KISSM_FORMAT_AUTO, KISSM_ERR_UNSUPPORTED_FORMAT,
                   NULL);
    /* only a comment: an empty cloud (or a parse error), never garbage */
    {
        kissm_cloud *cloud = SENTINEL_CLOUD;
        const char *path = write_text("empty.xyz", "# nothing here\n");
        const int32_t st = kissm_read_points(path, KISSM_FORMAT_AUTO, &cloud);
        CHECK_MSG(st == KISSM_OK || st == KISSM_ERR_PARSE, "comment-only xyz: %d", (int)st);
        if (st == KISSM_OK) {
            kissm_points view;
            kissm_result r;
            kissm_matcher *m = NULL;
            CHECK_EQ_INT(kissm_cloud_count(cloud), 0);
            CHECK(kissm_cloud_data(cloud) == NULL);
            CHECK_EQ_INT(kissm_cloud_points(cloud, &view), KISSM_OK);
            CHECK_EQ_INT(view.count, 0);
            REQUIRE(kissm_create(NULL, &m) == KISSM_OK);
            scn_result_poison(&r);
            CHECK_EQ_INT(kissm_register(m, &view, &view, &r), KISSM_ERR_EMPTY_INPUT);
            CHECK(scn_result_is_reset(&r));
            kissm_destroy(m);
            kissm_cloud_destroy(cloud);
        } else {
            CHECK(cloud == SENTINEL_CLOUD);
        }
    }
}

static void test_binary(void) {
    const float kitti[12] = {1.5f, -2.0f, 0.25f, 0.9f, 100.0f, 200.0f, -300.0f, 0.1f, -0.0f, 0.0f, 1e-3f, 1.0f};
    const double kitti_expected[9] = {1.5, -2.0, 0.25, 100.0, 200.0, -300.0, -0.0, 0.0, (double)1e-3f};
    const float raw[9] = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f, 8.0f, 9.5f};
    const double raw_expected[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9.5};
    const unsigned one = 1;
    if (*(const unsigned char *)&one != 1) return; /* files hold native floats: little-endian hosts only */
    check_read("KITTI .bin", write_file("k.bin", kitti, sizeof(kitti)), KISSM_FORMAT_AUTO, kitti_expected, 3);
    check_read("KITTI, explicit", write_file("k.data", kitti, sizeof(kitti)), KISSM_FORMAT_KITTI_BIN, kitti_expected,
               3);
    check_read("float32 xyz", write_file("r.raw", raw, sizeof(raw)), KISSM_FORMAT_BIN_XYZ, raw_expected, 3);
    /* the same 36 bytes as KITTI: not a whole number of 16-byte points */
    expect_failure("KITTI, truncated", write_file("t.bin", raw, sizeof(raw)), KISSM_FORMAT_AUTO, KISSM_ERR_PARSE, NULL);
}

static void test_errors(void) {
    char missing[700];
    snprintf(missing, sizeof(missing), "%s/does_not_exist.ply", g_dir);
    expect_failure("missing file", missing, KISSM_FORMAT_AUTO, KISSM_ERR_IO, "does_not_exist");
    expect_failure("missing file, explicit format", missing, KISSM_FORMAT_PLY, KISSM_ERR_IO, NULL);
    expect_failure("a directory", g_dir, KISSM_FORMAT_XYZ, KISSM_ERR_IO, NULL);
    expect_failure("garbage .ply", write_text("g.ply", "this is not a ply file\nat all\n"), KISSM_FORMAT_AUTO,
                   KISSM_ERR_PARSE, NULL);
    expect_failure("truncated ply",
                   write_text("tr.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                        "property float z\nend_header\n1 2 3\n4 5\n"),
                   KISSM_FORMAT_AUTO, KISSM_ERR_PARSE, NULL);
    expect_failure("ply without end_header",
                   write_text("nh.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
                   KISSM_FORMAT_AUTO, KISSM_ERR_PARSE, NULL);
    expect_failure("xyz with a word", write_text("w.xyz", "1 2 3\n4 five 6\n"), KISSM_FORMAT_AUTO, KISSM_ERR_PARSE,
                   NULL);
    {
        const unsigned char junk[] = {'h', 'e', 'l', 'l', 'o', 0x01, 0x02, 0xfe, 0xff, '\n', 'x'};
        expect_failure("unknown extension, unknown content", write_file("junk.foo", junk, sizeof(junk)),
                       KISSM_FORMAT_AUTO, KISSM_ERR_UNSUPPORTED_FORMAT, NULL);
        expect_failure("no extension, unknown content", write_file("junk", junk, sizeof(junk)), KISSM_FORMAT_AUTO,
                       KISSM_ERR_UNSUPPORTED_FORMAT, NULL);
    }
    /* invalid format ids, even for an existing, readable file */
    {
        const char *ok = write_text("ok.xyz", "1 2 3\n");
        const int32_t bad[] = {-1, 8, 9, 100, INT32_MIN, INT32_MAX};
        size_t i;
        for (i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i)
            expect_failure("invalid format id", ok, bad[i], KISSM_ERR_INVALID_ARGUMENT, "format");
    }
    /* NULL arguments */
    {
        kissm_cloud *cloud = SENTINEL_CLOUD;
        kissm_points view;
        const char *ok = write_text("ok2.xyz", "1 2 3\n4 5 6\n");
        CHECK_EQ_INT(kissm_read_points(NULL, KISSM_FORMAT_AUTO, &cloud), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("path"));
        CHECK(cloud == SENTINEL_CLOUD);
        CHECK_EQ_INT(kissm_read_points(ok, KISSM_FORMAT_AUTO, NULL), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("out_cloud"));
        CHECK_EQ_INT(kissm_cloud_points(NULL, &view), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("cloud"));
        cloud = NULL;
        REQUIRE(kissm_read_points(ok, KISSM_FORMAT_AUTO, &cloud) == KISSM_OK);
        CHECK_EQ_INT(kissm_cloud_points(cloud, NULL), KISSM_ERR_NULL_ARGUMENT);
        CHECK(msg_has("out_points"));
        CHECK_EQ_INT(kissm_cloud_count(cloud), 2);
        kissm_cloud_destroy(cloud);
    }
}

static void put_u16(unsigned char *p, unsigned v) {
    p[0] = (unsigned char)(v & 0xFF);
    p[1] = (unsigned char)(v >> 8);
}
static void put_u32(unsigned char *p, uint32_t v) {
    int i;
    for (i = 0; i < 4; ++i) p[i] = (unsigned char)(v >> (8 * i));
}
static void put_f64(unsigned char *p, double v) {
    uint64_t bits;
    int i;
    memcpy(&bits, &v, sizeof bits);
    for (i = 0; i < 8; ++i) p[i] = (unsigned char)(bits >> (8 * i));
}

/* A LAS 1.2 file (point format 0, scale 0.5, offset 10) of 5 points, points 1 and 3 withheld: 3 points read,
 * kissm_cloud_num_withheld() 2; every other format leaves nothing out (0). */
static void test_las_withheld(void) {
    unsigned char las[227 + 5 * 20];
    const double expected[9] = {10, 10, 10, 12, 12, 12, 14, 14, 14};
    kissm_cloud *cloud = NULL;
    const char *path;
    int i, k;
    memset(las, 0, sizeof las);
    memcpy(las, "LASF", 4);
    las[24] = 1;
    las[25] = 2;
    put_u16(las + 94, 227);
    put_u32(las + 96, 227);
    put_u16(las + 105, 20);
    put_u32(las + 107, 5);
    for (k = 0; k < 3; ++k) {
        put_f64(las + 131 + 8 * k, 0.5);
        put_f64(las + 155 + 8 * k, 10.0);
    }
    for (i = 0; i < 5; ++i) {
        for (k = 0; k < 3; ++k) put_u32(las + 227 + 20 * i + 4 * k, (uint32_t)(2 * i));
        if (i == 1 || i == 3) las[227 + 20 * i + 15] = 0x80; /* withheld: bit 7 of the classification byte */
    }
    path = write_file("withheld.las", las, sizeof las);
    check_read("las with withheld points", path, KISSM_FORMAT_AUTO, expected, 3);
    REQUIRE(kissm_read_points(path, KISSM_FORMAT_LAS, &cloud) == KISSM_OK);
    CHECK_EQ_INT(kissm_cloud_count(cloud), 3);
    CHECK_EQ_INT(kissm_cloud_num_withheld(cloud), 2);
    kissm_cloud_destroy(cloud);
    cloud = NULL;
    REQUIRE(kissm_read_points(write_text("none.xyz", "1 2 3\n"), KISSM_FORMAT_AUTO, &cloud) == KISSM_OK);
    CHECK_EQ_INT(kissm_cloud_num_withheld(cloud), 0);
    kissm_cloud_destroy(cloud);
    CHECK_EQ_INT(kissm_cloud_num_withheld(NULL), 0);
}

/* Clouds written as text (%.17g, exact) and as KITTI float32, read back and registered through the API. */
static void test_register_read_clouds(void) {
    scn_pair pair;
    char *text;
    size_t i, len = 0, cap;
    const char *src_path, *tgt_path;
    float *t32;
    float *xyzi;
    kissm_cloud *src = NULL, *tgt = NULL;
    kissm_points ps, pt, mem_s, mem_t;
    kissm_matcher *m = NULL;
    kissm_config c = scn_config(0.5);
    kissm_result from_files, from_memory;

    scn_make_pair(&pair, 4, 12.0, 0.01);
    cap = pair.source.count * 80 + 64;
    text = (char *)malloc(cap);
    REQUIRE(text != NULL);
    for (i = 0; i < pair.source.count; ++i)
        len += (size_t)snprintf(text + len, cap - len, "%.17g %.17g %.17g\n", pair.source.xyz[3 * i],
                                pair.source.xyz[3 * i + 1], pair.source.xyz[3 * i + 2]);
    src_path = write_file("scene_source.xyz", text, len);
    free(text);
    t32 = scn_cloud_to_float(&pair.target);
    xyzi = (float *)malloc(pair.target.count * 4 * sizeof(float));
    REQUIRE(xyzi != NULL);
    for (i = 0; i < pair.target.count; ++i) {
        memcpy(xyzi + 4 * i, t32 + 3 * i, 3 * sizeof(float));
        xyzi[4 * i + 3] = 0.5f;
    }
    tgt_path = write_file("scene_target.bin", xyzi, pair.target.count * 4 * sizeof(float));
    free(xyzi);
    REQUIRE(src_path != NULL && tgt_path != NULL);

    REQUIRE(kissm_read_points(src_path, KISSM_FORMAT_AUTO, &src) == KISSM_OK);
    REQUIRE(kissm_read_points(tgt_path, KISSM_FORMAT_AUTO, &tgt) == KISSM_OK);
    CHECK_EQ_INT(kissm_cloud_count(src), pair.source.count);
    CHECK_EQ_INT(kissm_cloud_count(tgt), pair.target.count);
    CHECK(memcmp(kissm_cloud_data(src), pair.source.xyz, pair.source.count * 3 * sizeof(double)) == 0);
    {
        const double *d = kissm_cloud_data(tgt);
        int same = 1;
        for (i = 0; i < 3 * pair.target.count; ++i)
            if (d[i] != (double)t32[i]) same = 0;
        CHECK(same);
    }
    CHECK_EQ_INT(kissm_cloud_points(src, &ps), KISSM_OK);
    CHECK_EQ_INT(kissm_cloud_points(tgt, &pt), KISSM_OK);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    scn_result_poison(&from_files);
    CHECK_EQ_INT(kissm_register(m, &ps, &pt, &from_files), KISSM_OK);
    CHECK_EQ_INT(from_files.valid, 1);
    CHECK(scn_rotation_error_deg(from_files.rotation, pair.truth.R) < 2.0);
    CHECK(scn_translation_error(from_files.translation, pair.truth.t) < 1.0);
    /* equal to registering the in-memory clouds (float64 source, float32 target) */
    mem_s = scn_points(&pair.source);
    mem_t = scn_points_f32(t32, pair.target.count);
    scn_result_poison(&from_memory);
    CHECK_EQ_INT(kissm_register(m, &mem_s, &mem_t, &from_memory), KISSM_OK);
    CHECK(scn_result_equal(&from_files, &from_memory));
    /* the clouds stay valid after the matcher is gone and can be read again */
    kissm_destroy(m);
    CHECK_EQ_INT(kissm_cloud_count(src), pair.source.count);
    kissm_cloud_destroy(src);
    kissm_cloud_destroy(tgt);
    free(t32);
    scn_pair_free(&pair);
}

int main(void) {
    const char *tmp = getenv("TMPDIR");
    int i, failed;
    snprintf(g_dir, sizeof(g_dir), "%s/kissm_capi_read_XXXXXX", (tmp && tmp[0]) ? tmp : "/tmp");
    if (mkdtemp(g_dir) == NULL) {
        fprintf(stderr, "cannot create a temporary directory; skipping\n");
        return 77;
    }
    RUN_TEST(test_ply);
    RUN_TEST(test_xyz_text);
    RUN_TEST(test_binary);
    RUN_TEST(test_errors);
    RUN_TEST(test_las_withheld);
    RUN_TEST(test_register_read_clouds);
    for (i = 0; i < g_num_paths; ++i) unlink(g_paths[i]);
    rmdir(g_dir);
    failed = TEST_SUMMARY();
    return failed;
}
