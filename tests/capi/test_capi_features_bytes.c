/* SPDX-License-Identifier: MIT */
/* Features as bytes (kissm_features_serialize / kissm_features_deserialize, docs/features-format.md): round
 * trips that register bit for bit like the originals, settings that still mismatch, exact statuses for bad
 * arguments, and bytes that are truncated, bit-flipped or forged (with a recomputed checksum) refused with
 * KISSM_ERR_PARSE and a message naming the field. C99.
 *
 *   capi_features_bytes                   the tests
 *   capi_features_bytes --corpus DIR      writes the fuzz seeds of tests/fuzz/corpus/features to DIR */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"
#include "scenes.h"

#define VOXEL 0.5

/* The layout of docs/features-format.md, version 1. */
#define OFF_VERSION 8
#define OFF_RESERVED 12
#define OFF_SIZE 16
#define OFF_VOXEL_SIZE 24
#define OFF_VIEWPOINT_MODE 125
#define OFF_NUM_VOXELS 128
#define OFF_NUM_KEYPOINTS 136
#define OFF_ORIGIN 144
#define OFF_POINTS 168

static scn_pair g_pair;
static scn_cloud g_plane; /* a small cloud: its features are a few KB */

/* ---- the format's helpers, written from the format document ----------------------------------------- */

static uint64_t features_checksum(const uint8_t *p, size_t n) {
    /* FNV-1a steps on 64-bit little-endian words, then on the bytes left (docs/features-format.md) */
    uint64_t h = 14695981039346656037ull;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w = 0;
        int k;
        for (k = 0; k < 8; ++k) w |= (uint64_t)p[i + (size_t)k] << (8 * k);
        h = (h ^ w) * 1099511628211ull;
    }
    for (; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}
static uint64_t get_u64(const uint8_t *p) {
    uint64_t v = 0;
    int i;
    for (i = 7; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}
static uint32_t get_u32(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static void put_u64(uint8_t *p, uint64_t v) {
    int i;
    for (i = 0; i < 8; ++i) p[i] = (uint8_t)(v >> (8 * i));
}
static void put_u32(uint8_t *p, uint32_t v) {
    int i;
    for (i = 0; i < 4; ++i) p[i] = (uint8_t)(v >> (8 * i));
}
static void put_f32(uint8_t *p, float f) {
    uint32_t b;
    memcpy(&b, &f, 4);
    put_u32(p, b);
}
static void put_f64(uint8_t *p, double d) {
    uint64_t b;
    memcpy(&b, &d, 8);
    put_u64(p, b);
}
/* Rewrites the checksum (the last 8 bytes) of a forged blob so that only the field checks can catch it. */
static void reseal(uint8_t *b, size_t n) { put_u64(b + n - 8, features_checksum(b, n - 8)); }

/* Offsets of a blob's sections after the points, found from its flags. */
typedef struct layout {
    uint64_t voxels, keypoints;
    size_t normal_flags, plane_flags, keypoint_list, descriptors, counts;
} layout;
static layout layout_of(const uint8_t *b) {
    layout l;
    size_t valid = 0, i;
    l.voxels = get_u64(b + OFF_NUM_VOXELS);
    l.keypoints = get_u64(b + OFF_NUM_KEYPOINTS);
    l.normal_flags = OFF_POINTS + 12 * (size_t)l.voxels;
    for (i = 0; i < l.voxels; ++i) valid += b[l.normal_flags + i];
    l.plane_flags = l.normal_flags + (size_t)l.voxels + 12 * valid;
    valid = 0;
    for (i = 0; i < l.voxels; ++i) valid += b[l.plane_flags + i];
    l.keypoint_list = l.plane_flags + (size_t)l.voxels + 12 * valid;
    l.descriptors = l.keypoint_list + 4 * (size_t)l.keypoints;
    l.counts = l.descriptors + 33 * 4 * (size_t)l.keypoints;
    return l;
}

/* ---- helpers ---------------------------------------------------------------------------------------- */

/* The bytes of f (malloc'ed), through a size query first. */
static uint8_t *to_bytes(const kissm_features *f, uint64_t *size) {
    uint8_t *b;
    uint64_t written = 0;
    *size = 0;
    if (kissm_features_serialize(f, NULL, 0, size) != KISSM_OK || *size == 0) return NULL;
    b = (uint8_t *)malloc((size_t)*size);
    if (b == NULL) return NULL;
    if (kissm_features_serialize(f, b, *size, &written) != KISSM_OK || written != *size) {
        free(b);
        return NULL;
    }
    return b;
}

static kissm_config config_of(int32_t refine_mode, int32_t suppression) {
    kissm_config c = scn_config(VOXEL);
    c.refine_mode = refine_mode;
    c.suppression = suppression;
    return c;
}

static kissm_features *features_of(const kissm_config *c, const scn_cloud *cloud) {
    kissm_matcher *m = NULL;
    kissm_features *f = NULL;
    kissm_points p = scn_points(cloud);
    if (kissm_create(c, &m) != KISSM_OK) return NULL;
    if (kissm_features_compute(m, &p, &f) != KISSM_OK) f = NULL;
    kissm_destroy(m);
    return f;
}

/* The small blob: the plane cloud under a large voxel. */
static uint8_t *small_blob(int32_t refine_mode, int32_t suppression, uint64_t *size) {
    kissm_config c = config_of(refine_mode, suppression);
    kissm_features *f;
    uint8_t *b;
    c.voxel_size = 2.0;
    f = features_of(&c, &g_plane);
    if (f == NULL) return NULL;
    b = to_bytes(f, size);
    kissm_features_destroy(f);
    return b;
}

/* Deserialising b must fail with KISSM_ERR_PARSE, leave the output alone, and name `what` in the message. */
static int refused(const uint8_t *b, size_t n, const char *what) {
    kissm_features *sentinel = (kissm_features *)&g_pair, *out = sentinel;
    const int32_t st = kissm_features_deserialize(b, n, &out);
    if (st == KISSM_OK) kissm_features_destroy(out);
    if (st != KISSM_ERR_PARSE || out != sentinel ||
        (what != NULL && strstr(kissm_last_error_message(), what) == NULL)) {
        fprintf(stderr, "  expected PARSE naming '%s': status %d, message '%s'\n", what ? what : "", (int)st,
                kissm_last_error_message());
        return 0;
    }
    return 1;
}

/* ---- tests ------------------------------------------------------------------------------------------ */

static void round_trip(int32_t refine_mode, int32_t suppression) {
    const kissm_config c = config_of(refine_mode, suppression);
    kissm_matcher *m = NULL;
    kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_features *fs = NULL, *ft = NULL, *ds = NULL, *dt = NULL;
    uint8_t *bs = NULL, *bt = NULL, *again = NULL;
    uint64_t ns = 0, nt = 0, n_again = 0;
    kissm_result a, b;
    double initial[16];
    fprintf(stderr, "  refine_mode %d, suppression %d\n", (int)refine_mode, (int)suppression);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
    bs = to_bytes(fs, &ns);
    bt = to_bytes(ft, &nt);
    REQUIRE(bs != NULL && bt != NULL);
    CHECK(strcmp(kissm_last_error_message(), "") == 0);
    CHECK_EQ_INT(kissm_features_deserialize(bs, ns, &ds), KISSM_OK);
    CHECK_EQ_INT(kissm_features_deserialize(bt, nt, &dt), KISSM_OK);
    REQUIRE(ds != NULL && dt != NULL);
    fprintf(stderr, "  source: %llu bytes for %llu voxels, %llu keypoints\n", (unsigned long long)ns,
            (unsigned long long)kissm_features_num_voxels(fs), (unsigned long long)kissm_features_num_keypoints(fs));

    CHECK_EQ_INT(kissm_features_num_points(ds), kissm_features_num_points(fs));
    CHECK_EQ_INT(kissm_features_num_voxels(ds), kissm_features_num_voxels(fs));
    CHECK_EQ_INT(kissm_features_num_keypoints(ds), kissm_features_num_keypoints(fs));
    CHECK_EQ_INT(kissm_features_num_keypoints(dt), kissm_features_num_keypoints(ft));
    CHECK(kissm_features_num_keypoints(ds) > 100);

    /* the same features give the same bytes */
    again = to_bytes(ds, &n_again);
    REQUIRE(again != NULL);
    CHECK(n_again == ns && memcmp(again, bs, (size_t)ns) == 0);

    /* registration and refinement from the loaded features: bit for bit the originals' (but the times) */
    scn_result_poison(&a);
    scn_result_poison(&b);
    CHECK_EQ_INT(kissm_register_features(m, fs, ft, &a), KISSM_OK);
    CHECK_EQ_INT(kissm_register_features(m, ds, dt, &b), KISSM_OK);
    CHECK_EQ_INT(a.valid, 1);
    CHECK(memcmp(a.transform, b.transform, sizeof a.transform) == 0);
    CHECK_MSG(scn_result_equal(&a, &b), "register_features from bytes differs");
    CHECK_EQ_INT(kissm_register_features(m, fs, dt, &b), KISSM_OK); /* mixed: loaded target only */
    CHECK(scn_result_equal(&a, &b));
    scn_pose_to_matrix(&g_pair.truth, initial);
    CHECK_EQ_INT(kissm_refine_features(m, fs, ft, initial, &a), KISSM_OK);
    CHECK_EQ_INT(kissm_refine_features(m, ds, dt, initial, &b), KISSM_OK);
    CHECK(memcmp(a.transform, b.transform, sizeof a.transform) == 0);
    CHECK_MSG(scn_result_equal(&a, &b), "refine_features from bytes differs");
    {
        /* the signature of loaded features: the original's bits */
        double sa[KISSM_SIGNATURE_SIZE], sb[KISSM_SIGNATURE_SIZE];
        CHECK_EQ_INT(kissm_features_signature(fs, sa), KISSM_OK);
        CHECK_EQ_INT(kissm_features_signature(ds, sb), KISSM_OK);
        CHECK(memcmp(sa, sb, sizeof sa) == 0);
    }
    /* the memory they hold: the same arrays and the same rebuilt indexes, up to vector slack */
    CHECK(kissm_features_memory_bytes(ds) <= kissm_features_memory_bytes(fs));
    CHECK(kissm_features_memory_bytes(ds) * 10 >= kissm_features_memory_bytes(fs) * 9);

    free(bs);
    free(bt);
    free(again);
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_features_destroy(ds);
    kissm_features_destroy(dt);
    kissm_destroy(m);
}

static void test_round_trips(void) {
    round_trip(KISSM_REFINE_NONE, KISSM_SUPPRESS_NONE);
    round_trip(KISSM_REFINE_GICP, KISSM_SUPPRESS_NONE);
    round_trip(KISSM_REFINE_NONE, KISSM_SUPPRESS_GROUND);
    round_trip(KISSM_REFINE_GICP, KISSM_SUPPRESS_GROUND);
}

/* Loaded features carry their settings: another matcher's are still a mismatch. */
static void test_mismatch(void) {
    const kissm_config c = config_of(KISSM_REFINE_NONE, KISSM_SUPPRESS_NONE);
    kissm_config other = c, ground = config_of(KISSM_REFINE_NONE, KISSM_SUPPRESS_GROUND);
    kissm_features *f = features_of(&c, &g_pair.source), *d = NULL;
    kissm_matcher *m = NULL;
    uint8_t *b;
    uint64_t n = 0;
    kissm_result r;
    REQUIRE(f != NULL);
    scn_result_poison(&r); /* struct_size set, every other byte garbage: a failed call must reset it */
    b = to_bytes(f, &n);
    REQUIRE(b != NULL);
    REQUIRE(kissm_features_deserialize(b, n, &d) == KISSM_OK);
    other.voxel_size = 0.6;
    REQUIRE(kissm_create(&other, &m) == KISSM_OK);
    CHECK_EQ_INT(kissm_register_features(m, d, d, &r), KISSM_ERR_FEATURES_MISMATCH);
    CHECK(scn_result_is_reset(&r));
    kissm_destroy(m);
    REQUIRE(kissm_create(&ground, &m) == KISSM_OK);
    CHECK_EQ_INT(kissm_register_features(m, d, d, &r), KISSM_ERR_FEATURES_MISMATCH);
    kissm_destroy(m);
    /* a matcher that differs only in what the features do not depend on accepts them */
    other = c;
    other.ratio_test = 0.8;
    other.refine_mode = KISSM_REFINE_POINT_TO_PLANE;
    REQUIRE(kissm_create(&other, &m) == KISSM_OK);
    CHECK_EQ_INT(kissm_register_features(m, d, d, &r), KISSM_OK);
    kissm_destroy(m);
    free(b);
    kissm_features_destroy(f);
    kissm_features_destroy(d);
}

static void test_bad_arguments(void) {
    const kissm_config c = config_of(KISSM_REFINE_NONE, KISSM_SUPPRESS_NONE);
    kissm_features *f = features_of(&c, &g_plane), *sentinel = (kissm_features *)&g_plane, *out = sentinel;
    uint64_t size = 0, got = 12345;
    uint8_t *buf;
    size_t i;
    int untouched = 1;
    REQUIRE(f != NULL);
    REQUIRE(kissm_features_serialize(f, NULL, 0, &size) == KISSM_OK && size > 0);
    buf = (uint8_t *)malloc((size_t)size + 16);
    REQUIRE(buf != NULL);

    CHECK_EQ_INT(kissm_features_serialize(NULL, buf, size, &got), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "features") != NULL);
    CHECK_EQ_INT(got, 12345);
    CHECK_EQ_INT(kissm_features_serialize(f, buf, size, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "out_size") != NULL);
    CHECK_EQ_INT(kissm_features_deserialize(NULL, size, &out), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "bytes") != NULL);
    CHECK(out == sentinel);
    CHECK_EQ_INT(kissm_features_deserialize(buf, size, NULL), KISSM_ERR_NULL_ARGUMENT);
    CHECK(strstr(kissm_last_error_message(), "out_features") != NULL);

    /* capacity one byte short: refused, the size needed reported, not a byte written */
    memset(buf, 0xCD, (size_t)size + 16);
    CHECK_EQ_INT(kissm_features_serialize(f, buf, size - 1, &got), KISSM_ERR_INVALID_ARGUMENT);
    CHECK_EQ_INT(got, size);
    CHECK(strstr(kissm_last_error_message(), "capacity") != NULL);
    for (i = 0; i < (size_t)size + 16; ++i) untouched &= buf[i] == 0xCD;
    CHECK_MSG(untouched, "a too small buffer was written");
    CHECK_EQ_INT(kissm_features_serialize(f, buf, 0, &got), KISSM_ERR_INVALID_ARGUMENT);
    /* exactly the capacity needed: written, and the guard bytes beyond it untouched */
    got = 0;
    CHECK_EQ_INT(kissm_features_serialize(f, buf, size, &got), KISSM_OK);
    CHECK_EQ_INT(got, size);
    untouched = 1;
    for (i = (size_t)size; i < (size_t)size + 16; ++i) untouched &= buf[i] == 0xCD;
    CHECK_MSG(untouched, "serialize wrote beyond the size it reported");
    /* a larger capacity writes the same size */
    CHECK_EQ_INT(kissm_features_serialize(f, buf, size + 16, &got), KISSM_OK);
    CHECK_EQ_INT(got, size);
    /* no bytes */
    CHECK(refused(buf, 0, "truncated"));

    free(buf);
    kissm_features_destroy(f);
}

/* Every truncation and every single-bit flip of a small blob is refused. */
static void test_truncated_and_flipped(void) {
    uint64_t n = 0;
    uint8_t *b = small_blob(KISSM_REFINE_GICP, KISSM_SUPPRESS_NONE, &n);
    size_t len, bit;
    int all = 1;
    kissm_features *f = NULL;
    REQUIRE(b != NULL);
    fprintf(stderr, "  small blob: %llu bytes, %llu voxels, %llu keypoints\n", (unsigned long long)n,
            (unsigned long long)get_u64(b + OFF_NUM_VOXELS), (unsigned long long)get_u64(b + OFF_NUM_KEYPOINTS));
    CHECK(n < 20000);
    CHECK_EQ_INT(kissm_features_deserialize(b, n, &f), KISSM_OK);
    kissm_features_destroy(f);
    for (len = 0; len < (size_t)n && all; ++len) {
        /* a short copy, so that a read past the end is a read past the allocation (ASan) */
        uint8_t *t = (uint8_t *)malloc(len ? len : 1);
        memcpy(t, b, len);
        all = refused(t, len, len >= 8 ? NULL : "truncated");
        if (!all) fprintf(stderr, "  truncation to %zu bytes\n", len);
        free(t);
    }
    CHECK_MSG(all, "a truncation was not refused");
    all = 1;
    for (bit = 0; bit < 8 * (size_t)n && all; ++bit) {
        b[bit / 8] ^= (uint8_t)(1u << (bit % 8));
        all = refused(b, (size_t)n, NULL);
        if (!all) fprintf(stderr, "  flip of bit %zu\n", bit);
        b[bit / 8] ^= (uint8_t)(1u << (bit % 8));
    }
    CHECK_MSG(all, "a bit flip was not refused");
    /* a flip in the data is reported as corruption */
    b[OFF_POINTS + 1] ^= 4;
    CHECK(refused(b, (size_t)n, "checksum"));
    b[OFF_POINTS + 1] ^= 4;
    free(b);
}

/* Forged blobs whose checksum was recomputed: the field checks alone refuse them, naming the field. */
static void test_forged(void) {
    uint64_t n = 0;
    uint8_t *orig = small_blob(KISSM_REFINE_NONE, KISSM_SUPPRESS_NONE, &n);
    uint8_t *b, *longer;
    layout l;
    kissm_features *f = NULL;
    REQUIRE(orig != NULL);
    l = layout_of(orig);
    REQUIRE(l.keypoints >= 2);
    REQUIRE(l.counts + 24 + 8 == n);
    b = (uint8_t *)malloc((size_t)n);
    REQUIRE(b != NULL);
#define FORGE(edit, what)                                                                                              \
  do {                                                                                                                 \
    memcpy(b, orig, (size_t)n);                                                                                        \
    edit;                                                                                                              \
    reseal(b, (size_t)n);                                                                                              \
    CHECK_MSG(refused(b, (size_t)n, what), "%s", #edit);                                                               \
  } while (0)
    /* a resealed copy of the original is accepted (the checksum is what the tests think it is) */
    memcpy(b, orig, (size_t)n);
    reseal(b, (size_t)n);
    CHECK(memcmp(b, orig, (size_t)n) == 0);

    FORGE(b[0] = 'X', "magic");
    FORGE(put_u32(b + OFF_VERSION, 2), "version");
    FORGE(put_u32(b + OFF_RESERVED, 1), "reserved");
    FORGE(put_u64(b + OFF_SIZE, n + 1), "declares");
    FORGE(put_f64(b + OFF_VOXEL_SIZE, -1.0), "voxel_size");
    FORGE(put_f64(b + OFF_VOXEL_SIZE, 0.0 / 0.0), "voxel_size");
    FORGE(b[OFF_VIEWPOINT_MODE] = 9, "viewpoint_mode");
    /* lying counts: more than the bytes can hold, never allocated */
    FORGE(put_u64(b + OFF_NUM_VOXELS, (uint64_t)1 << 40), "num_voxels");
    FORGE(put_u64(b + OFF_NUM_VOXELS, l.voxels + 1), NULL);
    FORGE(put_u64(b + OFF_NUM_VOXELS, 0), "num_voxels");
    FORGE(put_u64(b + OFF_NUM_KEYPOINTS, ~(uint64_t)0), "num_keypoints");
    FORGE(put_u64(b + OFF_NUM_KEYPOINTS, l.voxels + 1), "num_keypoints");
    FORGE(put_u64(b + OFF_NUM_KEYPOINTS, l.keypoints - 1), NULL);
    /* values the pipeline cannot produce */
    FORGE(put_f64(b + OFF_ORIGIN, 1.0 / 0.0), "origin");
    FORGE(put_f32(b + OFF_POINTS + 4, 0.0f / 0.0f), "voxel point 0");
    FORGE(put_f32(b + OFF_POINTS, 1e30f), "voxel point 0");
    FORGE(b[l.normal_flags] = 2, "normal flag");
    FORGE(b[l.plane_flags] = 7, "plane normal flag");
    FORGE(put_u32(b + l.keypoint_list, (uint32_t)l.voxels), "keypoint 0");
    FORGE(put_u32(b + l.keypoint_list, 0xFFFFFFFFu), "keypoint 0");
    FORGE(put_u32(b + l.keypoint_list + 4, get_u32(b + l.keypoint_list)), "keypoint 1");
    FORGE(put_f32(b + l.descriptors + 8, 0.0f / 0.0f), "descriptor value 2 of keypoint 0");
    FORGE(put_f32(b + l.descriptors, -1.0f), "descriptor");
    FORGE(put_f32(b + l.descriptors, 1e9f), "descriptor");
    FORGE(put_u64(b + l.counts, 3), "num_points");
    FORGE(put_u64(b + l.counts + 8, get_u64(b + l.counts) + 1), "num_points");
    FORGE(put_u64(b + l.counts + 8, 1), "num_nonfinite");
    FORGE(put_u64(b + l.counts + 16, 1), "num_suppressed");
#undef FORGE
    /* described without refinement, features carry no planes: every plane flag is 0, and a blob that stores a
     * plane normal anyway (a valid unit vector, sized and sealed) is refused */
    {
        size_t i, at = l.plane_flags + (size_t)l.voxels;
        uint8_t *planed = (uint8_t *)malloc((size_t)n + 12);
        for (i = 0; i < l.voxels; ++i) CHECK_EQ_INT(orig[l.plane_flags + i], 0);
        REQUIRE(planed != NULL);
        memcpy(planed, orig, at);
        planed[l.plane_flags] = 1;
        put_f32(planed + at, 0.0f);
        put_f32(planed + at + 4, 0.0f);
        put_f32(planed + at + 8, 1.0f);
        memcpy(planed + at + 12, orig + at, (size_t)n - at);
        put_u64(planed + OFF_SIZE, n + 12);
        reseal(planed, (size_t)n + 12);
        CHECK(refused(planed, (size_t)n + 12, "refine_mode is none"));
        free(planed);
    }
    /* a trailing byte, even declared in the header and sealed, is refused */
    longer = (uint8_t *)malloc((size_t)n + 1);
    REQUIRE(longer != NULL);
    memcpy(longer, orig, (size_t)n - 8);
    longer[n - 8] = 0;
    put_u64(longer + OFF_SIZE, n + 1);
    reseal(longer, (size_t)n + 1);
    CHECK(refused(longer, (size_t)n + 1, "unexpected bytes"));
    /* and the unforged original still loads */
    CHECK_EQ_INT(kissm_features_deserialize(orig, n, &f), KISSM_OK);
    kissm_features_destroy(f);
    free(longer);
    free(b);
    free(orig);
}

/* The fuzz seeds: small real blobs of four configs and truncations of one. */
static int write_file(const char *dir, const char *name, const uint8_t *b, size_t n) {
    char path[4096];
    FILE *out;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    out = fopen(path, "wb");
    if (out == NULL || fwrite(b, 1, n, out) != n) {
        fprintf(stderr, "cannot write %s\n", path);
        if (out) fclose(out);
        return 0;
    }
    return fclose(out) == 0;
}

static int write_corpus(const char *dir) {
    static const struct {
        const char *name;
        int32_t refine, suppression;
    } kinds[] = {{"plane_none", KISSM_REFINE_NONE, KISSM_SUPPRESS_NONE},
                 {"plane_gicp", KISSM_REFINE_GICP, KISSM_SUPPRESS_NONE},
                 {"plane_p2p_ground", KISSM_REFINE_POINT_TO_PLANE, KISSM_SUPPRESS_GROUND}};
    size_t k;
    for (k = 0; k < sizeof kinds / sizeof kinds[0]; ++k) {
        uint64_t n = 0;
        uint8_t *b = small_blob(kinds[k].refine, kinds[k].suppression, &n);
        char name[64];
        if (b == NULL || !write_file(dir, kinds[k].name, b, (size_t)n)) return 1;
        if (k == 0) {
            snprintf(name, sizeof name, "%s_truncated_header", kinds[k].name);
            if (!write_file(dir, name, b, 100)) return 1;
            snprintf(name, sizeof name, "%s_truncated_half", kinds[k].name);
            if (!write_file(dir, name, b, (size_t)n / 2)) return 1;
        }
        free(b);
    }
    return 0;
}

int main(int argc, char **argv) {
    scn_make_plane(&g_plane, 7, 600, 0.01);
    if (argc == 3 && strcmp(argv[1], "--corpus") == 0) {
        const int rc = write_corpus(argv[2]);
        scn_cloud_free(&g_plane);
        return rc;
    }
    scn_make_pair(&g_pair, 3, 15.0, 0.01);
    RUN_TEST(test_round_trips);
    RUN_TEST(test_mismatch);
    RUN_TEST(test_bad_arguments);
    RUN_TEST(test_truncated_and_flipped);
    RUN_TEST(test_forged);
    scn_pair_free(&g_pair);
    scn_cloud_free(&g_plane);
    return TEST_SUMMARY();
}
