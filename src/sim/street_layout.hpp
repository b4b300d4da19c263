// SPDX-License-Identifier: MIT
// The street of `kissm demo`, a deterministic function of one random stream.
//
// The main street runs along x between two kerbs (an asymmetric cross-section), is closed at one end by a
// row of buildings and crossed by a street along y. Along them: buildings with columns, balconies and
// entrances, walls, hedges, street lights, trees, parked cars and clutter, all as primitives of a Scene
// (ray_geometry.hpp). The ground undulates gently, is rough at small scale and is raised behind the kerbs
// (sidewalks, yards).
//
// The details are there for realism, and they matter: a perfectly smooth, symmetric street scanned by an
// ideal sensor is ambiguous (its ring patterns and mirror symmetry fit several poses), real streets are not.
#pragma once

#include <cmath>
#include <vector>

#include "demo_scene.hpp"
#include "pose_math.hpp"
#include "ray_geometry.hpp"
#include "rng.hpp"

namespace kissm_sim {
using namespace kissm_pose; // src/common/pose_math.hpp

// One side of the main street. Real streets are not symmetric, and neither is this one: each side has its
// own sidewalk width, kerb position and furniture, so that a scan turned by 180 degrees does not fit itself.
struct StreetSide {
    double sign = 1.0;     // -1: y < 0, +1: y > 0
    double kerb = 7.0;     // |y| of the kerb
    double sidewalk = 3.5; // width of the sidewalk behind the kerb
    bool poles = true;     // street lights
    bool trees = true;
    double parking = 0.7; // share of the kerb with parked cars
    std::vector<double> pole_x;
};

struct Layout {
    StreetSide sides[2];   // [0]: y < 0, [1]: y > 0
    double cross_x = 30.0; // centre line of the cross street, along y
    double cross_half_width = 6.0;
    double end_x = -45.0; // the main street ends here (T-junction): a row of buildings closes it

    double road_lo() const { return -sides[0].kerb; }
    double road_hi() const { return sides[1].kerb; }
    // The lanes: clear of the cars parked along the kerbs (sensor poses, stopped vehicles).
    double lane_lo() const { return road_lo() + 2.8; }
    double lane_hi() const { return road_hi() - 2.8; }
    bool in_cross_street(double x, double margin) const { return std::fabs(x - cross_x) < cross_half_width + margin; }
    bool beyond_end(double x) const { return end_x < 0.0 ? x < end_x : x > end_x; }
};

// The ground, the street's cross-section and everything that stands still: buildings, walls, street
// furniture, parked cars. Fills lay and counts into stats.
void build_street(Rng &rng, Scene &s, Layout &lay, DemoSceneStats &stats);

// The pieces build_street is made of, for the city (city_layout.hpp), which furnishes each stretch of its
// streets between two crossings with them, in the street's own frame (along x, centre line y = 0). A layout
// whose cross_x and end_x lie far away has neither a cross street nor an end.
//
// The ground's waves, slope and roughness (no streets yet: set them, curb_height, then bound_ground).
Ground make_ground(Rng &rng);
// The ray marcher's height bounds and gradient bound for points up to `extent` metres from the origin along x
// and along y (uses curb_height).
void bound_ground(Ground &g, double extent);
// Each side's kerb, sidewalk, lights, trees and parking (lay.sides).
void draw_cross_section(Rng &rng, Layout &lay);
// Buildings (wings, facade details, hedges, porches, walls across the gaps) along one side, from x_begin to
// about x_end.
void add_street_buildings(Scene &s, Rng &rng, const Layout &lay, const StreetSide &street, double x_begin, double x_end,
                          DemoSceneStats &stats);
// Street lights, trees and parked cars along both kerbs from x_lo to x_hi (a parked car may end up to a car
// length past x_hi).
void add_kerbside_furniture(Scene &s, Rng &rng, Layout &lay, double x_lo, double x_hi, DemoSceneStats &stats);
// `count` tries at a bin, bollard, cabinet, bush or sign post on either sidewalk between x_lo and x_hi.
void add_sidewalk_clutter(Scene &s, Rng &rng, const Layout &lay, double x_lo, double x_hi, int count,
                          DemoSceneStats &stats);
// A car at (cx, cy) heading along yaw: a body and a cabin, or a van.
void add_car(Scene &s, Rng &rng, double cx, double cy, double yaw, double length);
// Lorries and vans stopped in the street (in both scans), clear of the sensor poses a and b.
void add_stopped_vehicles(Scene &s, Rng &rng, const Layout &lay, const Pose &a, const Pose &b, DemoSceneStats &stats);
// Vehicles and pedestrians seen in one scan only (they moved between the two scans).
void add_movers(Scene &s, Rng &rng, const Layout &lay, const Pose &a, const Pose &b, DemoSceneStats &stats);

} // namespace kissm_sim
