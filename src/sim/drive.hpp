// SPDX-License-Identifier: MIT
// A long simulated drive through a city (city_layout.hpp): the vehicle follows its lane through the grid,
// turning at crossings with rounded corners, and comes back to crossings and streets it has driven before
// (real loops); the spinning LiDAR of the demo scans every `spacing` metres along the way. The poses are exact
// (the ground truth), the scans are in their sensor frames.
//
// Random streams of the seed: 0 the city, 1 the route and the vehicle's sway, 2 + i scan i (its traffic, its
// noise and dropout). A scan is a function of (seed, i) alone, so scans can be cast in any order, on any
// number of threads, with the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "city_layout.hpp"
#include "demo_scene.hpp"
#include "pose_math.hpp"

namespace kissm_sim {
using namespace kissm_pose; // src/common/pose_math.hpp

struct DriveOptions {
    uint64_t seed = 1;
    size_t scans = 1000;
    double spacing = 2.0;     // metres along the path between two scans
    double lane_offset = 1.8; // the path keeps this far right of the street's centre line
    double turn_radius = 7.0; // metres, of the arcs that round the corners
    double sway_deg = 0.5;    // amplitude of the vehicle's own roll and pitch, on top of the ground's slope
    CityOptions city;
    // The sensor: beams, azimuth steps, ranges, noise, dropout and its height above the ground (the seed and
    // the demo's pose fields are unused).
    DemoOptions sensor;
};

struct Drive {
    City city;
    std::vector<Pose> poses;      // sensor in world (p_world = R p_sensor + t), one per scan
    std::vector<double> distance; // metres along the path from the first scan, one per scan
    std::vector<int> route;       // the crossings passed, in order (index i + (xs.size()) * j)
    size_t legs = 0;              // stretches between crossings driven (the part before the first one counts)
    size_t distinct_legs = 0;     // of which different stretches, whatever the direction
};

// The city and the path (streams 0 and 1 of the seed). Throws std::invalid_argument for options it cannot
// drive (no scans, a spacing not above 0, a city it cannot build).
Drive plan_drive(const DriveOptions &options);

// Scan `index` of the drive: the city within the sensor's range plus that moment's traffic, ray-cast from the
// scan's pose (stream 2 + index of the seed); the points in the sensor frame.
DemoScan simulate_drive_scan(const Drive &drive, size_t index, const DriveOptions &options);

// A loop closure the ground truth knows: scans i < j at least min_gap metres apart along the path whose
// sensors are within `radius` metres of each other.
struct LoopPair {
    size_t i = 0, j = 0;
    double distance = 0.0; // between the sensors, metres
};
// Every such pair, ordered by i then j.
std::vector<LoopPair> true_loops(const Drive &drive, double min_gap, double radius);

} // namespace kissm_sim
