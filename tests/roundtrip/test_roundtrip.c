/* SPDX-License-Identifier: MIT */
/* Cross-language round trip, C side. Registers (kissm_register) or refines (kissm_refine, from the case's
 * "initial_transform") the clouds of tests/data (made by tools/make_roundtrip_data.py) as listed in
 * tests/data/golden.json, with the case's "refine" mode, and requires the result to equal the golden values
 * bit for bit: the transforms, the information matrix and every double (printed with %.17g, so they parse
 * back exactly; NaN is written as null), validity, reason and every count. The Python and Rust suites check
 * the same file, so the three languages agree with each other through it. Each case also runs at 2 and 4
 * threads.
 *
 * With --write, prints a fresh golden.json to stdout instead (tests/data/update_golden.sh). */
#include <math.h>
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
    int32_t refine_mode;         /* KISSM_REFINE_* */
    int is_refine_call;          /* kissm_refine from initial_transform() instead of kissm_register */
    int32_t viewpoint_mode;      /* KISSM_VIEWPOINT_* */
    int32_t suppression;         /* KISSM_SUPPRESS_* */
    int32_t rotation_dof;        /* 3 or 1 */
    double max_refine_rmse_gain; /* 0: the default */
    double min_refine_condition; /* 0: the default */
    int32_t allow_degenerate;    /* kissm_config.allow_degenerate */
    double max_ambiguity;        /* below 0: the default */
} golden_case;

static const golden_case kCases[] = {
    {"yard_float64_v0.25", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_NONE, 0, KISSM_VIEWPOINT_FIXED, KISSM_SUPPRESS_NONE,
     3, 0.0, 0.0, 0, -1.0},
    {"yard_float32_v0.3", KISSM_SCALAR_FLOAT32, 0.3, KISSM_REFINE_NONE, 0, KISSM_VIEWPOINT_FIXED, KISSM_SUPPRESS_NONE,
     3, 0.0, 0.0, 0, -1.0},
    {"yard_float64_v0.25_gicp", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_GICP, 0, KISSM_VIEWPOINT_FIXED,
     KISSM_SUPPRESS_NONE, 3, 0.0, 0.0, 0, -1.0},
    {"yard_float32_v0.3_point_to_plane", KISSM_SCALAR_FLOAT32, 0.3, KISSM_REFINE_POINT_TO_PLANE, 0,
     KISSM_VIEWPOINT_FIXED, KISSM_SUPPRESS_NONE, 3, 0.0, 0.0, 0, -1.0},
    {"yard_float64_v0.25_refine_gicp", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_GICP, 1, KISSM_VIEWPOINT_FIXED,
     KISSM_SUPPRESS_NONE, 3, 0.0, 0.0, 0, -1.0},
    {"yard_float64_v0.25_local", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_NONE, 0, KISSM_VIEWPOINT_LOCAL,
     KISSM_SUPPRESS_NONE, 3, 0.0, 0.0, 0, -1.0},
    {"yard_float32_v0.3_sign_free_gicp", KISSM_SCALAR_FLOAT32, 0.3, KISSM_REFINE_GICP, 0, KISSM_VIEWPOINT_SIGN_FREE,
     KISSM_SUPPRESS_NONE, 3, 0.0, 0.0, 0, -1.0},
    {"yard_float64_v0.25_ground", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_NONE, 0, KISSM_VIEWPOINT_FIXED,
     KISSM_SUPPRESS_GROUND, 3, 0.0, 0.0, 0, -1.0},
    {"yard_float32_v0.3_yaw_gicp", KISSM_SCALAR_FLOAT32, 0.3, KISSM_REFINE_GICP, 0, KISSM_VIEWPOINT_FIXED,
     KISSM_SUPPRESS_NONE, 1, 0.0, 0.0, 0, -1.0},
    /* kissm_refine held to a residual below what the yard's right alignment leaves: LOOSE_ALIGNMENT. */
    {"yard_float64_v0.25_refine_gicp_tight", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_GICP, 1, KISSM_VIEWPOINT_FIXED,
     KISSM_SUPPRESS_NONE, 3, 0.05, 0.0, 0, -1.0},
    /* A condition threshold above what the yard's directions reach: degenerate, with weak directions, and valid
     * because the case allows it. */
    {"yard_float64_v0.25_refine_gicp_allow_degenerate", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_GICP, 1,
     KISSM_VIEWPOINT_FIXED, KISSM_SUPPRESS_NONE, 3, 0.0, 0.5, 1, -1.0},
    /* An ambiguity bound below what the yard's best competing pose reaches: AMBIGUOUS, the refined pose kept. */
    {"yard_float64_v0.25_gicp_max_ambiguity", KISSM_SCALAR_FLOAT64, 0.25, KISSM_REFINE_GICP, 0, KISSM_VIEWPOINT_FIXED,
     KISSM_SUPPRESS_NONE, 3, 0.0, 0.0, 0, 0.05},
    /* The automatic voxel size (voxel_size 0): the pair's suggestion, reported in voxel_size_used. */
    {"yard_float64_auto", KISSM_SCALAR_FLOAT64, 0.0, KISSM_REFINE_NONE, 0, KISSM_VIEWPOINT_LOCAL, KISSM_SUPPRESS_NONE,
     3, 0.0, 0.0, 0, -1.0},
};

static const char *viewpoint_name(int32_t mode) {
    return mode == KISSM_VIEWPOINT_CLOUD_CENTER ? "cloud_center"
           : mode == KISSM_VIEWPOINT_SIGN_FREE  ? "sign_free"
           : mode == KISSM_VIEWPOINT_LOCAL      ? "local"
                                                : "fixed";
}

static const char *refine_name(int32_t mode) {
    return mode == KISSM_REFINE_GICP ? "gicp" : mode == KISSM_REFINE_POINT_TO_PLANE ? "point_to_plane" : "none";
}

#define NUM_CASES (sizeof(kCases) / sizeof(kCases[0]))

static char g_dir[4096];

/* The refine cases' start: the ground truth of tests/data turned by 3 degrees about z and moved by
 * (0.2, -0.15, 0.05), as a tracking prior would be off. */
static int initial_transform(double out[16]) {
    char path[4200];
    FILE *f;
    double gt[16];
    const double a = 3.0 * 3.14159265358979323846 / 180.0, c = cos(a), s = sin(a);
    const double turn[9] = {c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0}, shift[3] = {0.2, -0.15, 0.05};
    int i, j, k;
    char line[512];
    snprintf(path, sizeof path, "%s/roundtrip_ground_truth.txt", g_dir);
    f = fopen(path, "r");
    if (!f) return -1;
    for (i = 0; i < 4;) {
        if (!fgets(line, sizeof line, f)) break;
        if (line[0] == '#') continue;
        if (sscanf(line, "%lf %lf %lf %lf", &gt[4 * i], &gt[4 * i + 1], &gt[4 * i + 2], &gt[4 * i + 3]) != 4) break;
        ++i;
    }
    fclose(f);
    if (i != 4) return -1;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 4; ++j) {
            double v = 0.0;
            for (k = 0; k < 3; ++k) v += turn[3 * i + k] * gt[4 * k + j];
            out[4 * i + j] = v + (j == 3 ? shift[i] : 0.0);
        }
    }
    out[12] = out[13] = out[14] = 0.0;
    out[15] = 1.0;
    return 0;
}
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
    config.refine_mode = gc->refine_mode;
    config.viewpoint_mode = gc->viewpoint_mode;
    config.suppression = gc->suppression;
    config.rotation_dof = gc->rotation_dof;
    if (gc->max_refine_rmse_gain > 0.0) config.max_refine_rmse_gain = gc->max_refine_rmse_gain;
    if (gc->min_refine_condition > 0.0) config.min_refine_condition = gc->min_refine_condition;
    config.allow_degenerate = gc->allow_degenerate;
    if (gc->max_ambiguity >= 0.0) config.max_ambiguity = gc->max_ambiguity;
    result->struct_size = sizeof *result;
    status = kissm_create(&config, &matcher);
    if (status == KISSM_OK && gc->is_refine_call) {
        double initial[16];
        status = initial_transform(initial) == 0 ? kissm_refine(matcher, &sp, &tp, initial, result) : KISSM_ERR_IO;
    } else if (status == KISSM_OK) {
        status = kissm_register(matcher, &sp, &tp, result);
    }
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
    X(num_pruned_correspondences) X(num_rotation_inliers) X(num_final_inliers) X(max_core_number)    \
    X(num_refine_correspondences) X(refine_iterations) X(refine_converged) X(num_source_suppressed)     \
    X(num_target_suppressed) X(degenerate) X(num_weak_directions)
/* The doubles and arrays of doubles, by their golden.json names (NaN is written as null). */
#define SCALAR_FIELDS(X) X(residual_rms) X(overlap) X(refine_rmse) X(refine_condition) X(rotation_uncertainty) X(inlier_coverage) X(tilt) X(ambiguity) X(confidence) X(voxel_size_used)
#define ARRAY_FIELDS(X) X(transform, 16) X(coarse_transform, 16) X(information, 36) X(weak_directions, 36)
/* clang-format on */

static void print_double(double v) {
    if (v != v)
        printf("null");
    else
        printf("%.17g", v);
}

static void print_array(const char *name, const double *v, int n) {
    int i;
    printf("      \"%s\": [", name);
    for (i = 0; i < n; ++i) {
        printf("%s", i ? ", " : "");
        print_double(v[i]);
    }
    printf("],\n");
}

/* Parses a golden number or null (NaN) at *p and moves *p past it and its separator. */
static double parse_double(const char **p) {
    double v;
    char *next;
    *p += strspn(*p, " \t\r\n");
    if (strncmp(*p, "null", 4) == 0) {
        *p += 4;
        v = nan("");
    } else {
        v = strtod(*p, &next);
        *p = next;
    }
    *p += strspn(*p, ", ");
    return v;
}

/* kissm_config_init's max_refine_rmse_gain and min_refine_condition, written into every case so that the other
 * languages set them. */
static double default_rmse_gain(void) {
    kissm_config c;
    kissm_config_init(&c, sizeof c);
    return c.max_refine_rmse_gain;
}

static double default_max_ambiguity(void) {
    kissm_config c;
    kissm_config_init(&c, sizeof c);
    return c.max_ambiguity;
}

static double default_min_condition(void) {
    kissm_config c;
    kissm_config_init(&c, sizeof c);
    return c.min_refine_condition;
}

/* Bit for bit, or both NaN. */
static int same_double(double a, double b) { return (a != a && b != b) || memcmp(&a, &b, sizeof a) == 0; }

static void write_golden(void) {
    size_t c;
    printf("{\n  \"generator\": \"tests/data/update_golden.sh (tests/roundtrip/test_roundtrip.c --write)\",\n");
    printf("  \"kissm_version\": \"%s\",\n", kissm_version_string());
    printf("  \"source\": \"roundtrip_source.ply\",\n  \"target\": \"roundtrip_target.ply\",\n");
    printf("  \"num_threads\": 1,\n  \"cases\": [\n");
    for (c = 0; c < NUM_CASES; ++c) {
        kissm_result r;
        if (run_case(&kCases[c], 1, &r) != 0) exit(1);
        printf("    {\n      \"name\": \"%s\",\n", kCases[c].name);
        printf("      \"call\": \"%s\",\n", kCases[c].is_refine_call ? "refine" : "register");
        printf("      \"refine\": \"%s\",\n", refine_name(kCases[c].refine_mode));
        printf("      \"viewpoint\": \"%s\",\n", viewpoint_name(kCases[c].viewpoint_mode));
        printf("      \"suppression\": \"%s\",\n", kCases[c].suppression == KISSM_SUPPRESS_GROUND ? "ground" : "none");
        printf("      \"rotation_dof\": %d,\n", (int)kCases[c].rotation_dof);
        printf("      \"max_refine_rmse_gain\": %.17g,\n",
               kCases[c].max_refine_rmse_gain > 0.0 ? kCases[c].max_refine_rmse_gain : default_rmse_gain());
        printf("      \"min_refine_condition\": %.17g,\n",
               kCases[c].min_refine_condition > 0.0 ? kCases[c].min_refine_condition : default_min_condition());
        printf("      \"allow_degenerate\": %d,\n", (int)kCases[c].allow_degenerate);
        printf("      \"max_ambiguity\": %.17g,\n",
               kCases[c].max_ambiguity >= 0.0 ? kCases[c].max_ambiguity : default_max_ambiguity());
        printf("      \"scalar\": \"%s\",\n", kCases[c].scalar_type == KISSM_SCALAR_FLOAT32 ? "float32" : "float64");
        printf("      \"voxel_size\": %.17g,\n", kCases[c].voxel_size);
        if (kCases[c].is_refine_call) {
            double initial[16];
            if (initial_transform(initial) != 0) exit(1);
            print_array("initial_transform", initial, 16);
        }
        printf("      \"valid\": %d,\n      \"reason\": %d,\n", r.valid, r.reason);
#define PRINT_ARRAY(f, n) print_array(#f, r.f, n);
        ARRAY_FIELDS(PRINT_ARRAY)
#define PRINT_COUNT(f) printf("      \"" #f "\": %llu,\n", (unsigned long long)r.f);
        COUNT_FIELDS(PRINT_COUNT) {
            const char *sep = "";
#define PRINT_SCALAR(f) printf("%s      \"" #f "\": ", sep), print_double(r.f), sep = ",\n";
            SCALAR_FIELDS(PRINT_SCALAR)
        }
        printf("\n    }%s\n", c + 1 < NUM_CASES ? "," : "");
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
        REQUIRE(run_case(gc, threads[t], &r) == 0);
        v = value_of(begin, end, "valid");
        CHECK(v && strtol(v, NULL, 10) == r.valid);
        v = value_of(begin, end, "reason");
        CHECK(v && strtol(v, NULL, 10) == r.reason);
#define CHECK_ARRAY(f, n)                                                                                              \
  v = value_of(begin, end, #f);                                                                                        \
  REQUIRE(v != NULL);                                                                                                  \
  v = strchr(v, '[') + 1;                                                                                              \
  for (i = 0; i < (n); ++i) {                                                                                          \
    const double expect = parse_double(&v);                                                                            \
    CHECK_MSG(same_double(expect, r.f[i]), "%s threads %d " #f "[%d]: %.17g vs %.17g", gc->name, (int)threads[t], i,   \
              expect, r.f[i]);                                                                                         \
  }
        ARRAY_FIELDS(CHECK_ARRAY)
/* clang-format off */
#define CHECK_COUNT(f)                                                                                 \
    v = value_of(begin, end, #f);                                                                      \
    CHECK_MSG(v && strtoull(v, NULL, 10) == (unsigned long long)r.f, "%s threads %d: " #f " %llu", gc->name, (int)threads[t], \
              (unsigned long long)r.f);
        /* clang-format on */
        COUNT_FIELDS(CHECK_COUNT)
#define CHECK_SCALAR(f)                                                                                                \
  v = value_of(begin, end, #f);                                                                                        \
  REQUIRE(v != NULL);                                                                                                  \
  CHECK_MSG(same_double(parse_double(&v), r.f), "%s threads %d: " #f " %.17g", gc->name, (int)threads[t], r.f);
        SCALAR_FIELDS(CHECK_SCALAR)
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
