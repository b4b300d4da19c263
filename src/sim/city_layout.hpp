// SPDX-License-Identifier: MIT
// A city for long simulated drives (drive.hpp): a grid of blocks whose streets are furnished like the demo's
// street, a deterministic function of one random stream.
//
// Streets run along x and along y from one edge of the grid to the other. Each has its own asymmetric
// cross-section (kerbs, sidewalks, lights, trees, parking: draw_cross_section) and its own frame (along x,
// centre line y = 0, possibly turned by 180 degrees); every stretch between two crossings is furnished in that
// frame by street_layout's own functions (buildings with details, hedges, walls, lights, trees, parked cars,
// clutter), on flat ground, and then placed into the world, each primitive lifted by the city's ground under
// it. The ground is the demo's (waves, slope, roughness, raised behind the kerbs) with the grid's streets as
// its roads.
//
// A scan needs only what its sensor can reach: a uniform grid over the primitives gives the scene within
// range of a point (scene_near), so a scan costs about what a demo scan costs whatever the size of the city.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "demo_scene.hpp"
#include "pose_math.hpp"
#include "ray_geometry.hpp"
#include "rng.hpp"
#include "street_layout.hpp"

namespace kissm_sim {
using namespace kissm_pose; // src/common/pose_math.hpp

struct CityOptions {
    int blocks_x = 3, blocks_y = 3;             // blocks along x and along y, 1..7 each (Ground::kMaxRoads)
    double min_block = 80.0, max_block = 120.0; // street centre line to centre line, metres
};

// One street of the grid, from the first crossing to the last.
struct CityStreet {
    bool along_x = true; // along x at y = at, or along y at x = at
    double at = 0.0;
    double begin = 0.0, end = 0.0; // world coordinate along the street of its first and last crossing
    // The street's own frame: u along the street, v across it (street_layout's x and y). u = sign * the world
    // coordinate along the street; sign -1 turns the street by 180 degrees, so which side is the narrow one
    // does not follow the grid's axes.
    double sign = 1.0;
    Layout lay; // its cross-section, in its own frame

    // World position of (u, v) in the street's frame, and the rotation from that frame to the world.
    void to_world(double u, double v, double *x, double *y) const;
    double cos_yaw() const { return along_x ? sign : 0.0; }
    double sin_yaw() const { return along_x ? 0.0 : sign; }
};

struct City {
    Scene scene;            // the ground and every static primitive, in the world frame
    std::vector<double> xs; // centre lines of the streets along y (their x), increasing
    std::vector<double> ys; // centre lines of the streets along x (their y), increasing
    // One per ys (along x), then one per xs (along y).
    std::vector<CityStreet> streets;
    DemoSceneStats stats;

    // The uniform grid over the primitives' bounding circles (indices into scene.prims, increasing per cell).
    double cell = 20.0, grid_x0 = 0.0, grid_y0 = 0.0;
    int grid_nx = 0, grid_ny = 0;
    std::vector<std::vector<uint32_t>> cells;

    const CityStreet &street_along_x(size_t j) const { return streets[j]; }
    const CityStreet &street_along_y(size_t i) const { return streets[ys.size() + i]; }
};

// The ground is bounded (Ground::hmin/hmax) for points up to this far beyond the grid's outer streets: rays of
// sensors on the streets with a range up to this reach no farther.
constexpr double kCityGroundMargin = 150.0;

// The city of `seed` (random stream 0 of it).
City build_city(uint64_t seed, const CityOptions &options);

// The static primitives whose bounding circle comes within `range` of (x, y) in the x-y plane, as a scene of
// their own with the city's ground, in the city's order. The ray caster ignores everything farther than its
// maximum range and orders the rest by distance then index, so a scan of scene_near(range >= max range) is
// the same, bit for bit, as a scan of the whole city.
Scene scene_near(const City &city, double x, double y, double range);

// Vehicles in the lanes and pedestrians on the sidewalks of the streets near the sensor, none within 10 m of
// it: the traffic of one scan (they are elsewhere at the next).
void add_city_movers(Scene &s, Rng &rng, const City &city, const Pose &sensor);

} // namespace kissm_sim
