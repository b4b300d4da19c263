// SPDX-License-Identifier: MIT
// The automatic voxel size: chosen from the points alone, for one cloud or for several clouds that are to be
// described alike (a pair, a set of scans). The rule and its evidence: docs/design/voxel_auto.md.
#pragma once

#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// Occupied voxels the rule aims a cloud at: the voxel is the smallest rung of the ladder whose grid holds at
// most this many occupied voxels (a cloud of fewer than 4x as many finite points aims at a quarter of them).
constexpr std::uint64_t kSuggestTargetVoxels = 3000;

// A compact cloud (a surface folded about its own centre: an object scan, an indoor fragment) aims at fewer:
// it registers with two thirds of the voxels a LiDAR scan needs (docs/design/voxel_auto.md, table 3).
constexpr std::uint64_t kSuggestCompactVoxels = 2000;

// Compact: at the kSuggestTargetVoxels rung, occupied voxels per unit of sigma_1 * sigma_2 (the two largest
// principal spreads of the occupied voxels, in voxels) at least this. A plane gives about 12, the object scans
// and indoor fragments of the shared data 17-24, its LiDAR scans (sparse away from the sensor) 5-11.
constexpr double kCompactCoverage = 14.0;

// Rungs per octave of the voxel ladder: suggestions are 2^(k / kSuggestRungsPerOctave) metres (k an integer),
// so a cloud moved, turned slightly or given in another point order lands on the same rung.
constexpr int kSuggestRungsPerOctave = 8;

// The voxel size for the clouds (1 or more) together: each cloud's own rung, then their lower median (for a
// pair the smaller, the finer detail either needs; for a set, the rung a typical scan wants rather than its
// finest scan's; neither depends on the clouds' order, so a pair's suggestion is the same with source and target
// swapped), raised if needed so every cloud's extent stays within the voxel grid's range.
// Non-finite points are ignored. Single-threaded and order-free: the same bits whatever the thread count.
// Throws Failure(EmptyInput) for a cloud without finite points, Failure(TooFewPoints) for one with fewer than 4
// or whose finite points all coincide (no length to measure). `names` name the clouds in messages.
double suggest_voxel_size(const std::vector<PointsView> &clouds, const std::vector<const char *> &names);

KISSM_DETAIL_END
