// SPDX-License-Identifier: MIT
// The street layout (see street_layout.hpp).
#include "street_layout.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace kissm_sim {
namespace {

constexpr double kSceneExtent = 200.0; // metres from the world origin that the ground bounds cover

} // namespace

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

void bound_ground(Ground &g, double extent) {
    const double curb_height = g.curb_height;
    const double slope = std::fabs(g.gx) + std::fabs(g.gy);
    const double rough = Ground::kRoughWaves * std::max(g.rough_road, g.rough_off_road);
    double rough_gradient = 0.0;
    for (int i = 0; i < Ground::kRoughWaves; ++i) rough_gradient += std::hypot(g.rough_kx[i], g.rough_ky[i]);
    g.hmin = -(g.a1 + g.a2 + slope * extent + rough);
    g.hmax = g.a1 + g.a2 + slope * extent + curb_height + rough;
    // The kerb ramps also scale the roughness amplitude; both effects are bounded by the step allowance
    // (curb_height + rough) that hit_ground subtracts before each step.
    g.max_gradient = kWaveSlope * (g.a1 * std::hypot(g.k1x, g.k1y) + g.a2 * std::hypot(g.k2x, g.k2y) +
                                   std::max(g.rough_road, g.rough_off_road) * rough_gradient) +
                     std::hypot(g.gx, g.gy);
}

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

namespace {

// Fixes the streets (for the kerbs) and the bounds used by the ray marcher.
void finish_ground(Ground &g, const Layout &lay, double curb_height) {
    g.road_lo = lay.road_lo();
    g.road_hi = lay.road_hi();
    const double cross_x = lay.cross_x, cross_half_width = lay.cross_half_width;
    g.cross_x = cross_x;
    g.cross_half_width = cross_half_width;
    g.curb_height = curb_height;
    bound_ground(g, kSceneExtent);
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

} // namespace

void add_street_buildings(Scene &s, Rng &rng, const Layout &lay, const StreetSide &street, double x_begin, double x_end,
                          DemoSceneStats &stats) {
    const double side = street.sign;
    const double sidewalk_edge = street.kerb + street.sidewalk;
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

namespace {

// A building of depth (along x) by length (along y) and the given height at (cx, cy), slightly yawed, with
// facade details on the face whose outward normal is (front, 0) (front = +1 or -1).
void add_block_facing_x(Scene &s, Rng &rng, double cx, double cy, double depth, double length, double height,
                        double front, DemoSceneStats &stats) {
    const double g = s.ground.height(cx, cy);
    const double yaw = rng.uniform(-0.05, 0.05);
    s.add_box(cx, cy, g - 1.0, g + height, depth, length, yaw);
    ++stats.buildings;
    stats.details += add_facade_details(s, rng, cx, cy, g, depth, length, height, yaw, front, 0.0);
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
                add_block_facing_x(s, rng, cx, sy * (y + 0.5 * length), depth, length, height, -sx, stats);
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
        add_block_facing_x(s, rng, cx, y + 0.5 * length, depth, length, height, -sx, stats);
        y += length + (rng.chance(0.5) ? rng.uniform(0.0, 0.5) : rng.uniform(1.5, 5.0));
    }
}

} // namespace

void add_kerbside_furniture(Scene &s, Rng &rng, Layout &lay, double x_lo, double x_hi, DemoSceneStats &stats) {
    for (StreetSide &street : lay.sides) {
        const double side = street.sign;
        // Street lights at the kerb with an arm over the road.
        if (street.poles) {
            for (double x = x_lo + rng.uniform(0.0, 20.0); x < x_hi; x += rng.uniform(16.0, 32.0)) {
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
            for (double x = x_lo + rng.uniform(0.0, 10.0); x < x_hi; x += rng.uniform(6.0, 14.0)) {
                if (!rng.chance(0.7) || lay.in_cross_street(x, 2.0) || lay.beyond_end(x)) continue;
                bool near_pole = false;
                for (double px : street.pole_x) near_pole = near_pole || std::fabs(px - x) < 2.5;
                if (near_pole) continue;
                add_tree(s, rng, x, side * (street.kerb + offset));
                ++stats.trees;
            }
        }
        // Parked cars along the kerb.
        double x = x_lo + rng.uniform(0.0, 5.0);
        while (x < x_hi) {
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
}

void add_sidewalk_clutter(Scene &s, Rng &rng, const Layout &lay, double x_lo, double x_hi, int count,
                          DemoSceneStats &stats) {
    for (int i = 0; i < count; ++i) {
        const StreetSide &street = lay.sides[rng.uniform_int(0, 1)];
        const double x = rng.uniform(x_lo, x_hi);
        const double y = street.sign * (street.kerb + rng.uniform(0.3, street.sidewalk - 0.2));
        if (lay.in_cross_street(x, 0.0) || lay.beyond_end(x - 2.0)) continue;
        add_clutter(s, rng, x, y);
        ++stats.clutter;
    }
}

namespace {

// The demo's lights, trees, parked cars and clutter: along the main street, then clutter along the cross street.
void add_street_furniture(Scene &s, Rng &rng, Layout &lay, DemoSceneStats &stats) {
    add_kerbside_furniture(s, rng, lay, -90.0, 90.0, stats);
    add_sidewalk_clutter(s, rng, lay, -75.0, 75.0, 90, stats);
    for (int i = 0; i < 25; ++i) {
        const double x = lay.cross_x + rng.sign() * rng.uniform(lay.cross_half_width + 0.3, lay.cross_half_width + 3.0);
        const double y = rng.sign() * rng.uniform(12.0, 70.0);
        add_clutter(s, rng, x, y);
        ++stats.clutter;
    }
}

} // namespace

void draw_cross_section(Rng &rng, Layout &lay) {
    // An asymmetric street: a narrow and a wide side, lights on one side (sometimes both), parking mostly on
    // one side, trees where there is room.
    const int narrow = rng.uniform_int(0, 1);
    for (int k = 0; k < 2; ++k) {
        StreetSide &street = lay.sides[k];
        street.sign = k == 0 ? -1.0 : 1.0;
        street.kerb = k == narrow ? rng.uniform(5.0, 6.0) : rng.uniform(6.5, 8.5);
        street.sidewalk = k == narrow ? rng.uniform(2.0, 3.0) : rng.uniform(3.5, 5.5);
        street.poles = k == narrow ? rng.chance(0.3) : true;
        street.trees = k == narrow ? rng.chance(0.4) : rng.chance(0.8);
        street.parking = k == narrow ? rng.uniform(0.0, 0.5) : rng.uniform(0.6, 0.85);
    }
}

void build_street(Rng &rng, Scene &s, Layout &lay, DemoSceneStats &stats) {
    s.ground = make_ground(rng);
    draw_cross_section(rng, lay);
    lay.cross_x = rng.sign() * rng.uniform(22.0, 38.0);
    lay.cross_half_width = rng.uniform(5.0, 7.0);
    lay.end_x = (lay.cross_x < 0.0 ? 1.0 : -1.0) * rng.uniform(35.0, 55.0);
    finish_ground(s.ground, lay, rng.uniform(0.12, 0.18));

    const double x_begin = lay.end_x < 0.0 ? lay.end_x : -95.0, x_end = lay.end_x < 0.0 ? 95.0 : lay.end_x;
    for (const StreetSide &street : lay.sides) add_street_buildings(s, rng, lay, street, x_begin, x_end, stats);
    add_cross_street_buildings(s, rng, lay, stats);
    add_end_buildings(s, rng, lay, stats);
    add_street_furniture(s, rng, lay, stats);
}

void add_stopped_vehicles(Scene &s, Rng &rng, const Layout &lay, const Pose &a, const Pose &b, DemoSceneStats &stats) {
    const int count = rng.uniform_int(1, 3);
    for (int i = 0; i < count; ++i) {
        for (int attempt = 0; attempt < 20; ++attempt) {
            const double x = rng.uniform(-40.0, 40.0);
            if (std::fabs(x - a.t[0]) < 9.0 || std::fabs(x - b.t[0]) < 9.0 || lay.beyond_end(x) ||
                lay.in_cross_street(x, 3.0)) {
                continue;
            }
            const double y = rng.uniform(lay.lane_lo(), lay.lane_hi());
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

} // namespace kissm_sim
