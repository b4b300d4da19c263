// SPDX-License-Identifier: MIT
// The sensor poses and the ray caster (see lidar_sim.hpp).
#include "lidar_sim.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace kissm_sim {

SensorPoses draw_sensor_poses(Rng &rng, const Ground &ground, double lane_lo, double lane_hi,
                              const DemoOptions &options) {
    const double tilt = deg_to_rad(options.max_tilt_deg);
    const double xt = rng.uniform(-4.0, 4.0), yt = rng.uniform(lane_lo, lane_hi);
    const double yaw_t = rng.uniform(-kPi, kPi);
    SensorPoses poses;
    poses.target = pose_from_ypr(yaw_t, rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt), xt, yt,
                                 ground.height(xt, yt) + options.sensor_height);
    const double dist = rng.uniform(options.min_distance, options.max_distance);
    const double ys = rng.uniform(lane_lo, lane_hi);
    const double dy = std::min(std::fabs(ys - yt), dist);
    const double xs = xt + rng.sign() * std::sqrt(dist * dist - dy * dy);
    const double yaw_s = yaw_t + rng.sign() * deg_to_rad(rng.uniform(options.min_yaw_deg, options.max_yaw_deg));
    poses.source = pose_from_ypr(yaw_s, rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt), xs, ys,
                                 ground.height(xs, ys) + options.sensor_height);
    return poses;
}

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

} // namespace kissm_sim
