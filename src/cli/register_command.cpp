// SPDX-License-Identifier: MIT
// kissm register SOURCE TARGET --voxel V [options]
#include <cstdio>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_args.hpp"
#include "commands.hpp"
#include "pair_command.hpp"
#include "pose_math.hpp"

namespace kissm_cli {
using namespace kissm_pose; // src/common/pose_math.hpp

void log_to_stderr(void *, int32_t level, const char *message) {
    const char *name = level == KISSM_LOG_ERROR  ? "error"
                       : level == KISSM_LOG_WARN ? "warning"
                       : level == KISSM_LOG_INFO ? "info"
                                                 : "debug";
    std::fprintf(stderr, "kissm: [%s] %s\n", name, message ? message : "");
}

namespace {

void print_register_settings(std::FILE *out, const kissm_config &d) {
    std::fprintf(out,
                 "Registration:\n"
                 "  --preset NAME           the settings of a common kind of data, applied first: every option\n"
                 "                          given explicitly overrides them, in any order. lidar-vehicle (0.3 m\n"
                 "                          voxels, ground suppression, normals toward the sensor), lidar-handheld\n"
                 "                          (0.3 m, --viewpoint local), indoor-rgbd (0.05 m), object (0.006 m);\n"
                 "                          each gives a voxel size, so --voxel becomes optional\n"
                 "  --voxel V               voxel size in the clouds' unit, > 0, or auto (the library suggests one\n"
                 "                          for the pair: kissm_suggest_voxel_size); required without --preset;\n"
                 "                          every radius and noise bound scales with it. Try 0.3-0.5 for outdoor\n"
                 "                          LiDAR in metres, 0.05 for indoor RGB-D fragments\n"
                 "  --threads N             worker threads, 0 = all hardware threads (default 0); the result\n"
                 "                          does not depend on N\n"
                 "  --min-inliers N         final inliers a valid pose needs without refinement (default %d)\n"
                 "  --max-correspondences N cap on the matches kept, best first; 0: automatic, growing with the\n"
                 "                          keypoints (at least 5000) (default %d)\n"
                 "  --max-rotation-uncertainty RAD (default %g, i.e. %.3g deg)\n"
                 "                          without refinement, a valid pose needs inliers that pin its rotation\n"
                 "                          down to RAD radians (rotation_uncertainty), in (0, 3.15]: few inliers,\n"
                 "                          or all on one compact object, do not; with refinement it bounds 4\n"
                 "                          times the rotation sigma of the refined information\n"
                 "  --max-ambiguity X       largest ambiguity of a valid pose (default %g; 1 = never refused), in\n"
                 "                          [0, 1]: the best distinct competing pose's support over this one's;\n"
                 "                          repetitive or symmetric scenes match as well elsewhere (reason_code 14)\n"
                 "  --viewpoint MODE        how normals are oriented: local (the default) or sign-free (no\n"
                 "                          viewpoint: features that depend on no cloud's frame;\n"
                 "                          docs/design/frames.md), fixed (toward the sensor at the frame origin:\n"
                 "                          single scans in their sensor frame) or center (each cloud's centre)\n"
                 "  --viewpoint-center      the same as --viewpoint center\n"
                 "\n"
                 "Ground and up (scans of a sensor on a vehicle, in its own frame):\n"
                 "  --suppression MODE      none or ground (default %s): ground voxels around the sensor (at the\n"
                 "                          frame origin) get no keypoint; they stay in the refined clouds\n"
                 "  --rotation-dof N        3 or 1 (default %d): 1 = yaw about --up only, roll and pitch taken as\n"
                 "                          zero (a clearly tilted pair is not valid: reason_code 12, tilt)\n"
                 "  --up X,Y,Z              the up direction in each cloud's frame (default %g,%g,%g), any\n"
                 "                          length above 1e-9\n"
                 "  --sensor-height H       the sensor's height above the ground along up (default %g), in\n"
                 "                          [0, 1000]; 0 = estimate it from the cloud\n"
                 "\n",
                 d.min_inliers, d.max_correspondences, d.max_rotation_uncertainty,
                 rad_to_deg(d.max_rotation_uncertainty), d.max_ambiguity,
                 d.suppression == KISSM_SUPPRESS_GROUND ? "ground" : "none", d.rotation_dof, d.up[0], d.up[1], d.up[2],
                 d.sensor_height);
}

} // namespace

void print_register_help(std::FILE *out) {
    print_pair_help(out, PairCommand::Register,
                    "usage: kissm register SOURCE TARGET --voxel V [options]\n"
                    "       kissm register SOURCE TARGET --preset NAME [options]\n"
                    "\n"
                    "Globally registers SOURCE against TARGET (no initial guess needed) and prints the rigid\n"
                    "transform that maps SOURCE points into TARGET's frame: p_target = R p_source + t.\n"
                    "\n",
                    print_register_settings,
                    "Exit status: 0 valid pose, 1 registration ran but the pose is not valid (see the reason),\n"
                    "2 usage or input error (one \"kissm: ...\" line on stderr).\n");
}

int run_register(const std::vector<std::string> &args) { return run_pair_command(PairCommand::Register, args); }

} // namespace kissm_cli
