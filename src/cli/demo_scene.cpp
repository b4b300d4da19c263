// SPDX-License-Identifier: MIT
// The demo scene and LiDAR simulator (see demo_scene.hpp).
//
// World frame: z up. The main street runs along x between two kerbs (an asymmetric cross-section), is closed
// at one end by a row of buildings and crossed by a street along y. Solids are analytic: yawed boxes
// (buildings and their columns, balconies and entrances, walls, hedges, vehicles, clutter), vertical
// cylinders (poles, trunks, bins, pedestrians) and vertical ellipsoids (tree crowns and bushes, which rays
// may penetrate like foliage). The ground is a height field: gentle undulation, small-scale roughness and
// raised sidewalks behind kerbs. Each ray keeps its nearest hit, so everything behind a wall, a car or a
// tree is hidden exactly as for a real sensor.
//
// The details are there for realism, and they matter: a perfectly smooth, symmetric street scanned by an
// ideal sensor is ambiguous (its ring patterns and mirror symmetry fit several poses), real streets are not.
#include "demo_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "rng.hpp"

namespace kissm_cli {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kSceneExtent = 200.0; // metres from the world origin that the ground bounds cover

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
    double hmin = 0, hmax = 0;                     // bounds of h within kSceneExtent
    double max_gradient = 0; // bound of |grad h| away from the kerbs (which add at most curb_height)

    static constexpr double kKerbWidth = 0.08; // horizontal extent of the kerb's slope

    static double kerb(double d) { return d <= 0.0 ? 0.0 : (d >= kKerbWidth ? 1.0 : d / kKerbWidth); }

    double height(double x, double y) const {
        constexpr double c = 1.0 / (2.0 * kPi); // radians to cycles
        const double base = a1 * wave(c * (k1x * x + p1)) * wave(c * (k1y * y + q1) + 0.25) +
                            a2 * wave(c * (k2x * x + k2y * y + p2)) + gx * x + gy * y;
        const double off_road =
            std::min(kerb(std::max(road_lo - y, y - road_hi)), kerb(std::fabs(x - cross_x) - cross_half_width));
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

// ---------------------------------------------------------------------------------------------------
// Ray intersections: each returns the distance along the ray to the first hit in front of the origin,
// or +inf.
// ---------------------------------------------------------------------------------------------------

double hit_box(const Box &b, const Ray &r) {
    const double ox = r.o[0] - b.c[0], oy = r.o[1] - b.c[1];
    const double o[3] = {b.cs * ox + b.sn * oy, -b.sn * ox + b.cs * oy, r.o[2] - b.c[2]};
    const double d[3] = {b.cs * r.d[0] + b.sn * r.d[1], -b.sn * r.d[0] + b.cs * r.d[1], r.d[2]};
    double tmin = -kInf, tmax = kInf;
    for (int k = 0; k < 3; ++k) {
        if (std::fabs(d[k]) < 1e-12) {
            if (std::fabs(o[k]) > b.h[k]) return kInf;
            continue;
        }
        double t1 = (-b.h[k] - o[k]) / d[k];
        double t2 = (b.h[k] - o[k]) / d[k];
        if (t1 > t2) std::swap(t1, t2);
        tmin = std::max(tmin, t1);
        tmax = std::min(tmax, t2);
        if (tmin > tmax) return kInf;
    }
    return tmin > 0.0 ? tmin : kInf; // an origin inside a box sees nothing of it
}

double hit_cylinder(const Cylinder &c, const Ray &r) {
    const double ox = r.o[0] - c.cx, oy = r.o[1] - c.cy;
    double best = kInf;
    const double a = r.d[0] * r.d[0] + r.d[1] * r.d[1];
    if (a > 1e-12) {
        const double b = 2.0 * (ox * r.d[0] + oy * r.d[1]);
        const double cc = ox * ox + oy * oy - c.r * c.r;
        const double disc = b * b - 4.0 * a * cc;
        if (disc >= 0.0) {
            const double t = (-b - std::sqrt(disc)) / (2.0 * a);
            if (t > 0.0) {
                const double z = r.o[2] + t * r.d[2];
                if (z >= c.z0 && z <= c.z1) best = t;
            }
        }
    }
    if (r.d[2] < 0.0) { // the top cap, seen from above
        const double t = (c.z1 - r.o[2]) / r.d[2];
        if (t > 0.0 && t < best) {
            const double x = ox + t * r.d[0], y = oy + t * r.d[1];
            if (x * x + y * y <= c.r * c.r) best = t;
        }
    }
    return best;
}

double hit_ellipsoid(const Ellipsoid &e, const Ray &r, Rng &rng) {
    // Scale z so that the ellipsoid becomes a sphere of radius rxy; t keeps its meaning along the ray.
    const double s = e.rxy / e.rz;
    const double o[3] = {r.o[0] - e.c[0], r.o[1] - e.c[1], (r.o[2] - e.c[2]) * s};
    const double d[3] = {r.d[0], r.d[1], r.d[2] * s};
    const double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const double b = 2.0 * (o[0] * d[0] + o[1] * d[1] + o[2] * d[2]);
    const double c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - e.rxy * e.rxy;
    const double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) return kInf;
    const double sq = std::sqrt(disc);
    const double t0 = (-b - sq) / (2.0 * a);
    const double t1 = (-b + sq) / (2.0 * a);
    if (t1 <= 0.0) return kInf;
    const double enter = std::max(t0, 0.0);
    if (e.free_path <= 0.0) return enter > 0.0 ? enter : kInf;
    const double t = enter + rng.exponential(e.free_path);
    return t <= t1 ? t : kInf; // a ray may pass through sparse foliage
}

// First crossing of the ray with the height field, up to max_t: safe steps until the sign changes, then the
// Illinois variant of regula falsi. Away from the kerbs |f'| <= |dz| + max_gradient; a kerb can raise the
// ground by at most curb_height (plus the roughness it scales) within a step, so a step of
// (f - jump) / lipschitz cannot pass through the surface.
double hit_ground(const Ground &g, const Ray &r, double max_t) {
    const double dz = r.d[2];
    if (dz >= -1e-9) return kInf; // the sensor is well above the ground's whole height range
    const double t_lo = std::max(0.0, (r.o[2] - g.hmax) / -dz);
    const double t_hi = std::min(max_t, (r.o[2] - g.hmin) / -dz);
    if (t_lo > t_hi) return kInf;
    const auto f = [&](double t) { return r.o[2] + t * dz - g.height(r.o[0] + t * r.d[0], r.o[1] + t * r.d[1]); };
    const double lipschitz = -dz + g.max_gradient;
    const double jump = g.curb_height + Ground::kRoughWaves * std::fabs(g.rough_off_road - g.rough_road);
    double ta = t_lo, fa = f(ta);
    if (fa <= 0.0) return ta > 0.0 ? ta : kInf;
    while (ta < t_hi) {
        const double tb = std::min(t_hi, ta + std::max((fa - jump) / lipschitz, 0.1));
        const double fb = f(tb);
        if (fb <= 0.0) {
            double lo = ta, flo = fa, hi = tb, fhi = fb;
            int side = 0;
            for (int iter = 0; iter < 30; ++iter) {
                const double t = (lo * fhi - hi * flo) / (fhi - flo);
                const double ft = f(t);
                if (std::fabs(ft) < 1e-7) return t;
                if (ft > 0.0) {
                    lo = t;
                    flo = ft;
                    if (side == 1) fhi *= 0.5;
                    side = 1;
                } else {
                    hi = t;
                    fhi = ft;
                    if (side == -1) flo *= 0.5;
                    side = -1;
                }
            }
            return 0.5 * (lo + hi);
        }
        ta = tb;
        fa = fb;
    }
    return kInf;
}

double hit_prim(const Scene &s, const PrimRef &p, const Ray &r, Rng &rng) {
    switch (p.kind) {
    case Kind::Box: return hit_box(s.boxes[p.index], r);
    case Kind::Cylinder: return hit_cylinder(s.cylinders[p.index], r);
    case Kind::Ellipsoid: return hit_ellipsoid(s.ellipsoids[p.index], r, rng);
    }
    return kInf;
}

// ---------------------------------------------------------------------------------------------------
// Scene layout
// ---------------------------------------------------------------------------------------------------

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
    bool in_cross_street(double x, double margin) const { return std::fabs(x - cross_x) < cross_half_width + margin; }
    bool beyond_end(double x) const { return end_x < 0.0 ? x < end_x : x > end_x; }
};

Ground make_ground(Rng &rng) {
    Ground g;
    g.a1 = rng.uniform(0.08, 0.15);
    g.k1x = 2.0 * kPi / rng.uniform(30.0, 50.0);
    g.k1y = 2.0 * kPi / rng.uniform(25.0, 45.0);
    g.p1 = rng.uniform(0.0, 2.0 * kPi);
    g.q1 = rng.uniform(0.0, 2.0 * kPi);
    g.a2 = rng.uniform(0.03, 0.07);
    const double k2 = 2.0 * kPi / rng.uniform(12.0, 20.0), dir = rng.uniform(0.0, kPi);
    g.k2x = k2 * std::cos(dir);
    g.k2y = k2 * std::sin(dir);
    g.p2 = rng.uniform(0.0, 2.0 * kPi);
    g.gx = rng.uniform(-0.002, 0.002);
    g.gy = rng.uniform(-0.002, 0.002);
    for (int i = 0; i < Ground::kRoughWaves; ++i) {
        const double k = 2.0 * kPi / rng.uniform(0.8, 3.0), a = rng.uniform(0.0, kPi);
        g.rough_kx[i] = k * std::cos(a);
        g.rough_ky[i] = k * std::sin(a);
        g.rough_phase[i] = rng.uniform(0.0, 2.0 * kPi);
    }
    g.rough_road = rng.uniform(0.008, 0.012);
    g.rough_off_road = rng.uniform(0.015, 0.025);
    return g;
}

// Fixes the streets (for the kerbs) and the bounds used by the ray marcher.
void finish_ground(Ground &g, const Layout &lay, double curb_height) {
    g.road_lo = lay.road_lo();
    g.road_hi = lay.road_hi();
    const double cross_x = lay.cross_x, cross_half_width = lay.cross_half_width;
    g.cross_x = cross_x;
    g.cross_half_width = cross_half_width;
    g.curb_height = curb_height;
    const double slope = std::fabs(g.gx) + std::fabs(g.gy);
    const double rough = Ground::kRoughWaves * std::max(g.rough_road, g.rough_off_road);
    double rough_gradient = 0.0;
    for (int i = 0; i < Ground::kRoughWaves; ++i) rough_gradient += std::hypot(g.rough_kx[i], g.rough_ky[i]);
    g.hmin = -(g.a1 + g.a2 + slope * kSceneExtent + rough);
    g.hmax = g.a1 + g.a2 + slope * kSceneExtent + curb_height + rough;
    // The kerb ramps also scale the roughness amplitude; both effects are bounded by the step allowance
    // (curb_height + rough) that hit_ground subtracts before each step.
    g.max_gradient = kWaveSlope * (g.a1 * std::hypot(g.k1x, g.k1y) + g.a2 * std::hypot(g.k2x, g.k2y) +
                                   std::max(g.rough_road, g.rough_off_road) * rough_gradient) +
                     std::hypot(g.gx, g.gy);
}

// A car at (cx, cy) heading along yaw: a body and a cabin, or a van.
void add_car(Scene &s, Rng &rng, double cx, double cy, double yaw, double length) {
    const double ground = s.ground.height(cx, cy);
    const double width = rng.uniform(1.7, 1.9);
    if (rng.chance(0.15)) { // van
        s.add_box(cx, cy, ground + 0.3, ground + rng.uniform(1.9, 2.3), length, width, yaw);
        return;
    }
    const double body_top = ground + rng.uniform(0.95, 1.05);
    s.add_box(cx, cy, ground + 0.3, body_top, length, width, yaw);
    const double cabin = length * rng.uniform(0.45, 0.6);
    const double shift = length * rng.uniform(-0.12, 0.05);
    s.add_box(cx + shift * std::cos(yaw), cy + shift * std::sin(yaw), body_top - 0.05, ground + rng.uniform(1.4, 1.6),
              cabin, width - 0.15, yaw);
}

void add_tree(Scene &s, Rng &rng, double x, double y) {
    const double ground = s.ground.height(x, y);
    const double trunk = rng.uniform(2.0, 3.5);
    const double rz = rng.uniform(1.6, 3.0);
    s.add_cylinder(x, y, ground - 0.2, ground + trunk + 0.5 * rz, rng.uniform(0.15, 0.25));
    s.add_ellipsoid(x, y, ground + trunk + 0.75 * rz, rng.uniform(1.5, 2.8), rz, rng.uniform(0.1, 0.25));
}

void add_clutter(Scene &s, Rng &rng, double x, double y) {
    const double g = s.ground.height(x, y);
    switch (rng.uniform_int(0, 4)) {
    case 0: // waste bin
        s.add_cylinder(x, y, g - 0.1, g + rng.uniform(0.9, 1.2), rng.uniform(0.25, 0.35));
        break;
    case 1: // bollard
        s.add_cylinder(x, y, g - 0.1, g + 0.9, 0.08);
        break;
    case 2: // cabinet, bench, crate
        s.add_box(x, y, g - 0.1, g + rng.uniform(0.5, 1.4), rng.uniform(0.4, 1.6), rng.uniform(0.3, 0.8),
                  rng.uniform(0.0, kPi));
        break;
    case 3: { // bush
        const double rz = rng.uniform(0.4, 0.9);
        s.add_ellipsoid(x, y, g + 0.6 * rz, rng.uniform(0.5, 1.2), rz, 0.15);
        break;
    }
    default: { // sign post
        const double top = g + rng.uniform(2.2, 2.8);
        s.add_cylinder(x, y, g - 0.1, top, 0.04);
        s.add_box(x, y, top - 0.6, top, 0.6, 0.05, rng.uniform(0.0, kPi));
        break;
    }
    }
}

// Columns, balconies and an entrance on one face of a building box (centre cx, cy; ground g; size lx by ly
// in its own frame; yaw). The face is the one whose outward normal in the box frame is (nx, ny), a unit axis.
int add_facade_details(Scene &s, Rng &rng, double cx, double cy, double g, double lx, double ly, double height,
                       double yaw, double nx, double ny) {
    const double cs = std::cos(yaw), sn = std::sin(yaw);
    const double length = nx != 0.0 ? ly : lx; // along the face
    const double half_depth = nx != 0.0 ? 0.5 * lx : 0.5 * ly;
    int added = 0;
    // A box of width w along the face, sticking out by d, from z0 to z1, centred at u along the face.
    const auto place = [&](double u, double w, double d, double z0, double z1) {
        const double out = half_depth + 0.5 * d - 0.05;
        const double bx = nx * out - ny * u, by = ny * out + nx * u;
        s.add_box(cx + cs * bx - sn * by, cy + sn * bx + cs * by, z0, z1, nx != 0.0 ? d : w, nx != 0.0 ? w : d, yaw);
        ++added;
    };
    if (rng.chance(0.5)) { // columns or pilasters
        const double spacing = rng.uniform(3.0, 6.0), w = rng.uniform(0.3, 0.6), d = rng.uniform(0.15, 0.4);
        const double top = rng.chance(0.5) ? g + height : g + rng.uniform(3.0, 4.5);
        for (double u = -0.5 * length + rng.uniform(0.3, spacing); u < 0.5 * length - 0.3; u += spacing) {
            place(u, w, d, g - 0.5, top);
        }
    }
    if (height > 6.0 && rng.chance(0.6)) { // balconies
        const int floors = static_cast<int>((height - 3.0) / 3.0);
        const double bay = rng.uniform(3.0, 6.0);
        for (int f = 1; f <= floors; ++f) {
            const double z = g + 3.0 * f + 0.2;
            for (double u = -0.5 * length + 0.5 * bay; u < 0.5 * length - 0.5 * bay; u += bay) {
                if (rng.chance(0.4))
                    place(u, rng.uniform(1.5, std::min(3.0, bay - 0.5)), rng.uniform(0.8, 1.4), z,
                          z + rng.uniform(0.9, 1.1));
            }
        }
    }
    if (length > 4.0 && rng.chance(0.6)) { // entrance steps and a canopy
        const double u = rng.uniform(-0.5 * length + 1.5, 0.5 * length - 1.5), w = rng.uniform(1.5, 3.0);
        place(u, w, rng.uniform(0.8, 1.5), g - 0.5, g + rng.uniform(0.2, 0.6));
        if (rng.chance(0.5))
            place(u, w + 0.4, rng.uniform(1.0, 1.6), g + rng.uniform(2.6, 3.2), g + rng.uniform(3.3, 3.5));
    }
    return added;
}

// Buildings along one side of the main street.
void add_street_buildings(Scene &s, Rng &rng, const Layout &lay, const StreetSide &street, DemoSceneStats &stats) {
    const double side = street.sign;
    const double sidewalk_edge = street.kerb + street.sidewalk;
    const double x_begin = lay.end_x < 0.0 ? lay.end_x : -95.0, x_end = lay.end_x < 0.0 ? 95.0 : lay.end_x;
    double x = x_begin + rng.uniform(0.0, 3.0);
    while (x < x_end) {
        const double width = std::min(rng.uniform(8.0, 24.0), std::max(x_end - x, 4.0));
        if (x + width > lay.cross_x - lay.cross_half_width - 3.0 && x < lay.cross_x + lay.cross_half_width + 3.0) {
            x = lay.cross_x + lay.cross_half_width + 3.0 + rng.uniform(0.0, 3.0);
            continue;
        }
        const double setback = rng.uniform(0.0, 4.5);
        const double depth = rng.uniform(8.0, 18.0);
        const double height = rng.chance(0.15) ? rng.uniform(18.0, 30.0) : rng.uniform(4.0, 16.0);
        const double yaw = rng.chance(0.2) ? rng.uniform(-0.5, 0.5) : rng.uniform(-0.05, 0.05);
        const double front = sidewalk_edge + setback;
        const double cx = x + 0.5 * width, cy = side * (front + 0.5 * depth);
        const double g = s.ground.height(cx, cy);
        // One block, or two or three attached wings whose fronts and heights differ.
        const int wings = std::abs(yaw) < 0.1 ? rng.uniform_int(1, 3) : 1;
        double wx0 = x;
        for (int wing = 0; wing < wings; ++wing) {
            const double ww = wing == wings - 1 ? x + width - wx0 : width * rng.uniform(0.2, 0.4); // last >= 20%
            const double shift = wing == 0 ? 0.0 : std::max(rng.uniform(-1.5, 2.5), -setback);
            const double wd = std::max(4.0, depth - std::max(shift, 0.0));
            const double wh = wing == 0 ? height : std::max(3.0, height * rng.uniform(0.6, 1.3));
            const double wcx = wx0 + 0.5 * ww, wcy = side * (front + std::max(shift, 0.0) + 0.5 * wd);
            const double wfront = front + shift;
            const double wcy2 = shift < 0.0 ? side * (wfront + 0.5 * (wd - shift)) : wcy;
            const double wd2 = shift < 0.0 ? wd - shift : wd;
            s.add_box(wcx, wcy2, g - 1.0, g + wh, ww, wd2, yaw);
            ++stats.buildings;
            stats.details += add_facade_details(s, rng, wcx, wcy2, g, ww, wd2, wh, yaw, 0.0, -side);
            wx0 += ww;
        }
        if (setback > 2.0 && rng.chance(0.3)) { // a hedge in the front yard
            const double hx = x + 0.5 * width + rng.uniform(-0.2, 0.2) * width,
                         hy = side * (sidewalk_edge + 0.5 * setback);
            const double hg = s.ground.height(hx, hy);
            s.add_box(hx, hy, hg - 0.3, hg + rng.uniform(0.8, 1.6), width * rng.uniform(0.4, 0.9),
                      rng.uniform(0.6, 1.0), yaw);
            ++stats.walls;
        }
        if (setback > 2.5 && rng.chance(0.4)) { // a low shop front or porch in front of the facade
            const double d2 = rng.uniform(1.5, setback - 0.5);
            const double w2 = rng.uniform(3.0, 0.7 * width);
            const double x2 = x + rng.uniform(0.0, width - w2) + 0.5 * w2;
            s.add_box(x2, side * (front - 0.5 * d2 + 0.2), g - 1.0, g + rng.uniform(2.8, 4.5), w2, d2 + 0.4, yaw);
            ++stats.buildings;
        }
        const double gap = rng.chance(0.3) ? rng.uniform(0.0, 0.5) : rng.uniform(2.0, 10.0);
        if (gap > 2.0 && rng.chance(0.4)) { // a wall or fence across the gap
            const double wx = x + width + 0.5 * gap, wy = side * (front + rng.uniform(0.0, 2.0));
            const double wg = s.ground.height(wx, wy);
            s.add_box(wx, wy, wg - 0.5, wg + rng.uniform(1.0, 2.0), gap, 0.3, 0.0);
            ++stats.walls;
        }
        x += width + gap;
    }
}

// Buildings along both sides of the cross street, beyond the corner blocks.
void add_cross_street_buildings(Scene &s, Rng &rng, const Layout &lay, DemoSceneStats &stats) {
    for (double sy : {-1.0, 1.0}) {
        for (double sx : {-1.0, 1.0}) {
            double y = 36.0 + rng.uniform(0.0, 4.0);
            while (y < 95.0) {
                const double length = rng.uniform(8.0, 20.0);
                const double depth = rng.uniform(8.0, 16.0);
                const double height = rng.chance(0.15) ? rng.uniform(18.0, 30.0) : rng.uniform(4.0, 16.0);
                const double setback = rng.uniform(0.5, 4.0);
                const double cx = lay.cross_x + sx * (lay.cross_half_width + 3.0 + setback + 0.5 * depth);
                const double cy = sy * (y + 0.5 * length);
                const double g = s.ground.height(cx, cy);
                const double yaw = rng.uniform(-0.05, 0.05);
                s.add_box(cx, cy, g - 1.0, g + height, depth, length, yaw);
                ++stats.buildings;
                stats.details += add_facade_details(s, rng, cx, cy, g, depth, length, height, yaw, -sx, 0.0);
                y += length + (rng.chance(0.3) ? rng.uniform(0.0, 0.5) : rng.uniform(2.0, 8.0));
            }
        }
    }
}

// The buildings across the end of the main street, their fronts facing down the street.
void add_end_buildings(Scene &s, Rng &rng, const Layout &lay, DemoSceneStats &stats) {
    const double sx = lay.end_x < 0.0 ? -1.0 : 1.0; // away from the street
    double y = -35.0 + rng.uniform(0.0, 3.0);
    while (y < 35.0) {
        const double length = rng.uniform(8.0, 20.0);
        const double depth = rng.uniform(8.0, 16.0);
        const double height = rng.chance(0.2) ? rng.uniform(16.0, 28.0) : rng.uniform(5.0, 15.0);
        const double cx = lay.end_x + sx * (rng.uniform(2.0, 5.0) + 0.5 * depth);
        const double cy = y + 0.5 * length;
        const double g = s.ground.height(cx, cy);
        const double yaw = rng.uniform(-0.05, 0.05);
        s.add_box(cx, cy, g - 1.0, g + height, depth, length, yaw);
        ++stats.buildings;
        stats.details += add_facade_details(s, rng, cx, cy, g, depth, length, height, yaw, -sx, 0.0);
        y += length + (rng.chance(0.5) ? rng.uniform(0.0, 0.5) : rng.uniform(1.5, 5.0));
    }
}

// Lorries and vans stopped in the street (in both scans), clear of the two sensor poses.
void add_stopped_vehicles(Scene &s, Rng &rng, const Layout &lay, const Pose &a, const Pose &b, DemoSceneStats &stats) {
    const int count = rng.uniform_int(1, 3);
    for (int i = 0; i < count; ++i) {
        for (int attempt = 0; attempt < 20; ++attempt) {
            const double x = rng.uniform(-40.0, 40.0);
            if (std::fabs(x - a.t[0]) < 9.0 || std::fabs(x - b.t[0]) < 9.0 || lay.beyond_end(x) ||
                lay.in_cross_street(x, 3.0)) {
                continue;
            }
            const double y = rng.uniform(lay.road_lo() + 2.8, lay.road_hi() - 2.8);
            const double yaw = rng.uniform(-0.05, 0.05) + (rng.chance(0.5) ? kPi : 0.0);
            const double g = s.ground.height(x, y);
            const double length = rng.uniform(6.0, 9.0), width = rng.uniform(2.3, 2.5);
            s.add_box(x, y, g + 0.4, g + rng.uniform(2.8, 3.6), length, width, yaw); // box body
            const double cab = 0.5 * length + 1.1;
            s.add_box(x + cab * std::cos(yaw), y + cab * std::sin(yaw), g + 0.4, g + rng.uniform(2.4, 2.8), 2.0, width,
                      yaw);
            ++stats.cars;
            break;
        }
    }
}

void add_street_furniture(Scene &s, Rng &rng, Layout &lay, DemoSceneStats &stats) {
    for (StreetSide &street : lay.sides) {
        const double side = street.sign;
        // Street lights at the kerb with an arm over the road.
        if (street.poles) {
            for (double x = -90.0 + rng.uniform(0.0, 20.0); x < 90.0; x += rng.uniform(16.0, 32.0)) {
                if (lay.in_cross_street(x, 1.0) || lay.beyond_end(x)) continue;
                const double y = side * (street.kerb + 0.6);
                const double g = s.ground.height(x, y);
                const double top = g + rng.uniform(6.0, 8.5);
                s.add_cylinder(x, y, g - 0.2, top, rng.uniform(0.10, 0.14));
                const double arm = rng.uniform(1.2, 2.0);
                s.add_box(x, y - side * 0.5 * arm, top - 0.25, top - 0.1, 0.15, arm, 0.0);
                street.pole_x.push_back(x);
                ++stats.poles;
            }
        }
        // Trees on the sidewalk, away from the poles.
        if (street.trees) {
            const double offset = std::min(2.2, 0.6 * street.sidewalk);
            for (double x = -90.0 + rng.uniform(0.0, 10.0); x < 90.0; x += rng.uniform(6.0, 14.0)) {
                if (!rng.chance(0.7) || lay.in_cross_street(x, 2.0) || lay.beyond_end(x)) continue;
                bool near_pole = false;
                for (double px : street.pole_x) near_pole = near_pole || std::fabs(px - x) < 2.5;
                if (near_pole) continue;
                add_tree(s, rng, x, side * (street.kerb + offset));
                ++stats.trees;
            }
        }
        // Parked cars along the kerb.
        double x = -90.0 + rng.uniform(0.0, 5.0);
        while (x < 90.0) {
            const double length = rng.uniform(3.9, 4.9);
            if (rng.chance(street.parking) && !lay.in_cross_street(x + 0.5 * length, 2.5) && !lay.beyond_end(x - 3.0) &&
                !lay.beyond_end(x + length + 3.0)) {
                add_car(s, rng, x + 0.5 * length, side * (street.kerb - 1.15), rng.uniform(-0.04, 0.04), length);
                ++stats.cars;
                x += length + rng.uniform(0.6, 5.0);
            } else {
                x += rng.uniform(2.0, 8.0);
            }
        }
    }
    // Clutter on the main street's sidewalks and along the cross street.
    for (int i = 0; i < 90; ++i) {
        const StreetSide &street = lay.sides[rng.uniform_int(0, 1)];
        const double x = rng.uniform(-75.0, 75.0);
        const double y = street.sign * (street.kerb + rng.uniform(0.3, street.sidewalk - 0.2));
        if (lay.in_cross_street(x, 0.0) || lay.beyond_end(x - 2.0)) continue;
        add_clutter(s, rng, x, y);
        ++stats.clutter;
    }
    for (int i = 0; i < 25; ++i) {
        const double x = lay.cross_x + rng.sign() * rng.uniform(lay.cross_half_width + 0.3, lay.cross_half_width + 3.0);
        const double y = rng.sign() * rng.uniform(12.0, 70.0);
        add_clutter(s, rng, x, y);
        ++stats.clutter;
    }
}

// Vehicles and pedestrians seen in one scan only (they moved between the two scans).
void add_movers(Scene &s, Rng &rng, const Layout &lay, const Pose &a, const Pose &b, DemoSceneStats &stats) {
    const int vehicles = rng.uniform_int(1, 3);
    for (int i = 0; i < vehicles; ++i) {
        for (int attempt = 0; attempt < 20; ++attempt) {
            const double x = rng.uniform(-45.0, 45.0);
            if (std::fabs(x - a.t[0]) < 7.0 || std::fabs(x - b.t[0]) < 7.0) continue;
            const double y = rng.uniform(lay.road_lo() + 2.6, lay.road_hi() - 2.6);
            add_car(s, rng, x, y, rng.uniform(-0.05, 0.05), rng.uniform(4.0, 4.8));
            ++stats.movers;
            break;
        }
    }
    const int walkers = rng.uniform_int(2, 4);
    for (int i = 0; i < walkers; ++i) {
        const StreetSide &street = lay.sides[rng.uniform_int(0, 1)];
        const double x = rng.uniform(-40.0, 40.0);
        const double y = street.sign * (street.kerb + rng.uniform(0.5, street.sidewalk - 0.3));
        const double g = s.ground.height(x, y);
        s.add_cylinder(x, y, g - 0.1, g + rng.uniform(1.55, 1.9), rng.uniform(0.2, 0.28));
        ++stats.movers;
    }
}

// ---------------------------------------------------------------------------------------------------
// The sensor
// ---------------------------------------------------------------------------------------------------

DemoScan cast_scan(const Scene &scene, const Pose &sensor, const DemoOptions &opt, Rng &rng) {
    DemoScan scan;
    scan.sensor_in_world = sensor;

    // Candidate primitives per azimuth sector (world frame, seen from the sensor position), nearest first:
    // a primitive whose bounding circle starts farther away than the best hit so far cannot be hit first.
    constexpr int kSectors = 720;
    constexpr double kSectorWidth = 2.0 * kPi / kSectors;
    struct Candidate {
        double near; // horizontal distance from the sensor to the bounding circle
        uint32_t index;
    };
    std::vector<std::vector<Candidate>> sectors(kSectors);
    const double sx = sensor.t[0], sy = sensor.t[1];
    for (size_t i = 0; i < scene.prims.size(); ++i) {
        const PrimRef &p = scene.prims[i];
        const double dist = std::hypot(p.cx - sx, p.cy - sy);
        if (dist - p.radius > opt.max_range) continue;
        int first = 0, last = kSectors - 1;
        if (dist > p.radius + 1e-6) {
            const double centre = std::atan2(p.cy - sy, p.cx - sx);
            const double half = std::asin(p.radius / dist) + 0.5 * kSectorWidth;
            first = static_cast<int>(std::floor((centre - half + kPi) / kSectorWidth));
            last = static_cast<int>(std::floor((centre + half + kPi) / kSectorWidth));
        }
        const Candidate c{std::max(0.0, dist - p.radius), static_cast<uint32_t>(i)};
        for (int k = first; k <= last; ++k)
            sectors[static_cast<size_t>(((k % kSectors) + kSectors) % kSectors)].push_back(c);
    }
    for (std::vector<Candidate> &list : sectors) {
        std::sort(list.begin(), list.end(), [](const Candidate &a, const Candidate &b) {
            return a.near < b.near || (a.near == b.near && a.index < b.index);
        });
    }

    const int beams = std::max(opt.beams, 2);
    const int upper = beams / 2; // the upper half of the beams is packed more densely near the horizon
    std::vector<double> sin_el(static_cast<size_t>(beams)), cos_el(static_cast<size_t>(beams));
    for (int b = 0; b < beams; ++b) {
        double deg = opt.fov_up_deg - (opt.fov_up_deg - opt.fov_down_deg) * b / (beams - 1);
        if (opt.dense_upper_block) {
            deg = b < upper ? opt.fov_up_deg + (opt.split_deg - opt.fov_up_deg) * b / (upper - 1)
                            : opt.split_deg - 0.5 +
                                  (opt.fov_down_deg - opt.split_deg + 0.5) * (b - upper) / (beams - upper - 1);
        }
        const double el = deg_to_rad(deg);
        sin_el[static_cast<size_t>(b)] = std::sin(el);
        cos_el[static_cast<size_t>(b)] = std::cos(el);
    }
    const double az0 = rng.uniform(0.0, 2.0 * kPi); // where the revolution starts
    scan.xyz.reserve(static_cast<size_t>(beams) * static_cast<size_t>(opt.azimuth_steps) * 3u * 3u / 4u);
    const double *R = sensor.R;
    for (int a = 0; a < opt.azimuth_steps; ++a) {
        const double az = az0 + 2.0 * kPi * a / opt.azimuth_steps;
        const double ca = std::cos(az), sa = std::sin(az);
        for (size_t b = 0; b < sin_el.size(); ++b) {
            const double ds[3] = {cos_el[b] * ca, cos_el[b] * sa, sin_el[b]};
            Ray ray{{sensor.t[0], sensor.t[1], sensor.t[2]},
                    {R[0] * ds[0] + R[1] * ds[1] + R[2] * ds[2], R[3] * ds[0] + R[4] * ds[1] + R[5] * ds[2],
                     R[6] * ds[0] + R[7] * ds[1] + R[8] * ds[2]}};
            ++scan.rays;
            double t = kInf;
            const double world_az = std::atan2(ray.d[1], ray.d[0]);
            int sector = static_cast<int>(std::floor((world_az + kPi) / kSectorWidth));
            sector = std::min(std::max(sector, 0), kSectors - 1);
            for (const Candidate &c : sectors[static_cast<size_t>(sector)]) {
                if (c.near > t) break;
                t = std::min(t, hit_prim(scene, scene.prims[c.index], ray, rng));
            }
            t = std::min(t, hit_ground(scene.ground, ray, std::min(t, opt.max_range)));
            if (!(t >= opt.min_range && t <= opt.max_range)) continue;
            if (rng.chance(opt.dropout)) continue;
            const double range = t + opt.range_noise * rng.normal();
            scan.xyz.push_back(ds[0] * range);
            scan.xyz.push_back(ds[1] * range);
            scan.xyz.push_back(ds[2] * range);
        }
    }
    return scan;
}

} // namespace

DemoData generate_demo(const DemoOptions &options) {
    DemoData out{};
    Rng layout_rng(options.seed, 0);
    Scene common;
    common.ground = make_ground(layout_rng);

    // An asymmetric street: a narrow and a wide side, lights on one side (sometimes both), parking mostly on
    // one side, trees where there is room.
    Layout lay;
    const int narrow = layout_rng.uniform_int(0, 1);
    for (int k = 0; k < 2; ++k) {
        StreetSide &street = lay.sides[k];
        street.sign = k == 0 ? -1.0 : 1.0;
        street.kerb = k == narrow ? layout_rng.uniform(5.0, 6.0) : layout_rng.uniform(6.5, 8.5);
        street.sidewalk = k == narrow ? layout_rng.uniform(2.0, 3.0) : layout_rng.uniform(3.5, 5.5);
        street.poles = k == narrow ? layout_rng.chance(0.3) : true;
        street.trees = k == narrow ? layout_rng.chance(0.4) : layout_rng.chance(0.8);
        street.parking = k == narrow ? layout_rng.uniform(0.0, 0.5) : layout_rng.uniform(0.6, 0.85);
    }
    lay.cross_x = layout_rng.sign() * layout_rng.uniform(22.0, 38.0);
    lay.cross_half_width = layout_rng.uniform(5.0, 7.0);
    lay.end_x = (lay.cross_x < 0.0 ? 1.0 : -1.0) * layout_rng.uniform(35.0, 55.0);
    finish_ground(common.ground, lay, layout_rng.uniform(0.12, 0.18));

    for (const StreetSide &street : lay.sides) add_street_buildings(common, layout_rng, lay, street, out.stats);
    add_cross_street_buildings(common, layout_rng, lay, out.stats);
    add_end_buildings(common, layout_rng, lay, out.stats);
    add_street_furniture(common, layout_rng, lay, out.stats);

    // Sensor poses: both on the main street, 10-15 m apart, with a large relative yaw and a little roll and
    // pitch (a vehicle on a cambered road).
    const double tilt = deg_to_rad(options.max_tilt_deg);
    // Both poses are in the lanes, clear of the parked cars.
    const double lane_lo = lay.road_lo() + 2.8, lane_hi = lay.road_hi() - 2.8;
    const double xt = layout_rng.uniform(-4.0, 4.0), yt = layout_rng.uniform(lane_lo, lane_hi);
    const double yaw_t = layout_rng.uniform(-kPi, kPi);
    const Pose target_pose = pose_from_ypr(yaw_t, layout_rng.uniform(-tilt, tilt), layout_rng.uniform(-tilt, tilt), xt,
                                           yt, common.ground.height(xt, yt) + options.sensor_height);
    const double dist = layout_rng.uniform(options.min_distance, options.max_distance);
    const double ys = layout_rng.uniform(lane_lo, lane_hi);
    const double dy = std::min(std::fabs(ys - yt), dist);
    const double xs = xt + layout_rng.sign() * std::sqrt(dist * dist - dy * dy);
    const double yaw_s =
        yaw_t + layout_rng.sign() * deg_to_rad(layout_rng.uniform(options.min_yaw_deg, options.max_yaw_deg));
    const Pose source_pose = pose_from_ypr(yaw_s, layout_rng.uniform(-tilt, tilt), layout_rng.uniform(-tilt, tilt), xs,
                                           ys, common.ground.height(xs, ys) + options.sensor_height);

    add_stopped_vehicles(common, layout_rng, lay, source_pose, target_pose, out.stats);
    Scene source_scene = common, target_scene = common;
    add_movers(source_scene, layout_rng, lay, source_pose, target_pose, out.stats);
    add_movers(target_scene, layout_rng, lay, source_pose, target_pose, out.stats);
    out.stats.primitives = common.prims.size() + (source_scene.prims.size() - common.prims.size()) +
                           (target_scene.prims.size() - common.prims.size());

    Rng source_rng(options.seed, 1), target_rng(options.seed, 2);
    out.source = cast_scan(source_scene, source_pose, options, source_rng);
    out.target = cast_scan(target_scene, target_pose, options, target_rng);
    pose_to_matrix(pose_compose(pose_inverse(target_pose), source_pose), out.gt_target_from_source);
    return out;
}

} // namespace kissm_cli
