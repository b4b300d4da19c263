// SPDX-License-Identifier: MIT
// The simulated spinning LiDAR of `kissm demo`: where the two sensor poses are, and the scans they see.
// Each ray keeps its nearest hit among the scene's primitives and the ground (ray_geometry.hpp), so
// everything behind a wall, a car or a tree is hidden exactly as for a real sensor; then returns out of
// range are lost, a share drops out at random and the range gets Gaussian noise along the beam.
#pragma once

#include "demo_scene.hpp"
#include "pose_math.hpp"
#include "ray_geometry.hpp"
#include "rng.hpp"

namespace kissm_sim {
using namespace kissm_pose; // src/common/pose_math.hpp

struct SensorPoses {
    Pose source;
    Pose target;
};

// Both poses in the lanes y in [lane_lo, lane_hi] of the main street, options.min_distance to
// options.max_distance apart, with a large relative yaw and a little roll and pitch (a vehicle on a cambered
// road), options.sensor_height above the ground.
SensorPoses draw_sensor_poses(Rng &rng, const Ground &ground, double lane_lo, double lane_hi,
                              const DemoOptions &options);

// One revolution of the sensor at the given pose (options: beams, azimuth steps, ranges, noise, dropout);
// the points are in the sensor frame.
DemoScan cast_scan(const Scene &scene, const Pose &sensor, const DemoOptions &opt, Rng &rng);

} // namespace kissm_sim
