// SPDX-License-Identifier: MIT
// kissm refine SOURCE TARGET --initial T.txt --voxel V [options]
#include <cstdio>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_args.hpp"
#include "commands.hpp"
#include "pair_command.hpp"

namespace kissm_cli {

namespace {

void print_refine_settings(std::FILE *out, const kissm_config &) {
    std::fprintf(out, "Registration:\n"
                      "  --initial FILE          the starting transform (required): 4 lines of 4 numbers, a 4x4\n"
                      "                          row-major rigid transform mapping SOURCE into TARGET (lines\n"
                      "                          starting with # are ignored), as --out-transform writes it\n"
                      "  --voxel V               voxel size in the clouds' unit, > 0 (required)\n"
                      "  --threads N             worker threads, 0 = all hardware threads (default 0); the result\n"
                      "                          does not depend on N\n"
                      "  --viewpoint MODE        fixed (default), center, sign-free or local, as for 'kissm register'\n"
                      "  --viewpoint-center      the same as --viewpoint center\n"
                      "\n");
}

} // namespace

void print_refine_help(std::FILE *out) {
    print_pair_help(out, PairCommand::Refine,
                    "usage: kissm refine SOURCE TARGET --initial T.txt --voxel V [options]\n"
                    "\n"
                    "Refines a known pose (tracking, re-localisation, or `kissm register --out-transform`'s\n"
                    "result) by fine registration of the voxelised clouds, without the global search, and\n"
                    "prints the refined transform that maps SOURCE points into TARGET's frame.\n"
                    "\n",
                    print_refine_settings,
                    "Exit status: 0 valid refined pose, 1 refinement ran but the pose is not valid (see the\n"
                    "reason: too little overlap, a direction the clouds leave free, or a refinement still moving\n"
                    "at its iteration cap), 2 usage or input error, including a malformed, non-finite or\n"
                    "non-rigid --initial file (one \"kissm: ...\" line on stderr).\n");
}

int run_refine(const std::vector<std::string> &args) { return run_pair_command(PairCommand::Refine, args); }

} // namespace kissm_cli
