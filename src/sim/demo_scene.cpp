// SPDX-License-Identifier: MIT
// The demo scene (see demo_scene.hpp): the street (street_layout.cpp), the two sensor poses and scans
// (lidar_sim.cpp) and the ground truth, in a fixed order of random draws. Stream 0 of the seed draws the
// street, the poses, the stopped vehicles and the movers; streams 1 and 2 the source and target scans.
#include "demo_scene.hpp"

#include "lidar_sim.hpp"
#include "pose_math.hpp"
#include "ray_geometry.hpp"
#include "rng.hpp"
#include "street_layout.hpp"

namespace kissm_sim {
using namespace kissm_pose; // src/common/pose_math.hpp

DemoData generate_demo(const DemoOptions &options) {
    DemoData out{};
    Rng layout_rng(options.seed, 0);
    Scene common;
    Layout lay;
    build_street(layout_rng, common, lay, out.stats);
    const SensorPoses poses = draw_sensor_poses(layout_rng, common.ground, lay.lane_lo(), lay.lane_hi(), options);

    add_stopped_vehicles(common, layout_rng, lay, poses.source, poses.target, out.stats);
    Scene source_scene = common, target_scene = common;
    add_movers(source_scene, layout_rng, lay, poses.source, poses.target, out.stats);
    add_movers(target_scene, layout_rng, lay, poses.source, poses.target, out.stats);
    out.stats.primitives = common.prims.size() + (source_scene.prims.size() - common.prims.size()) +
                           (target_scene.prims.size() - common.prims.size());

    Rng source_rng(options.seed, 1), target_rng(options.seed, 2);
    out.source = cast_scan(source_scene, poses.source, options, source_rng);
    out.target = cast_scan(target_scene, poses.target, options, target_rng);
    pose_to_matrix(pose_compose(pose_inverse(poses.target), poses.source), out.gt_target_from_source);
    return out;
}

} // namespace kissm_sim
