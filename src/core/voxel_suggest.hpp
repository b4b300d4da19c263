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

// Rungs per octave of the voxel ladder: suggestions are 2^(k / kSuggestRungsPerOctave) metres (k an integer),
// so a cloud moved, turned slightly or given in another point order lands on the same rung.
constexpr int kSuggestRungsPerOctave = 8;

// The voxel size for the clouds (1 or more) together: each cloud's own rung, then the smallest of them (the
// finest detail any cloud needs; a min does not depend on the clouds' order, so a pair's suggestion is the same
// with source and target swapped), raised if needed so every cloud's extent stays within the voxel grid's range.
// Non-finite points are ignored. Single-threaded and order-free: the same bits whatever the thread count.
// Throws Failure(EmptyInput) for a cloud without finite points, Failure(TooFewPoints) for one with fewer than 4
// or whose finite points all coincide (no length to measure). `names` name the clouds in messages.
double suggest_voxel_size(const std::vector<PointsView> &clouds, const std::vector<const char *> &names);

KISSM_DETAIL_END
