// SPDX-License-Identifier: MIT
// Stage 1: one centroid per occupied voxel.
// The paper (KISS-Matcher, Sec. III-A, \label{subsec:problem}) takes clouds voxelised with voxel size v as
// its input; it numbers no equation for the voxel centroid, which is here the mean of the voxel's points.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "detail_namespace.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// At most this many voxels per axis: keys then pack into 63 bits, and single-precision local coordinates
// stay well below the voxel size (half the extent carries at most v/16 of rounding).
constexpr std::uint64_t kMaxVoxelsPerAxis = std::uint64_t(1) << 21;

// The grid is anchored at the cloud's bounding-box minimum; the local origin is the bounding-box centre.
// Output order is by voxel key (x-major), independent of input order and thread count; centroids come from
// integer sums of fixed-point offsets, so a permutation of the input gives a bitwise identical output.
// Throws Failure(VoxelRange) when the extent needs more than kMaxVoxelsPerAxis voxels on an axis.
// keys, when given, receives each voxel's grid key (ascending: the voxels come in key order), for
// voxel_of_points.
VoxelCloud voxelize(const InputCloud &input, double voxel_size, const std::string &name, RunContext &ctx,
                    std::vector<std::uint64_t> *keys = nullptr);

constexpr std::uint32_t kNoVoxel = ~std::uint32_t(0);

// For each point of `input`, the number of its voxel in voxelize(input, voxel_size, ...), whose keys are
// `keys` (kNoVoxel for a non-finite point the policy drops): how a per-voxel label reaches the caller's points.
std::vector<std::uint32_t> voxel_of_points(const InputCloud &input, double voxel_size, const std::string &name,
                                           const std::vector<std::uint64_t> &keys, RunContext &ctx);

KISSM_DETAIL_END
