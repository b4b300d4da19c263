/* Cross-language round trip, C side. Registers the clouds of tests/data (made by
 * tools/make_roundtrip_data.py) as listed in tests/data/golden.json and requires the result to equal the
 * golden values bit for bit: the transform (doubles printed with %.17g, so they parse back exactly),
 * validity, reason and every count. The Python and Rust suites check the same file, so the three
 * languages agree with each other through it. Each case also runs at 2 and 4 threads.
 *
 * With --write, prints a fresh golden.json to stdout instead (tests/data/update_golden.sh). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"

/* The cases: the same pair as float64 and, cast by the caller, as float32. */
typedef struct {
    const char *name;
    int32_t scalar_type;
    double voxel_size;
} golden_case;

static const golden_case kCases[] = {
    {"yard_float64_v0.25", KISSM_SCALAR_FLOAT64, 0.25},
    {"yard_float32_v0.3", KISSM_SCALAR_FLOAT32, 0.3},
};

#define NUM_CASES (sizeof(kCases) / sizeof(kCases[0]))

static char g_dir[4096];

static int run_case(const golden_case *gc, int32_t threads, kissm_result *result) {
    char src_path[4200], tgt_path[4200];
    kissm_cloud *src = NULL, *tgt = NULL;
    kissm_config config;
    kissm_matcher *matcher = NULL;
    kissm_points sp, tp;
    float *src32 = NULL, *tgt32 = NULL;
    int32_t status;
    snprintf(src_path, sizeof src_path, "%s/roundtrip_source.ply", g_dir);
    snprintf(tgt_path, sizeof tgt_path, "%s/roundtrip_target.ply", g_dir);
    if (kissm_read_points(src_path, KISSM_FORMAT_AUTO, &src) != KISSM_OK ||
        kissm_read_points(tgt_path, KISSM_FORMAT_AUTO, &tgt) != KISSM_OK) {
        fprintf(stderr, "cannot read the round-trip clouds: %s\n", kissm_last_error_message());
        kissm_cloud_destroy(src);
        return -1;
    }
    kissm_cloud_points(src, &sp);
    kissm_cloud_points(tgt, &tp);
    if (gc->scalar_type == KISSM_SCALAR_FLOAT32) {
        uint64_t i;
        src32 = (float *)malloc(3 * sp.count * sizeof(float));
        tgt32 = (float *)malloc(3 * tp.count * sizeof(float));
        if (!src32 || !tgt32) return -1;
        for (i = 0; i < 3 * sp.count; ++i) src32[i] = (float)kissm_cloud_data(src)[i];
        for (i = 0; i < 3 * tp.count; ++i) tgt32[i] = (float)kissm_cloud_data(tgt)[i];
        sp.data = src32, sp.stride_bytes = 0, sp.scalar_type = KISSM_SCALAR_FLOAT32;
        tp.data = tgt32, tp.stride_bytes = 0, tp.scalar_type = KISSM_SCALAR_FLOAT32;
    }
    kissm_config_init(&config, sizeof config);
    config.voxel_size = gc->voxel_size;
    config.num_threads = threads;
    result->struct_size = sizeof *result;
    status = kissm_create(&config, &matcher);
    if (status == KISSM_OK) status = kissm_register(matcher, &sp, &tp, result);
    if (status != KISSM_OK) fprintf(stderr, "%s: %s\n", gc->name, kissm_last_error_message());
    kissm_destroy(matcher);
    kissm_cloud_destroy(src);
    kissm_cloud_destroy(tgt);
    free(src32);
    free(tgt32);
    return status == KISSM_OK ? 0 : -1;
}

/* The counts, by the names golden.json uses (the kissm_result field names). */
/* One X(...) per field, wrapped by hand. */
/* clang-format off */
#define COUNT_FIELDS(X)                                                                                \
    X(num_source_points) X(num_target_points) X(num_source_voxels) X(num_target_voxels)              \
    X(num_source_keypoints) X(num_target_keypoints) X(num_initial_correspondences)                   \
    X(num_pruned_correspondences) X(num_rotation_inliers) X(num_final_inliers) X(max_core_number)
/* clang-format on */

static void write_golden(void) {
    size_t c;
    printf("{\n  \"generator\": \"tests/data/update_golden.sh (tests/roundtrip/test_roundtrip.c --write)\",\n");
    printf("  \"kissm_version\": \"%s\",\n", kissm_version_string());
    printf("  \"source\": \"roundtrip_source.ply\",\n  \"target\": \"roundtrip_target.ply\",\n");
    printf("  \"num_threads\": 1,\n  \"cases\": [\n");
    for (c = 0; c < NUM_CASES; ++c) {
        kissm_result r;
        int i;
        if (run_case(&kCases[c], 1, &r) != 0) exit(1);
        printf("    {\n      \"name\": \"%s\",\n", kCases[c].name);
        printf("      \"scalar\": \"%s\",\n", kCases[c].scalar_type == KISSM_SCALAR_FLOAT32 ? "float32" : "float64");
        printf("      \"voxel_size\": %.17g,\n", kCases[c].voxel_size);
        printf("      \"valid\": %d,\n      \"reason\": %d,\n", r.valid, r.reason);
        printf("      \"transform\": [");
        for (i = 0; i < 16; ++i) printf("%s%.17g", i ? ", " : "", r.transform[i]);
        printf("],\n");
#define PRINT_COUNT(f) printf("      \"" #f "\": %llu,\n", (unsigned long long)r.f);
        COUNT_FIELDS(PRINT_COUNT)
        printf("      \"residual_rms\": %.17g\n    }%s\n", r.residual_rms, c + 1 < NUM_CASES ? "," : "");
    }
    printf("  ]\n}\n");
}

/* The text of case `name` in the golden file: from its name to the closing brace. */
static const char *find_case(const char *text, const char *name, const char **end) {
    char key[256];
    const char *p;
    snprintf(key, sizeof key, "\"name\": \"%s\"", name);
    p = strstr(text, key);
    if (!p) return NULL;
    *end = strchr(p, '}');
    return *end ? p : NULL;
}

static const char *value_of(const char *begin, const char *end, const char *field) {
    char key[128];
    const char *p;
    snprintf(key, sizeof key, "\"%s\":", field);
    p = strstr(begin, key);
    return (p && p < end) ? p + strlen(key) : NULL;
}

static void check_case(const char *text, const golden_case *gc) {
    const char *end = NULL, *begin = find_case(text, gc->name, &end), *v;
    int32_t threads[] = {1, 2, 4};
    size_t t;
    CHECK_MSG(begin != NULL, "golden.json has no case %s", gc->name);
    if (!begin) return;
    for (t = 0; t < sizeof threads / sizeof threads[0]; ++t) {
        kissm_result r;
        int i;
        char *next;
        REQUIRE(run_case(gc, threads[t], &r) == 0);
        v = value_of(begin, end, "valid");
        CHECK(v && strtol(v, NULL, 10) == r.valid);
        v = value_of(begin, end, "reason");
        CHECK(v && strtol(v, NULL, 10) == r.reason);
        v = value_of(begin, end, "transform");
        REQUIRE(v != NULL);
        v = strchr(v, '[') + 1;
        for (i = 0; i < 16; ++i) {
            const double expect = strtod(v, &next);
            CHECK_MSG(memcmp(&expect, &r.transform[i], sizeof(double)) == 0, "%s threads %d transform[%d]: %.17g vs %.17g",
                      gc->name, (int)threads[t], i, expect, r.transform[i]);
            v = next + strspn(next, ", ");
        }
/* clang-format off */
#define CHECK_COUNT(f)                                                                                 \
    v = value_of(begin, end, #f);                                                                      \
    CHECK_MSG(v && strtoull(v, NULL, 10) == r.f, "%s threads %d: " #f " %llu", gc->name, (int)threads[t], \
              (unsigned long long)r.f);
/* clang-format on */
        COUNT_FIELDS(CHECK_COUNT)
        v = value_of(begin, end, "residual_rms");
        {
            const double expect = v ? strtod(v, NULL) : -1.0;
            CHECK(v && memcmp(&expect, &r.residual_rms, sizeof(double)) == 0);
        }
    }
    fprintf(stderr, "%s: matches golden.json at 1, 2 and 4 threads\n", gc->name);
}

int main(int argc, char **argv) {
    char path[4200];
    FILE *f;
    char *text;
    long size;
    size_t c;
    if (argc < 2) {
        fprintf(stderr, "usage: %s DATA_DIR [--write]\n", argv[0]);
        return 2;
    }
    snprintf(g_dir, sizeof g_dir, "%s", argv[1]);
    if (argc > 2 && strcmp(argv[2], "--write") == 0) {
        write_golden();
        return 0;
    }
    snprintf(path, sizeof path, "%s/golden.json", g_dir);
    f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "cannot open %s\n", path);
        return 1;
    }
    fseek(f, 0, SEEK_END);
    size = ftell(f);
    fseek(f, 0, SEEK_SET);
    text = (char *)calloc((size_t)size + 1, 1);
    if (!text || fread(text, 1, (size_t)size, f) != (size_t)size) return 1;
    fclose(f);
    for (c = 0; c < NUM_CASES; ++c) check_case(text, &kCases[c]);
    free(text);
    return TEST_SUMMARY();
}
