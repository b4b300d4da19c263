// SPDX-License-Identifier: MIT
// Ground segmentation for geometric suppression (KISS-Matcher, Sec. III-B, \label{subsec:kissmatcher}: points
// on the ground flood the matching with look-alike correspondences, so they get no keypoint). The paper uses
// Patchwork (Lim et al., RA-L 2021) for it and numbers no equation; this is a region-wise ground model in
// the spirit of Patchwork and Patchwork++ (Lee et al., IROS 2022), written from their descriptions:
//  - a concentric zone model around the sensor in the plane perpendicular to `up`: zones of rings x sectors,
//    coarser far away, where the points are sparse;
//  - per bin, seeds from the lowest points, then a few iterations of a PCA plane fit and re-assignment of
//    the points within a distance of the plane (or below it);
//  - a bin is ground when its plane is upright (normal within 45 degrees of `up`), not elevated far above the
//    expected ground near the sensor (a car roof, a table) unless very flat, and has enough points.
// It runs on the voxel centroids (tens of thousands, not the raw scan), so its thresholds are in metres of
// the cloud and the seed counts are those of a thinned cloud.
#pragma once

#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

struct GroundParams {
    Eigen::Vector3d up{0.0, 0.0, 1.0};     // unit, in the cloud's own frame
    Eigen::Vector3d sensor{0.0, 0.0, 0.0}; // the sensor (the cloud frame's origin) in the coordinates of `points`
    double sensor_height = 0.0;            // metres of the sensor above the ground; 0 = unknown (estimate it)
    double voxel_size = 0.3;               // the voxel size the points were thinned with

    // The zone model covers horizontal distances [min_range, max_range) from the sensor; points outside are
    // never ground. Patchwork++'s KITTI defaults: within 2.7 m a car-mounted scanner sees its own vehicle.
    double min_range = 2.7;
    double max_range = 80.0;
    // A point is ground when its signed distance above its bin's plane is below this (points under the plane
    // are ground too: under-ground returns are not features either).
    double plane_distance = 0.125;
    // Seeds: the points at most this far above the mean height of the lowest points of a bin.
    double seed_distance = 0.125;
    // A bin's plane is upright when normal . up >= this (cos 45 degrees).
    double min_uprightness = 0.707;
};

// One flag per point of `points` (voxel centroids, float, offset frame as VoxelCloud::points): 1 = ground.
// Deterministic: depends only on the inputs, bitwise the same for any ctx.threads(). Never prints, never aborts.
// An `up` that is zero or not finite, or non-finite parameters, give no ground (all 0): validation is the
// caller's.
std::vector<std::uint8_t> segment_ground(const std::vector<Vec3f> &points, const GroundParams &params, RunContext &ctx);

// The height of the ground below the sensor along `up` (negative when the sensor is above it) estimated from
// the points near the sensor: the lowest dense layer of heights. NaN when too few points are near. Exposed for
// tests.
double estimate_ground_height(const std::vector<Vec3f> &points, const GroundParams &params);

KISSM_DETAIL_END
