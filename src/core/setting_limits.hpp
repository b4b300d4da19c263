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

namespace limits {

constexpr IntLimits num_threads{0, 1024};
constexpr RealLimits voxel_size{0.0, HUGE_VAL, true};
constexpr RealLimits fpfh_radius_gain{1.5, 50.0, false};
// normal_radius_gain's upper end is the configuration's fpfh_radius_gain.
constexpr RealLimits normal_radius_gain_below(double fpfh_gain) { return {0.0, fpfh_gain, true}; }
constexpr RealLimits max_linearity{0.0, 1.0, true};
constexpr RealLimits ratio_test{0.0, 1.0, true};
constexpr RealLimits prune_noise_bound_gain{0.0, 1e6, true};
constexpr RealLimits solver_noise_bound_gain{0.0, 1e6, true};
constexpr RealLimits noise_bound_max{0.0, 1e300, false};
constexpr IntLimits min_normal_neighbors{3, 100000};
constexpr IntLimits max_correspondences{3, 100000};
constexpr IntLimits min_inliers{3, 100000};
constexpr IntLimits refine_max_iterations{1, 1000};
constexpr RealLimits refine_max_distance_gain{0.0, 100.0, true};
constexpr RealLimits refine_kernel_gain{0.0, 100.0, true};
constexpr RealLimits refine_rotation_epsilon{0.0, 1.0, false};
constexpr RealLimits refine_translation_epsilon_gain{0.0, 1.0, false};
constexpr RealLimits min_overlap{0.0, 1.0, false};
constexpr RealLimits max_rotation_uncertainty{0.0, 3.15, true};
constexpr RealLimits min_inlier_coverage{0.0, 1.0, false};
constexpr IntLimits refine_min_inliers{3, 100000};
constexpr RealLimits min_refine_condition{0.0, 1.0, false};
constexpr RealLimits refine_normal_radius_gain{0.0, 50.0, true};
constexpr RealLimits sensor_height{0.0, 1000.0, false};

} // namespace limits

// Every field of `limits` but normal_radius_gain (whose upper end is fpfh_radius_gain), for the docs check.
#define KISSM_SETTING_LIMITS(X)                                                                                        \
  X(num_threads)                                                                                                       \
  X(voxel_size)                                                                                                        \
  X(fpfh_radius_gain)                                                                                                  \
  X(max_linearity)                                                                                                     \
  X(ratio_test)                                                                                                        \
  X(prune_noise_bound_gain)                                                                                            \
  X(solver_noise_bound_gain)                                                                                           \
  X(noise_bound_max)                                                                                                   \
  X(min_normal_neighbors)                                                                                              \
  X(max_correspondences)                                                                                               \
  X(min_inliers)                                                                                                       \
  X(refine_max_iterations)                                                                                             \
  X(refine_max_distance_gain)                                                                                          \
  X(refine_kernel_gain)                                                                                                \
  X(refine_rotation_epsilon)                                                                                           \
  X(refine_translation_epsilon_gain)                                                                                   \
  X(min_overlap)                                                                                                       \
  X(max_rotation_uncertainty)                                                                                          \
  X(min_inlier_coverage)                                                                                               \
  X(refine_min_inliers)                                                                                                \
  X(min_refine_condition)                                                                                              \
  X(refine_normal_radius_gain)                                                                                         \
  X(sensor_height)

KISSM_DETAIL_END
