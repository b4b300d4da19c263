/* SPDX-License-Identifier: MIT */
/* Harness of docs_readme_c_snippet (readme_c_snippet.cmake puts README.md's "C API in short" block where
 * KISSM_README_SNIPPET_HERE stands, unchanged).
 *
 *   readme_snippet SOURCE TARGET GROUND_TRUTH
 *
 * Gives the snippet what it uses without declaring: src_xyz / n_src (SOURCE as float64, packed), tgt_xyz /
 * n_tgt (TARGET converted to float32, packed), <stdio.h>. After the snippet, in the same scope, checks the
 * `status` and `result` it left: KISSM_OK, a valid pose, and close to GROUND_TRUTH (4 rows of 4 numbers
 * after a # comment line, tests/data/roundtrip_ground_truth.txt). Exit status 0 only then. */
#include <kissm.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static const double *src_xyz;
static uint64_t n_src;
static const float *tgt_xyz;
static uint64_t n_tgt;

static double ground_truth[16];
static int snippet_verdict = -1; /* set after the snippet: 0 = checks passed */

static int check_pose(int32_t status, const kissm_result *result) {
    int i;
    double worst_rotation = 0.0, worst_translation = 0.0;
    if (status != KISSM_OK) {
        fprintf(stderr, "readme_snippet: kissm_register returned %d\n", (int)status);
        return 1;
    }
    if (result->valid != 1) {
        fprintf(stderr, "readme_snippet: no valid pose (%s)\n", kissm_reason_string(result->reason));
        return 1;
    }
    for (i = 0; i < 12; ++i) {
        double d = fabs(result->transform[i] - ground_truth[i]);
        if (!(d == d)) d = HUGE_VAL; /* NaN */
        if (i % 4 == 3) {
            if (d > worst_translation) worst_translation = d;
        } else if (d > worst_rotation) {
            worst_rotation = d;
        }
    }
    printf("readme_snippet: valid pose, %llu inliers; largest error %.2e (rotation entry), %.2e (translation)\n",
           (unsigned long long)result->num_final_inliers, worst_rotation, worst_translation);
    /* The clouds are a rigid copy with noise: the pose must be close, at the snippet's voxel size too. */
    if (worst_rotation > 0.05 || worst_translation > 0.25) {
        fprintf(stderr, "readme_snippet: the pose is far from the ground truth\n");
        return 1;
    }
    return 0;
}

/* The snippet's own returns (`return 1;` on a failed kissm_create) end up here too. */
static int readme_snippet(void) {
    /* KISSM_README_SNIPPET_HERE */
    snippet_verdict = check_pose(status, &result);
    return 0;
}

static int read_ground_truth(const char *path) {
    FILE *f = fopen(path, "r");
    int c, i, ok = f != NULL;
    if (!ok) return 0;
    while ((c = fgetc(f)) != EOF && c != '\n') { /* the # comment line */
    }
    for (i = 0; ok && i < 16; ++i) ok = fscanf(f, "%lf", &ground_truth[i]) == 1;
    fclose(f);
    return ok;
}

int main(int argc, char **argv) {
    kissm_cloud *source = NULL, *target = NULL;
    float *target32 = NULL;
    uint64_t i;
    int snippet_status;

    if (argc != 4 || !read_ground_truth(argv[3])) {
        fprintf(stderr, "usage: readme_snippet SOURCE TARGET GROUND_TRUTH (readable, 16 numbers)\n");
        return 2;
    }
    if (kissm_read_points(argv[1], KISSM_FORMAT_AUTO, &source) != KISSM_OK ||
        kissm_read_points(argv[2], KISSM_FORMAT_AUTO, &target) != KISSM_OK) {
        fprintf(stderr, "readme_snippet: cannot read the clouds: %s\n", kissm_last_error_message());
        return 2;
    }
    src_xyz = kissm_cloud_data(source);
    n_src = kissm_cloud_count(source);
    n_tgt = kissm_cloud_count(target);
    target32 = malloc((size_t)n_tgt * 3 * sizeof *target32);
    if (target32 == NULL) return 2;
    for (i = 0; i < 3 * n_tgt; ++i) target32[i] = (float)kissm_cloud_data(target)[i];
    tgt_xyz = target32;
    printf("readme_snippet: %llu source points (float64), %llu target points (float32)\n", (unsigned long long)n_src,
           (unsigned long long)n_tgt);

    snippet_status = readme_snippet();
    free(target32);
    kissm_cloud_destroy(source);
    kissm_cloud_destroy(target);
    if (snippet_status != 0) {
        fprintf(stderr, "readme_snippet: the snippet returned %d\n", snippet_status);
        return 1;
    }
    if (snippet_verdict != 0) {
        fprintf(stderr, "readme_snippet: %s\n",
                snippet_verdict < 0 ? "the checks after the snippet did not run"
                                    : "the snippet did not find the right pose");
        return 1;
    }
    printf("readme_snippet: PASS\n");
    return 0;
}
