// SPDX-License-Identifier: MIT
// The drive (see drive.hpp): a random walk over the city's crossings, the lane that follows it with rounded
// corners, the sensor poses along it, and the scans.
#include "drive.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

#include "lidar_sim.hpp"
#include "ray_geometry.hpp"
#include "rng.hpp"

namespace kissm_sim {
namespace {

constexpr uint64_t kRouteStream = 1;
constexpr uint64_t kFirstScanStream = 2;
constexpr double kWheelbase = 2.7; // metres between the axles: the pitch follows the ground over this
constexpr double kTrack = 1.6;     // between the wheels of an axle: the roll follows the ground over this

// A piece of the path: a straight line, or a quarter circle turning left (+1) or right (-1).
struct Piece {
    double x0 = 0.0, y0 = 0.0; // start
    double dx = 0.0, dy = 0.0; // a line's direction (a unit axis vector)
    double heading0 = 0.0;     // at the start, radians
    double length = 0.0;
    bool arc = false;
    double cx = 0.0, cy = 0.0, turn = 0.0; // an arc's centre and sense
};

struct Grid {
    const City &city;
    int nx, ny;
    double x(int node) const { return city.xs[static_cast<size_t>(node % nx)]; }
    double y(int node) const { return city.ys[static_cast<size_t>(node / nx)]; }
    std::vector<int> neighbours(int node) const {
        const int i = node % nx, j = node / nx;
        std::vector<int> out;
        if (i > 0) out.push_back(node - 1);
        if (i + 1 < nx) out.push_back(node + 1);
        if (j > 0) out.push_back(node - nx);
        if (j + 1 < ny) out.push_back(node + nx);
        return out;
    }
    size_t edge(int a, int b) const {
        const int lo = std::min(a, b), hi = std::max(a, b);
        return static_cast<size_t>(lo) * static_cast<size_t>(nx * ny) + static_cast<size_t>(hi);
    }
    double length(int a, int b) const { return std::fabs(x(a) - x(b)) + std::fabs(y(a) - y(b)); }
};

// The walk over the crossings: never straight back, and at each crossing the streets driven less often so
// far are likelier (1 / (1 + times driven)), so that it covers the city and then comes back over it.
class Walk {
public:
    Walk(const Grid &grid, Rng &rng)
        : grid_(grid), rng_(rng),
          visits_(static_cast<size_t>(grid.nx * grid.ny) * static_cast<size_t>(grid.nx * grid.ny), 0) {
        const int a = rng_.uniform_int(0, grid.nx * grid.ny - 1);
        const std::vector<int> next = grid.neighbours(a);
        const int b = next[static_cast<size_t>(rng_.uniform_int(0, static_cast<int>(next.size()) - 1))];
        route_ = {a, b};
        ++visits_[grid.edge(a, b)];
        centre_length_ = 0.5 * grid.length(a, b);
    }

    void step() {
        const int from = route_[route_.size() - 2], at = route_.back();
        std::vector<int> options;
        std::vector<double> weights;
        double total = 0.0;
        for (int n : grid_.neighbours(at)) {
            if (n == from) continue;
            options.push_back(n);
            weights.push_back(1.0 / (1.0 + visits_[grid_.edge(at, n)]));
            total += weights.back();
        }
        double pick = rng_.uniform(0.0, total);
        size_t k = 0;
        while (k + 1 < options.size() && pick >= weights[k]) pick -= weights[k++];
        route_.push_back(options[k]);
        ++visits_[grid_.edge(at, options[k])];
        centre_length_ += grid_.length(at, options[k]);
    }

    const std::vector<int> &route() const { return route_; }
    double centre_length() const { return centre_length_; }

private:
    const Grid &grid_;
    Rng &rng_;
    std::vector<int> visits_;
    std::vector<int> route_;
    double centre_length_ = 0.0;
};

// The lane along the route: from the middle of the first street stretch to the last crossing, `offset` right
// of the centre lines, its corners rounded by quarter circles of `radius`. Streets cross at right angles and
// the walk never turns back, so each corner is a right or left turn by 90 degrees.
std::vector<Piece> lane_pieces(const Grid &grid, const std::vector<int> &route, double offset, double radius) {
    std::vector<std::pair<double, double>> pts;
    pts.emplace_back(0.5 * (grid.x(route[0]) + grid.x(route[1])), 0.5 * (grid.y(route[0]) + grid.y(route[1])));
    for (size_t k = 1; k < route.size(); ++k) pts.emplace_back(grid.x(route[k]), grid.y(route[k]));
    // Crossings driven straight over are no corners.
    std::vector<std::pair<double, double>> corners(1, pts[0]);
    const auto dir = [](const std::pair<double, double> &a, const std::pair<double, double> &b) {
        const double dx = b.first - a.first, dy = b.second - a.second;
        return std::make_pair(dx > 0 ? 1.0 : (dx < 0 ? -1.0 : 0.0), dy > 0 ? 1.0 : (dy < 0 ? -1.0 : 0.0));
    };
    for (size_t k = 1; k + 1 < pts.size(); ++k) {
        if (dir(pts[k - 1], pts[k]) != dir(pts[k], pts[k + 1])) corners.push_back(pts[k]);
    }
    corners.push_back(pts.back());

    std::vector<Piece> pieces;
    const size_t legs = corners.size() - 1;
    double sx = 0.0, sy = 0.0; // where the next line starts
    for (size_t k = 0; k < legs; ++k) {
        const auto d = dir(corners[k], corners[k + 1]);
        const double nx = d.second, ny = -d.first; // right of the direction
        if (k == 0) {
            sx = corners[0].first + offset * nx;
            sy = corners[0].second + offset * ny;
        }
        Piece line;
        line.x0 = sx;
        line.y0 = sy;
        line.dx = d.first;
        line.dy = d.second;
        line.heading0 = std::atan2(d.second, d.first);
        if (k + 1 == legs) {
            const double ex = corners[k + 1].first + offset * nx, ey = corners[k + 1].second + offset * ny;
            line.length = std::fabs(ex - sx) + std::fabs(ey - sy);
            pieces.push_back(line);
            break;
        }
        // The corner where this lane line meets the next one, then the arc tangent to both.
        const auto e = dir(corners[k + 1], corners[k + 2]);
        const double mx = e.second, my = -e.first;
        const double cx = corners[k + 1].first + offset * (nx + mx), cy = corners[k + 1].second + offset * (ny + my);
        const double t1x = cx - radius * d.first, t1y = cy - radius * d.second;
        line.length = std::fabs(t1x - sx) + std::fabs(t1y - sy);
        pieces.push_back(line);
        Piece arc;
        arc.arc = true;
        arc.x0 = t1x;
        arc.y0 = t1y;
        arc.heading0 = line.heading0;
        arc.length = 0.5 * kPi * radius;
        arc.turn = d.first * e.second - d.second * e.first; // +1 left, -1 right
        arc.cx = t1x + radius * e.first;
        arc.cy = t1y + radius * e.second;
        pieces.push_back(arc);
        sx = cx + radius * e.first;
        sy = cy + radius * e.second;
    }
    return pieces;
}

double path_length(const std::vector<Piece> &pieces) {
    double total = 0.0;
    for (const Piece &p : pieces) total += p.length;
    return total;
}

// Position and heading at distance a into the piece.
void evaluate(const Piece &p, double a, double *x, double *y, double *heading) {
    if (!p.arc) {
        *x = p.x0 + a * p.dx;
        *y = p.y0 + a * p.dy;
        *heading = p.heading0;
        return;
    }
    const double radius = std::hypot(p.x0 - p.cx, p.y0 - p.cy);
    const double phi = p.turn * a / radius;
    const double c = std::cos(phi), s = std::sin(phi);
    const double rx = p.x0 - p.cx, ry = p.y0 - p.cy;
    *x = p.cx + c * rx - s * ry;
    *y = p.cy + s * rx + c * ry;
    *heading = p.heading0 + phi;
}

// A smooth random sway: two sines of distance with random wavelengths and phases, |value| <= amplitude.
struct Sway {
    double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0;
    explicit Sway(Rng &rng) {
        k1 = 2.0 * kPi / rng.uniform(12.0, 30.0);
        k2 = 2.0 * kPi / rng.uniform(4.0, 11.0);
        p1 = rng.uniform(0.0, 2.0 * kPi);
        p2 = rng.uniform(0.0, 2.0 * kPi);
    }
    double operator()(double s, double amplitude) const {
        return amplitude * (0.7 * std::sin(k1 * s + p1) + 0.3 * std::sin(k2 * s + p2));
    }
};

} // namespace

Drive plan_drive(const DriveOptions &options) {
    if (options.scans == 0 || !(options.spacing > 0.0) || !std::isfinite(options.spacing)) {
        throw std::invalid_argument("kissm_sim::plan_drive: needs at least one scan and a spacing above 0");
    }
    Drive drive;
    drive.city = build_city(options.seed, options.city);
    const City &city = drive.city;
    const Grid grid{city, static_cast<int>(city.xs.size()), static_cast<int>(city.ys.size())};

    // The route: walk on until the lane is long enough for every scan.
    Rng rng(options.seed, kRouteStream);
    const Sway roll_sway(rng), pitch_sway(rng), yaw_sway(rng);
    Walk walk(grid, rng);
    const double needed = static_cast<double>(options.scans - 1) * options.spacing;
    std::vector<Piece> pieces;
    for (;;) {
        while (walk.centre_length() < needed + 2.0 * options.turn_radius + 20.0) walk.step();
        pieces = lane_pieces(grid, walk.route(), options.lane_offset, options.turn_radius);
        if (path_length(pieces) >= needed) break;
        walk.step();
    }
    drive.route = walk.route();

    // The poses, every `spacing` metres.
    const Ground &ground = city.scene.ground;
    const double sway = deg_to_rad(options.sway_deg);
    size_t piece = 0;
    double piece_start = 0.0;
    for (size_t i = 0; i < options.scans; ++i) {
        const double s = static_cast<double>(i) * options.spacing;
        while (piece + 1 < pieces.size() && s >= piece_start + pieces[piece].length) {
            piece_start += pieces[piece].length;
            ++piece;
        }
        double x = 0.0, y = 0.0, heading = 0.0;
        evaluate(pieces[piece], std::min(s - piece_start, pieces[piece].length), &x, &y, &heading);
        // The vehicle stands on the ground: pitch and roll follow its slope under the wheels, plus its own sway.
        const double c = std::cos(heading), sn = std::sin(heading);
        const double front = ground.height(x + 0.5 * kWheelbase * c, y + 0.5 * kWheelbase * sn);
        const double back = ground.height(x - 0.5 * kWheelbase * c, y - 0.5 * kWheelbase * sn);
        const double left = ground.height(x - 0.5 * kTrack * sn, y + 0.5 * kTrack * c);
        const double right = ground.height(x + 0.5 * kTrack * sn, y - 0.5 * kTrack * c);
        const double pitch = -std::atan((front - back) / kWheelbase) + pitch_sway(s, sway);
        const double roll = std::atan((left - right) / kTrack) + roll_sway(s, sway);
        const double yaw = heading + yaw_sway(s, 0.5 * sway);
        drive.poses.push_back(
            pose_from_ypr(yaw, pitch, roll, x, y, ground.height(x, y) + options.sensor.sensor_height));
        drive.distance.push_back(s);
    }

    // The stretches between crossings that the scans lie on (the lane's length differs from the centre
    // line's by a few metres per corner; this is a count for the summary).
    const double driven = drive.distance.back();
    std::vector<size_t> seen;
    double at = 0.0;
    for (size_t k = 0; k + 1 < drive.route.size(); ++k) {
        if (at > driven) break;
        ++drive.legs;
        seen.push_back(grid.edge(drive.route[k], drive.route[k + 1]));
        const double len = grid.length(drive.route[k], drive.route[k + 1]);
        at += k == 0 ? 0.5 * len : len;
    }
    std::sort(seen.begin(), seen.end());
    drive.distinct_legs = static_cast<size_t>(std::unique(seen.begin(), seen.end()) - seen.begin());
    return drive;
}

DemoScan simulate_drive_scan(const Drive &drive, size_t index, const DriveOptions &options) {
    const Pose &pose = drive.poses.at(index);
    Rng rng(options.seed, kFirstScanStream + static_cast<uint64_t>(index));
    // Everything the sensor can reach (a little more: the caster applies the exact cut itself).
    Scene scene = scene_near(drive.city, pose.t[0], pose.t[1], options.sensor.max_range + 1.0);
    add_city_movers(scene, rng, drive.city, pose);
    return cast_scan(scene, pose, options.sensor, rng);
}

std::vector<LoopPair> true_loops(const Drive &drive, double min_gap, double radius) {
    // Sensors in square cells of side `radius`: pairs within radius are in the same or adjacent cells.
    std::map<std::pair<int64_t, int64_t>, std::vector<size_t>> cells;
    const auto cell_of = [&](const Pose &p) {
        return std::make_pair(static_cast<int64_t>(std::floor(p.t[0] / radius)),
                              static_cast<int64_t>(std::floor(p.t[1] / radius)));
    };
    for (size_t i = 0; i < drive.poses.size(); ++i) cells[cell_of(drive.poses[i])].push_back(i);
    std::vector<LoopPair> out;
    for (size_t i = 0; i < drive.poses.size(); ++i) {
        const Pose &a = drive.poses[i];
        const auto c = cell_of(a);
        for (int64_t dy = -1; dy <= 1; ++dy) {
            for (int64_t dx = -1; dx <= 1; ++dx) {
                const auto it = cells.find({c.first + dx, c.second + dy});
                if (it == cells.end()) continue;
                for (size_t j : it->second) {
                    if (j <= i || drive.distance[j] - drive.distance[i] < min_gap) continue;
                    const Pose &b = drive.poses[j];
                    const double d =
                        std::sqrt((a.t[0] - b.t[0]) * (a.t[0] - b.t[0]) + (a.t[1] - b.t[1]) * (a.t[1] - b.t[1]) +
                                  (a.t[2] - b.t[2]) * (a.t[2] - b.t[2]));
                    if (d <= radius) out.push_back({i, j, d});
                }
            }
        }
    }
    std::sort(out.begin(), out.end(),
              [](const LoopPair &p, const LoopPair &q) { return p.i < q.i || (p.i == q.i && p.j < q.j); });
    return out;
}

} // namespace kissm_sim
