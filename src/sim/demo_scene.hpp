// SPDX-License-Identifier: MIT
// The synthetic outdoor scene behind `kissm demo`: a street with buildings, poles, trees, parked cars and
// clutter on rough, gently undulating ground, scanned twice by a simulated spinning LiDAR (ray casting
// against the analytic primitives, so occlusion and partial overlap are real). Everything is a deterministic
// function of the options (seed included); no std::random_device and no std:: distributions are used.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "pose_math.hpp"

namespace kissm_sim {
using namespace kissm_pose; // src/common/pose_math.hpp

struct DemoOptions {
    uint64_t seed = 1;
    int beams = 64;              // rows of the spinning sensor
    int azimuth_steps = 900;     // columns per revolution (0.4 degrees)
    double fov_up_deg = 2.0;     // elevation of the top beam
    double fov_down_deg = -24.8; // elevation of the bottom beam
    // HDL-64E-like layout: the upper half of the beams spans fov_up..split_deg (about 1/3 degree apart), the
    // lower half split_deg - 0.5 .. fov_down (about 1/2 degree apart). Otherwise the beams are evenly spread.
    bool dense_upper_block = true;
    double split_deg = -8.33;
    double max_range = 60.0;    // metres; farther returns are lost
    double min_range = 1.0;     // metres; nearer returns are discarded (the vehicle itself)
    double range_noise = 0.015; // metres, one sigma, along the beam
    double dropout = 0.02;      // probability that a return is lost
    double sensor_height = 1.8; // metres above the ground
    // Relative motion between the two sensor poses: distance along the street and yaw.
    double min_distance = 10.0, max_distance = 15.0; // metres
    double min_yaw_deg = 120.0, max_yaw_deg = 165.0; // either direction
    double max_tilt_deg = 3.0;                       // roll and pitch of each pose
};

struct DemoScan {
    std::vector<double> xyz; // packed x y z, in the sensor frame (sensor at the origin)
    Pose sensor_in_world;    // p_world = R p_sensor + t
    size_t rays = 0;         // rays cast
};

struct DemoSceneStats {
    int buildings = 0; // building boxes (annexes included)
    int walls = 0;     // low walls and fences
    int poles = 0;     // street lights and sign posts
    int trees = 0;
    int cars = 0;          // parked (in both scans)
    int movers = 0;        // vehicles present in one scan only
    int clutter = 0;       // bins, bollards, boxes, bushes
    int details = 0;       // facade columns, balconies, entrances
    size_t primitives = 0; // analytic primitives, ground excluded
};

struct DemoData {
    DemoScan source;
    DemoScan target;
    // Ground truth: maps source-frame points into the target frame (row-major 4x4).
    double gt_target_from_source[16];
    DemoSceneStats stats;
};

DemoData generate_demo(const DemoOptions &options);

} // namespace kissm_sim
