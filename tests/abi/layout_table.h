/* SPDX-License-Identifier: MIT */
/* The layout of every public struct of kissm.h, field by field, in declaration order, for 64-bit targets
 * (x86-64 and aarch64: 8-byte pointers, 8-byte aligned doubles and uint64_t).
 *
 *   X(struct, field, type, offset, size)
 *
 * layout.c turns each row into _Static_asserts against the compiled header, layout_types.cpp checks each
 * field's type, and `abi_layout --json` prints the compiled layout as tests/abi/layout.json, the file the
 * Python and Rust tests compare their own declarations with.
 *
 * These numbers are the ABI. A published row never changes: new fields are appended at the end of
 * kissm_config, kissm_result and kissm_align_options only (they carry struct_size); kissm_points is frozen. See
 * docs/abi-policy.md. */
#ifndef KISSM_TEST_ABI_LAYOUT_TABLE_H
#define KISSM_TEST_ABI_LAYOUT_TABLE_H

/* X(struct, id, size): the structs, with their KISSM_STRUCT_* id and sizeof. */
#define KISSM_LAYOUT_STRUCTS(X)                                                                                        \
  X(kissm_config, KISSM_STRUCT_CONFIG, 304)                                                                            \
  X(kissm_points, KISSM_STRUCT_POINTS, 32)                                                                             \
  X(kissm_result, KISSM_STRUCT_RESULT, 1272)                                                                           \
  X(kissm_align_options, KISSM_STRUCT_ALIGN_OPTIONS, 80)

#define KISSM_LAYOUT_CONFIG(X)                                                                                         \
  X(kissm_config, struct_size, uint32_t, 0, 4)                                                                         \
  X(kissm_config, num_threads, int32_t, 4, 4)                                                                          \
  X(kissm_config, voxel_size, double, 8, 8)                                                                            \
  X(kissm_config, normal_radius_gain, double, 16, 8)                                                                   \
  X(kissm_config, fpfh_radius_gain, double, 24, 8)                                                                     \
  X(kissm_config, max_linearity, double, 32, 8)                                                                        \
  X(kissm_config, ratio_test, double, 40, 8)                                                                           \
  X(kissm_config, prune_noise_bound_gain, double, 48, 8)                                                               \
  X(kissm_config, solver_noise_bound_gain, double, 56, 8)                                                              \
  X(kissm_config, noise_bound_max, double, 64, 8)                                                                      \
  X(kissm_config, viewpoint, double[3], 72, 24)                                                                        \
  X(kissm_config, min_normal_neighbors, int32_t, 96, 4)                                                                \
  X(kissm_config, max_correspondences, int32_t, 100, 4)                                                                \
  X(kissm_config, min_inliers, int32_t, 104, 4)                                                                        \
  X(kissm_config, nonfinite_policy, int32_t, 108, 4)                                                                   \
  X(kissm_config, viewpoint_mode, int32_t, 112, 4)                                                                     \
  X(kissm_config, log_level, int32_t, 116, 4)                                                                          \
  X(kissm_config, log_fn, kissm_log_fn, 120, 8)                                                                        \
  X(kissm_config, log_user_data, void *, 128, 8)                                                                       \
  X(kissm_config, progress_fn, kissm_progress_fn, 136, 8)                                                              \
  X(kissm_config, progress_user_data, void *, 144, 8)                                                                  \
  X(kissm_config, refine_mode, int32_t, 152, 4)                                                                        \
  X(kissm_config, refine_max_iterations, int32_t, 156, 4)                                                              \
  X(kissm_config, refine_max_distance_gain, double, 160, 8)                                                            \
  X(kissm_config, refine_kernel_gain, double, 168, 8)                                                                  \
  X(kissm_config, refine_rotation_epsilon, double, 176, 8)                                                             \
  X(kissm_config, refine_translation_epsilon_gain, double, 184, 8)                                                     \
  X(kissm_config, max_rotation_uncertainty, double, 192, 8)                                                            \
  X(kissm_config, min_overlap, double, 200, 8)                                                                         \
  X(kissm_config, min_inlier_coverage, double, 208, 8)                                                                 \
  X(kissm_config, refine_min_inliers, int32_t, 216, 4)                                                                 \
  X(kissm_config, reserved1, int32_t, 220, 4)                                                                          \
  X(kissm_config, min_refine_condition, double, 224, 8)                                                                \
  X(kissm_config, refine_normal_radius_gain, double, 232, 8)                                                           \
  X(kissm_config, suppression, int32_t, 240, 4)                                                                        \
  X(kissm_config, rotation_dof, int32_t, 244, 4)                                                                       \
  X(kissm_config, up, double[3], 248, 24)                                                                              \
  X(kissm_config, sensor_height, double, 272, 8)                                                                       \
  X(kissm_config, max_refine_rmse_gain, double, 280, 8)                                                                \
  X(kissm_config, allow_degenerate, int32_t, 288, 4)                                                                   \
  X(kissm_config, reserved2, int32_t, 292, 4)                                                                          \
  X(kissm_config, max_ambiguity, double, 296, 8)

#define KISSM_LAYOUT_POINTS(X)                                                                                         \
  X(kissm_points, data, const void *, 0, 8)                                                                            \
  X(kissm_points, count, uint64_t, 8, 8)                                                                               \
  X(kissm_points, stride_bytes, uint64_t, 16, 8)                                                                       \
  X(kissm_points, scalar_type, int32_t, 24, 4)                                                                         \
  X(kissm_points, reserved, int32_t, 28, 4)

#define KISSM_LAYOUT_RESULT(X)                                                                                         \
  X(kissm_result, struct_size, uint32_t, 0, 4)                                                                         \
  X(kissm_result, valid, int32_t, 4, 4)                                                                                \
  X(kissm_result, reason, int32_t, 8, 4)                                                                               \
  X(kissm_result, reserved0, int32_t, 12, 4)                                                                           \
  X(kissm_result, transform, double[16], 16, 128)                                                                      \
  X(kissm_result, rotation, double[9], 144, 72)                                                                        \
  X(kissm_result, translation, double[3], 216, 24)                                                                     \
  X(kissm_result, num_source_points, uint64_t, 240, 8)                                                                 \
  X(kissm_result, num_target_points, uint64_t, 248, 8)                                                                 \
  X(kissm_result, num_source_nonfinite, uint64_t, 256, 8)                                                              \
  X(kissm_result, num_target_nonfinite, uint64_t, 264, 8)                                                              \
  X(kissm_result, num_source_voxels, uint64_t, 272, 8)                                                                 \
  X(kissm_result, num_target_voxels, uint64_t, 280, 8)                                                                 \
  X(kissm_result, num_source_keypoints, uint64_t, 288, 8)                                                              \
  X(kissm_result, num_target_keypoints, uint64_t, 296, 8)                                                              \
  X(kissm_result, num_initial_correspondences, uint64_t, 304, 8)                                                       \
  X(kissm_result, num_pruned_correspondences, uint64_t, 312, 8)                                                        \
  X(kissm_result, num_rotation_inliers, uint64_t, 320, 8)                                                              \
  X(kissm_result, num_final_inliers, uint64_t, 328, 8)                                                                 \
  X(kissm_result, max_core_number, uint64_t, 336, 8)                                                                   \
  X(kissm_result, inlier_ratio, double, 344, 8)                                                                        \
  X(kissm_result, residual_rms, double, 352, 8)                                                                        \
  X(kissm_result, noise_bound, double, 360, 8)                                                                         \
  X(kissm_result, inlier_extent, double[3], 368, 24)                                                                   \
  X(kissm_result, time_voxelize_ms, double, 392, 8)                                                                    \
  X(kissm_result, time_features_ms, double, 400, 8)                                                                    \
  X(kissm_result, time_matching_ms, double, 408, 8)                                                                    \
  X(kissm_result, time_pruning_ms, double, 416, 8)                                                                     \
  X(kissm_result, time_solver_ms, double, 424, 8)                                                                      \
  X(kissm_result, time_total_ms, double, 432, 8)                                                                       \
  X(kissm_result, coarse_transform, double[16], 440, 128)                                                              \
  X(kissm_result, information, double[36], 568, 288)                                                                   \
  X(kissm_result, overlap, double, 856, 8)                                                                             \
  X(kissm_result, refine_rmse, double, 864, 8)                                                                         \
  X(kissm_result, refine_condition, double, 872, 8)                                                                    \
  X(kissm_result, rotation_uncertainty, double, 880, 8)                                                                \
  X(kissm_result, inlier_coverage, double, 888, 8)                                                                     \
  X(kissm_result, time_refine_ms, double, 896, 8)                                                                      \
  X(kissm_result, num_refine_correspondences, uint64_t, 904, 8)                                                        \
  X(kissm_result, refine_iterations, int32_t, 912, 4)                                                                  \
  X(kissm_result, refine_converged, int32_t, 916, 4)                                                                   \
  X(kissm_result, num_source_suppressed, uint64_t, 920, 8)                                                             \
  X(kissm_result, num_target_suppressed, uint64_t, 928, 8)                                                             \
  X(kissm_result, time_suppression_ms, double, 936, 8)                                                                 \
  X(kissm_result, tilt, double, 944, 8)                                                                                \
  X(kissm_result, degenerate, int32_t, 952, 4)                                                                         \
  X(kissm_result, num_weak_directions, int32_t, 956, 4)                                                                \
  X(kissm_result, weak_directions, double[36], 960, 288)                                                               \
  X(kissm_result, ambiguity, double, 1248, 8)                                                                          \
  X(kissm_result, confidence, double, 1256, 8)                                                                         \
  X(kissm_result, voxel_size_used, double, 1264, 8)

#define KISSM_LAYOUT_ALIGN_OPTIONS(X)                                                                                  \
  X(kissm_align_options, struct_size, uint32_t, 0, 4)                                                                  \
  X(kissm_align_options, pairs, int32_t, 4, 4)                                                                         \
  X(kissm_align_options, pair_list, const uint64_t *, 8, 8)                                                            \
  X(kissm_align_options, num_pairs, uint64_t, 16, 8)                                                                   \
  X(kissm_align_options, priors, const double *, 24, 8)                                                                \
  X(kissm_align_options, loop_radius, double, 32, 8)                                                                   \
  X(kissm_align_options, loop_gap, int32_t, 40, 4)                                                                     \
  X(kissm_align_options, loops_per_scan, int32_t, 44, 4)                                                               \
  X(kissm_align_options, bound, double, 48, 8)                                                                         \
  X(kissm_align_options, sessions, const uint32_t *, 56, 8)                                                            \
  X(kissm_align_options, stride, int32_t, 64, 4)                                                                       \
  X(kissm_align_options, reserved, int32_t, 68, 4)                                                                     \
  X(kissm_align_options, similar_per_scan, int32_t, 72, 4)                                                             \
  X(kissm_align_options, reserved2, int32_t, 76, 4)

#define KISSM_LAYOUT_FIELDS(X)                                                                                         \
  KISSM_LAYOUT_CONFIG(X) KISSM_LAYOUT_POINTS(X) KISSM_LAYOUT_RESULT(X) KISSM_LAYOUT_ALIGN_OPTIONS(X)

#endif
