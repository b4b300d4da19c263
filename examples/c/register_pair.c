/* SPDX-License-Identifier: MIT */
/* A small kissm consumer: reads two point clouds through the API, registers them and prints the pose.
 *
 *   kissm_example SOURCE TARGET [VOXEL_SIZE]
 *
 * SOURCE and TARGET may be PLY, PCD, KITTI .bin, raw float32 .bin, .npy, xyz text or LAS files (whatever
 * kissm_read_points() reads). VOXEL_SIZE is in the clouds' unit (default 0.3, for LiDAR scans in metres).
 * Prints the rigid transform that maps SOURCE points into TARGET's frame.
 * Exit status: 0 a valid pose, 1 no trustworthy pose, 2 an error.
 *
 * Plain C99; builds against an installed kissm with CMake (find_package) or pkg-config: see README.md. */
#include <kissm.h>

#include <stdio.h>
#include <stdlib.h>

static int report_failure(const char *what, int32_t status) {
    fprintf(stderr, "kissm_example: %s failed: %s (%d): %s\n", what, kissm_status_string(status), (int)status,
            kissm_last_error_message());
    return 2;
}

static int read_cloud(const char *path, kissm_cloud **cloud, kissm_points *points) {
    int32_t status = kissm_read_points(path, KISSM_FORMAT_AUTO, cloud);
    if (status != KISSM_OK) return report_failure("kissm_read_points", status);
    status = kissm_cloud_points(*cloud, points);
    if (status != KISSM_OK) return report_failure("kissm_cloud_points", status);
    return 0;
}

int main(int argc, char **argv) {
    kissm_cloud *source_cloud = NULL, *target_cloud = NULL;
    kissm_points source, target;
    kissm_config config;
    kissm_matcher *matcher = NULL;
    kissm_result result;
    double voxel_size = 0.3;
    int32_t status;
    int exit_code = 2, row;

    if (argc < 3 || argc > 4) {
        fprintf(stderr, "usage: %s SOURCE TARGET [VOXEL_SIZE]\n", argc > 0 ? argv[0] : "kissm_example");
        return 2;
    }
    if (argc == 4) {
        char *end = NULL;
        voxel_size = strtod(argv[3], &end);
        if (end == argv[3] || *end != '\0') {
            fprintf(stderr, "kissm_example: VOXEL_SIZE '%s' is not a number\n", argv[3]);
            return 2;
        }
    }

    /* The library this program runs with must have the ABI of the header it was compiled against. */
    if (kissm_abi_version() != KISSM_ABI_VERSION) {
        fprintf(stderr, "kissm_example: built for kissm ABI %d but running with ABI %u (%s)\n", KISSM_ABI_VERSION,
                (unsigned)kissm_abi_version(), kissm_version_string());
        return 2;
    }
    printf("kissm %s (header %s, ABI %u)\n", kissm_version_string(), KISSM_VERSION_STRING,
           (unsigned)kissm_abi_version());

    if (read_cloud(argv[1], &source_cloud, &source) != 0 || read_cloud(argv[2], &target_cloud, &target) != 0) goto done;
    printf("source: %llu points, target: %llu points, voxel size %g\n", (unsigned long long)source.count,
           (unsigned long long)target.count, voxel_size);

    status = kissm_config_init(&config, (uint32_t)sizeof config);
    if (status != KISSM_OK) {
        exit_code = report_failure("kissm_config_init", status);
        goto done;
    }
    config.voxel_size = voxel_size;
    status = kissm_create(&config, &matcher);
    if (status != KISSM_OK) {
        exit_code = report_failure("kissm_create", status);
        goto done;
    }

    result.struct_size = (uint32_t)sizeof result;
    status = kissm_register(matcher, &source, &target, &result);
    if (status != KISSM_OK) {
        exit_code = report_failure("kissm_register", status);
        goto done;
    }

    printf("valid: %s", result.valid ? "yes" : "no");
    if (!result.valid) printf(" (%s)", kissm_reason_string(result.reason));
    printf("\ntransform (maps source points into the target frame):\n");
    for (row = 0; row < 4; ++row) {
        const double *r = &result.transform[4 * row];
        printf("  [ %12.8f %12.8f %12.8f %14.8f ]\n", r[0], r[1], r[2], r[3]);
    }
    printf("correspondences: %llu initial, %llu after pruning, %llu final inliers (rms %.4f)\n",
           (unsigned long long)result.num_initial_correspondences,
           (unsigned long long)result.num_pruned_correspondences, (unsigned long long)result.num_final_inliers,
           result.residual_rms);
    exit_code = result.valid ? 0 : 1;

done:
    kissm_destroy(matcher);
    kissm_cloud_destroy(source_cloud);
    kissm_cloud_destroy(target_cloud);
    return exit_code;
}
