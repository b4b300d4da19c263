// SPDX-License-Identifier: MIT
// The ranges of the numeric settings, once: the C boundary's validation (src/capi/config.cpp) and the features
// format's reader (features_codec.cpp) both check against these, and docs/parameters.md's "Ranges" table is
// checked against them (tests/core/test_setting_limits.cpp).
#pragma once

#include <cmath>
#include <cstdint>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// [lo, hi], or (lo, hi] when lo_open; finite values only (hi may be infinite: "any finite value above lo").
struct RealLimits {
    double lo;
    double hi;
    bool lo_open;
    bool contains(double v) const { return std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi; }
};

// [lo, hi].
struct IntLimits {
    std::int64_t lo;
    std::int64_t hi;
    constexpr bool contains(std::int64_t v) const { return v >= lo && v <= hi; }
};

// Every numeric setting's range but normal_radius_gain's (below): REAL(field, lo, hi, lo_open), INT(field, lo, hi).
#define KISSM_SETTING_LIMITS(REAL, INT)                                                                                \
  INT(num_threads, 0, 1024)                                                                                            \
  REAL(voxel_size, 0.0, HUGE_VAL, true)                                                                                \
  REAL(fpfh_radius_gain, 1.5, 50.0, false)                                                                             \
  REAL(max_linearity, 0.0, 1.0, true)                                                                                  \
  REAL(ratio_test, 0.0, 1.0, true)                                                                                     \
  REAL(prune_noise_bound_gain, 0.0, 1e6, true)                                                                         \
  REAL(solver_noise_bound_gain, 0.0, 1e6, true)                                                                        \
  REAL(noise_bound_max, 0.0, 1e300, false)                                                                             \
  INT(min_normal_neighbors, 3, 100000)                                                                                 \
  INT(max_correspondences, 3, 100000)                                                                                  \
  INT(min_inliers, 3, 100000)                                                                                          \
  INT(refine_max_iterations, 1, 1000)                                                                                  \
  REAL(refine_max_distance_gain, 0.0, 100.0, true)                                                                     \
  REAL(refine_kernel_gain, 0.0, 100.0, true)                                                                           \
  REAL(refine_rotation_epsilon, 0.0, 1.0, false)                                                                       \
  REAL(refine_translation_epsilon_gain, 0.0, 1.0, false)                                                               \
  REAL(min_overlap, 0.0, 1.0, false)                                                                                   \
  REAL(max_rotation_uncertainty, 0.0, 3.15, true)                                                                      \
  REAL(min_inlier_coverage, 0.0, 1.0, false)                                                                           \
  INT(refine_min_inliers, 3, 100000)                                                                                   \
  REAL(min_refine_condition, 0.0, 1.0, false)                                                                          \
  REAL(refine_normal_radius_gain, 0.0, 50.0, true)                                                                     \
  REAL(sensor_height, 0.0, 1000.0, false)                                                                              \
  REAL(max_refine_rmse_gain, 0.0, 100.0, true)                                                                         \
  INT(allow_degenerate, 0, 1)                                                                                          \
  REAL(max_ambiguity, 0.0, 1.0, false)

namespace limits {

#define KISSM_REAL_LIMITS(field, lo, hi, lo_open) constexpr RealLimits field{lo, hi, lo_open};
#define KISSM_INT_LIMITS(field, lo, hi) constexpr IntLimits field{lo, hi};
KISSM_SETTING_LIMITS(KISSM_REAL_LIMITS, KISSM_INT_LIMITS)
#undef KISSM_REAL_LIMITS
#undef KISSM_INT_LIMITS

// normal_radius_gain's upper end is the configuration's fpfh_radius_gain.
constexpr RealLimits normal_radius_gain_below(double fpfh_gain) { return {0.0, fpfh_gain, true}; }

} // namespace limits

KISSM_DETAIL_END
