// SPDX-License-Identifier: MIT
// The city (see city_layout.hpp).
#include "city_layout.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace kissm_sim {
namespace {

// A layout's cross street and end placed where they can never matter: the city's streets are furnished one
// stretch at a time, between crossings that the stretch's limits already keep clear.
constexpr double kFarAway = 1e9;

// How far the buildings of one stretch may reach past the limits given to add_street_buildings: a yawed
// building's corners before the first (about 3 m), and past the last a 4 m minimum building plus a wall
// across a gap of up to 10 m. The stretch is shortened by these so that nothing stands in a crossing street.
constexpr double kBuildingOverhangBegin = 4.0;
constexpr double kBuildingOverhangEnd = 14.5;
// A parked car may start just before the furniture's upper limit and be up to 4.9 m long.
constexpr double kCarOverhang = 5.0;
// Clutter tries per metre of a stretch (the demo's street: 90 tries along 150 m).
constexpr double kClutterPerMetre = 0.6;

double half_road(const Layout &lay) { return std::max(lay.sides[0].kerb, lay.sides[1].kerb); }
double half_street(const Layout &lay) {
    return std::max(lay.sides[0].kerb + lay.sides[0].sidewalk, lay.sides[1].kerb + lay.sides[1].sidewalk);
}

// Centre lines of `blocks` blocks of random sizes, centred on 0.
std::vector<double> draw_centre_lines(Rng &rng, int blocks, const CityOptions &options) {
    std::vector<double> at(1, 0.0);
    for (int k = 0; k < blocks; ++k) at.push_back(at.back() + rng.uniform(options.min_block, options.max_block));
    const double mid = 0.5 * at.back();
    for (double &a : at) a -= mid;
    return at;
}

// Moves the primitives of `local` (built in the street's frame on flat ground) into the world scene, each
// lifted by the world's ground under its centre. The frame turns by multiples of 90 degrees, so the rotated
// yaws are exact.
void place_in_world(const Scene &local, const CityStreet &st, Scene &world) {
    const double c = st.cos_yaw(), s = st.sin_yaw();
    for (const PrimRef &p : local.prims) {
        double x = 0.0, y = 0.0;
        st.to_world(p.cx, p.cy, &x, &y);
        const double g = world.ground.height(x, y);
        switch (p.kind) {
        case Kind::Box: {
            Box b = local.boxes[p.index];
            const double cs = b.cs * c - b.sn * s, sn = b.sn * c + b.cs * s;
            b.c[0] = x;
            b.c[1] = y;
            b.c[2] += g;
            b.cs = cs;
            b.sn = sn;
            world.prims.push_back({Kind::Box, static_cast<uint32_t>(world.boxes.size()), x, y, p.radius});
            world.boxes.push_back(b);
            break;
        }
        case Kind::Cylinder: {
            Cylinder cy = local.cylinders[p.index];
            cy.cx = x;
            cy.cy = y;
            cy.z0 += g;
            cy.z1 += g;
            world.prims.push_back({Kind::Cylinder, static_cast<uint32_t>(world.cylinders.size()), x, y, p.radius});
            world.cylinders.push_back(cy);
            break;
        }
        case Kind::Ellipsoid: {
            Ellipsoid e = local.ellipsoids[p.index];
            e.c[0] = x;
            e.c[1] = y;
            e.c[2] += g;
            world.prims.push_back({Kind::Ellipsoid, static_cast<uint32_t>(world.ellipsoids.size()), x, y, p.radius});
            world.ellipsoids.push_back(e);
            break;
        }
        }
    }
}

// A scene on flat ground (every amplitude zero: height 0 everywhere) to furnish a stretch in its own frame.
Scene flat_scene() { return Scene{}; }

// The road of a street as a rectangle in the world: its length from the far kerb of the first crossing to
// the far kerb of the last, its width from kerb to kerb.
void add_road(Ground &g, const CityStreet &st, double first_half, double last_half) {
    double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
    const double u0 = st.sign * (st.sign > 0 ? st.begin - first_half : st.end + last_half);
    const double u1 = st.sign * (st.sign > 0 ? st.end + last_half : st.begin - first_half);
    st.to_world(u0, -st.lay.sides[0].kerb, &x0, &y0);
    st.to_world(u1, st.lay.sides[1].kerb, &x1, &y1);
    const int k = g.roads++;
    g.road_x0[k] = std::min(x0, x1);
    g.road_x1[k] = std::max(x0, x1);
    g.road_y0[k] = std::min(y0, y1);
    g.road_y1[k] = std::max(y0, y1);
}

// Everything along one street: each stretch between two crossings, furnished in the street's frame.
void furnish_street(Rng &rng, City &city, CityStreet &st, const std::vector<const Layout *> &crossings,
                    const std::vector<double> &crossing_at) {
    for (size_t k = 0; k + 1 < crossing_at.size(); ++k) {
        // The stretch in the street's own u, from the crossing at its lower u (a) to the one at its higher u (b).
        const size_t a = st.sign > 0 ? k : k + 1, b = st.sign > 0 ? k + 1 : k;
        const double ua = st.sign * crossing_at[a], ub = st.sign * crossing_at[b];
        Scene local = flat_scene();
        const double build_lo = ua + half_street(*crossings[a]) + 0.5 + kBuildingOverhangBegin;
        const double build_hi = ub - half_street(*crossings[b]) - 0.5 - kBuildingOverhangEnd;
        for (const StreetSide &side : st.lay.sides) {
            add_street_buildings(local, rng, st.lay, side, build_lo, build_hi, city.stats);
        }
        // Lights, trees and clutter stay on the sidewalks, clear of the crossing streets' roads.
        const double kerb_lo = ua + half_road(*crossings[a]) + 1.5;
        const double kerb_hi = ub - half_road(*crossings[b]) - 1.5;
        add_kerbside_furniture(local, rng, st.lay, kerb_lo, kerb_hi - kCarOverhang, city.stats);
        const int clutter = static_cast<int>(kClutterPerMetre * (kerb_hi - kerb_lo));
        add_sidewalk_clutter(local, rng, st.lay, kerb_lo, kerb_hi, clutter, city.stats);
        place_in_world(local, st, city.scene);
    }
}

void build_grid_index(City &city) {
    const std::vector<PrimRef> &prims = city.scene.prims;
    double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
    for (size_t i = 0; i < prims.size(); ++i) {
        const PrimRef &p = prims[i];
        x0 = i == 0 ? p.cx - p.radius : std::min(x0, p.cx - p.radius);
        y0 = i == 0 ? p.cy - p.radius : std::min(y0, p.cy - p.radius);
        x1 = i == 0 ? p.cx + p.radius : std::max(x1, p.cx + p.radius);
        y1 = i == 0 ? p.cy + p.radius : std::max(y1, p.cy + p.radius);
    }
    city.grid_x0 = x0;
    city.grid_y0 = y0;
    city.grid_nx = std::max(1, static_cast<int>(std::ceil((x1 - x0) / city.cell)));
    city.grid_ny = std::max(1, static_cast<int>(std::ceil((y1 - y0) / city.cell)));
    city.cells.assign(static_cast<size_t>(city.grid_nx) * static_cast<size_t>(city.grid_ny), {});
    const auto clamp_cell = [](double v, int n) { return std::min(std::max(static_cast<int>(v), 0), n - 1); };
    for (size_t i = 0; i < prims.size(); ++i) {
        const PrimRef &p = prims[i];
        const int i0 = clamp_cell(std::floor((p.cx - p.radius - x0) / city.cell), city.grid_nx);
        const int i1 = clamp_cell(std::floor((p.cx + p.radius - x0) / city.cell), city.grid_nx);
        const int j0 = clamp_cell(std::floor((p.cy - p.radius - y0) / city.cell), city.grid_ny);
        const int j1 = clamp_cell(std::floor((p.cy + p.radius - y0) / city.cell), city.grid_ny);
        for (int j = j0; j <= j1; ++j) {
            for (int k = i0; k <= i1; ++k) {
                city.cells[static_cast<size_t>(j) * static_cast<size_t>(city.grid_nx) + static_cast<size_t>(k)]
                    .push_back(static_cast<uint32_t>(i));
            }
        }
    }
}

} // namespace

void CityStreet::to_world(double u, double v, double *x, double *y) const {
    if (along_x) {
        *x = sign * u;
        *y = at + sign * v;
    } else {
        *x = at - sign * v;
        *y = sign * u;
    }
}

City build_city(uint64_t seed, const CityOptions &options) {
    const int max_blocks = Ground::kMaxRoads / 2 - 1;
    if (options.blocks_x < 1 || options.blocks_y < 1 || options.blocks_x > max_blocks ||
        options.blocks_y > max_blocks || !(options.min_block >= 40.0) || !(options.max_block >= options.min_block)) {
        throw std::invalid_argument("kissm_sim::build_city: 1..7 blocks each way of at least 40 m");
    }
    City city;
    Rng rng(seed, 0);
    city.scene.ground = make_ground(rng);
    city.xs = draw_centre_lines(rng, options.blocks_x, options);
    city.ys = draw_centre_lines(rng, options.blocks_y, options);

    // Each street's cross-section and orientation.
    for (int pass = 0; pass < 2; ++pass) {
        const std::vector<double> &at = pass == 0 ? city.ys : city.xs;
        const std::vector<double> &along = pass == 0 ? city.xs : city.ys;
        for (double a : at) {
            CityStreet st;
            st.along_x = pass == 0;
            st.at = a;
            st.begin = along.front();
            st.end = along.back();
            draw_cross_section(rng, st.lay);
            st.lay.cross_x = kFarAway;
            st.lay.end_x = -kFarAway;
            st.sign = rng.sign();
            city.streets.push_back(st);
        }
    }

    // The ground: the streets as its roads, then the bounds over the whole city and the reach of its sensors.
    Ground &g = city.scene.ground;
    const size_t nx = city.xs.size(), ny = city.ys.size();
    for (size_t j = 0; j < ny; ++j) {
        add_road(g, city.streets[j], half_road(city.street_along_y(0).lay), half_road(city.street_along_y(nx - 1).lay));
    }
    for (size_t i = 0; i < nx; ++i) {
        add_road(g, city.streets[ny + i], half_road(city.street_along_x(0).lay),
                 half_road(city.street_along_x(ny - 1).lay));
    }
    g.curb_height = rng.uniform(0.12, 0.18);
    const double extent = std::max({-city.xs.front(), city.xs.back(), -city.ys.front(), city.ys.back()});
    bound_ground(g, extent + kCityGroundMargin);

    // The stretches of every street, street after street.
    for (size_t s = 0; s < city.streets.size(); ++s) {
        CityStreet &st = city.streets[s];
        std::vector<const Layout *> crossings;
        const size_t n = st.along_x ? nx : ny;
        for (size_t k = 0; k < n; ++k) {
            crossings.push_back(st.along_x ? &city.street_along_y(k).lay : &city.street_along_x(k).lay);
        }
        furnish_street(rng, city, st, crossings, st.along_x ? city.xs : city.ys);
    }
    city.stats.primitives = city.scene.prims.size();
    build_grid_index(city);
    return city;
}

Scene scene_near(const City &city, double x, double y, double range) {
    Scene out;
    out.ground = city.scene.ground;
    const auto cell_of = [&](double v, double v0, int n) {
        return std::min(std::max(static_cast<int>(std::floor((v - v0) / city.cell)), 0), n - 1);
    };
    const int i0 = cell_of(x - range, city.grid_x0, city.grid_nx), i1 = cell_of(x + range, city.grid_x0, city.grid_nx);
    const int j0 = cell_of(y - range, city.grid_y0, city.grid_ny), j1 = cell_of(y + range, city.grid_y0, city.grid_ny);
    std::vector<uint32_t> ids;
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            const std::vector<uint32_t> &cell =
                city.cells[static_cast<size_t>(j) * static_cast<size_t>(city.grid_nx) + static_cast<size_t>(i)];
            ids.insert(ids.end(), cell.begin(), cell.end());
        }
    }
    // In the city's order, each once: the ray caster breaks ties between equally near primitives by index.
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    const Scene &s = city.scene;
    for (uint32_t id : ids) {
        const PrimRef &p = s.prims[id];
        if (std::hypot(p.cx - x, p.cy - y) - p.radius > range) continue;
        PrimRef q = p;
        switch (p.kind) {
        case Kind::Box:
            q.index = static_cast<uint32_t>(out.boxes.size());
            out.boxes.push_back(s.boxes[p.index]);
            break;
        case Kind::Cylinder:
            q.index = static_cast<uint32_t>(out.cylinders.size());
            out.cylinders.push_back(s.cylinders[p.index]);
            break;
        case Kind::Ellipsoid:
            q.index = static_cast<uint32_t>(out.ellipsoids.size());
            out.ellipsoids.push_back(s.ellipsoids[p.index]);
            break;
        }
        out.prims.push_back(q);
    }
    return out;
}

void add_city_movers(Scene &s, Rng &rng, const City &city, const Pose &sensor) {
    constexpr double kReach = 45.0;     // movers this far along the street from the sensor, at most
    constexpr double kClearance = 10.0; // and never this close to it
    const double sx = sensor.t[0], sy = sensor.t[1];
    // The streets whose centre line passes within kReach of the sensor.
    std::vector<const CityStreet *> near;
    for (const CityStreet &st : city.streets) {
        const double across = st.along_x ? sy - st.at : sx - st.at;
        const double along = st.along_x ? sx : sy;
        if (std::fabs(across) < kReach && along > st.begin - kReach && along < st.end + kReach) near.push_back(&st);
    }
    if (near.empty()) return;
    const auto place = [&](const CityStreet &st, Scene &local) { place_in_world(local, st, s); };
    const auto draw_u = [&](const CityStreet &st) {
        const double along = std::min(std::max(st.along_x ? sx : sy, st.begin), st.end);
        const double w = std::min(std::max(along + rng.uniform(-kReach, kReach), st.begin), st.end);
        return st.sign * w;
    };
    const auto clear_of_sensor = [&](const CityStreet &st, double u, double v) {
        double x = 0.0, y = 0.0;
        st.to_world(u, v, &x, &y);
        return std::hypot(x - sx, y - sy) >= kClearance;
    };
    const int vehicles = rng.uniform_int(0, 3);
    for (int i = 0; i < vehicles; ++i) {
        for (int attempt = 0; attempt < 20; ++attempt) {
            const CityStreet &st = *near[static_cast<size_t>(rng.uniform_int(0, static_cast<int>(near.size()) - 1))];
            const double u = draw_u(st), v = rng.uniform(st.lay.lane_lo(), st.lay.lane_hi());
            if (!clear_of_sensor(st, u, v)) continue;
            Scene local = flat_scene();
            add_car(local, rng, u, v, rng.uniform(-0.05, 0.05) + (rng.chance(0.5) ? kPi : 0.0), rng.uniform(4.0, 4.8));
            place(st, local);
            break;
        }
    }
    const int walkers = rng.uniform_int(1, 4);
    for (int i = 0; i < walkers; ++i) {
        const CityStreet &st = *near[static_cast<size_t>(rng.uniform_int(0, static_cast<int>(near.size()) - 1))];
        const StreetSide &side = st.lay.sides[rng.uniform_int(0, 1)];
        const double u = draw_u(st), v = side.sign * (side.kerb + rng.uniform(0.5, side.sidewalk - 0.3));
        const double radius = rng.uniform(0.2, 0.28), height = rng.uniform(1.55, 1.9);
        if (!clear_of_sensor(st, u, v)) continue;
        Scene local = flat_scene();
        local.add_cylinder(u, v, -0.1, height, radius);
        place(st, local);
    }
}

} // namespace kissm_sim
