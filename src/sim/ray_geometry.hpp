// SPDX-License-Identifier: MIT
// What the simulated LiDAR's rays can hit, and where they hit it. Solids are analytic: yawed boxes, vertical
// cylinders and vertical ellipsoids (which rays may penetrate like foliage); the ground is a height field.
// A Scene holds them all, each with a bounding circle in the x-y plane for the ray caster's culling
// (lidar_sim.cpp). World frame: z up.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "pose_math.hpp"
#include "rng.hpp"

namespace kissm_sim {
using namespace kissm_pose; // src/common/pose_math.hpp

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Ray {
    double o[3];
    double d[3]; // unit length
};

// A sine-like wave of period 1 built from two parabolas (C1, |value| <= 1, |slope| <= 8): the ray marcher
// evaluates the ground millions of times, and this is several times cheaper than std::sin.
inline double wave(double cycles) {
    const double f = cycles - std::floor(cycles);
    return f < 0.5 ? 16.0 * f * (0.5 - f) : -16.0 * (f - 0.5) * (1.0 - f);
}
constexpr double kWaveSlope = 8.0 / (2.0 * kPi); // |d wave(k x / 2 pi) / dx| <= kWaveSlope * k

// h(x, y) = a1 w(k1x x + p1) w(k1y y + q1 + 1/4) + a2 w(k2x x + k2y y + p2) + gx x + gy y + roughness + kerbs,
// w(a) ~ sin(a): everything off the two streets (sidewalks, yards) is raised by curb_height behind a kerb.
struct Ground {
    double a1 = 0, k1x = 0, k1y = 0, p1 = 0, q1 = 0;
    double a2 = 0, k2x = 0, k2y = 0, p2 = 0;
    double gx = 0, gy = 0;
    double curb_height = 0.0, road_lo = -7.0, road_hi = 7.0, cross_x = 30.0, cross_half_width = 6.0;
    // Small-scale roughness (worn asphalt, grass): a few short waves in assorted directions, stronger off the road.
    static constexpr int kRoughWaves = 4;
    double rough_kx[kRoughWaves] = {}, rough_ky[kRoughWaves] = {}, rough_phase[kRoughWaves] = {};
    double rough_road = 0.0, rough_off_road = 0.0; // amplitude of each wave
    double hmin = 0, hmax = 0;                     // bounds of h within the scene's extent
    double max_gradient = 0; // bound of |grad h| away from the kerbs (which add at most curb_height)
    // A city's streets (city_layout.hpp): when there are any, these rectangles of road replace the demo's
    // main street and cross street as what lies below the kerbs; the demo leaves them empty.
    static constexpr int kMaxRoads = 16;
    int roads = 0;
    double road_x0[kMaxRoads] = {}, road_x1[kMaxRoads] = {}, road_y0[kMaxRoads] = {}, road_y1[kMaxRoads] = {};

    static constexpr double kKerbWidth = 0.08; // horizontal extent of the kerb's slope

    static double kerb(double d) { return d <= 0.0 ? 0.0 : (d >= kKerbWidth ? 1.0 : d / kKerbWidth); }

    // How far (x, y) lies outside the nearest of the city's road rectangles (<= 0 on a road). The kerb is
    // monotone, so the kerb of the least distance is the least kerb, as the demo's min of two kerbs.
    double outside_roads(double x, double y) const {
        double d = kInf;
        for (int i = 0; i < roads; ++i) {
            d = std::min(d,
                         std::max(std::max(road_x0[i] - x, x - road_x1[i]), std::max(road_y0[i] - y, y - road_y1[i])));
        }
        return d;
    }

    double height(double x, double y) const {
        constexpr double c = 1.0 / (2.0 * kPi); // radians to cycles
        const double base = a1 * wave(c * (k1x * x + p1)) * wave(c * (k1y * y + q1) + 0.25) +
                            a2 * wave(c * (k2x * x + k2y * y + p2)) + gx * x + gy * y;
        const double off_road = roads == 0 ? std::min(kerb(std::max(road_lo - y, y - road_hi)),
                                                      kerb(std::fabs(x - cross_x) - cross_half_width))
                                           : kerb(outside_roads(x, y));
        double rough = 0.0;
        for (int i = 0; i < kRoughWaves; ++i) rough += wave(c * (rough_kx[i] * x + rough_ky[i] * y + rough_phase[i]));
        return base + curb_height * off_road + (rough_road + (rough_off_road - rough_road) * off_road) * rough;
    }
};

struct Box {
    double c[3];   // centre
    double h[3];   // half sizes along the box's own axes
    double cs, sn; // cos and sin of the yaw
};

struct Cylinder { // vertical
    double cx, cy, z0, z1, r;
};

struct Ellipsoid { // vertical axis of revolution
    double c[3];
    double rxy, rz;
    double free_path; // > 0: foliage, a ray stops after an exponential depth of this mean or passes through
};

enum class Kind : uint8_t { Box, Cylinder, Ellipsoid };

struct PrimRef {
    Kind kind;
    uint32_t index;
    double cx, cy, radius; // bounding circle in the x-y plane
};

struct Scene {
    Ground ground;
    std::vector<Box> boxes;
    std::vector<Cylinder> cylinders;
    std::vector<Ellipsoid> ellipsoids;
    std::vector<PrimRef> prims;

    void add_box(double cx, double cy, double z0, double z1, double lx, double ly, double yaw) {
        Box b{};
        b.c[0] = cx;
        b.c[1] = cy;
        b.c[2] = 0.5 * (z0 + z1);
        b.h[0] = 0.5 * lx;
        b.h[1] = 0.5 * ly;
        b.h[2] = 0.5 * (z1 - z0);
        b.cs = std::cos(yaw);
        b.sn = std::sin(yaw);
        prims.push_back({Kind::Box, static_cast<uint32_t>(boxes.size()), cx, cy, 0.5 * std::hypot(lx, ly)});
        boxes.push_back(b);
    }
    void add_cylinder(double cx, double cy, double z0, double z1, double r) {
        prims.push_back({Kind::Cylinder, static_cast<uint32_t>(cylinders.size()), cx, cy, r});
        cylinders.push_back({cx, cy, z0, z1, r});
    }
    void add_ellipsoid(double cx, double cy, double cz, double rxy, double rz, double free_path) {
        prims.push_back({Kind::Ellipsoid, static_cast<uint32_t>(ellipsoids.size()), cx, cy, rxy});
        ellipsoids.push_back({{cx, cy, cz}, rxy, rz, free_path});
    }
};

// Distance along the ray to the first hit in front of its origin, or +inf. Foliage (an ellipsoid with a
// free path) draws its penetration depth from rng.
double hit_prim(const Scene &s, const PrimRef &p, const Ray &r, Rng &rng);
// The same for the ground, up to max_t.
double hit_ground(const Ground &g, const Ray &r, double max_t);

} // namespace kissm_sim
