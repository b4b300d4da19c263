// SPDX-License-Identifier: MIT
// kissm: the command-line front end of the kissm library.
//
//   kissm register SOURCE TARGET --voxel V [options]   global registration of two point files
//   kissm refine SOURCE TARGET --initial T.txt --voxel V [options]   fine registration from a known pose
//   kissm demo [--out DIR] [--threads N] [--seed S]     synthetic LiDAR scene, registered end to end
//   kissm ground IN --voxel V [--out-ground G.ply] [--out-rest R.ply]   a scan's ground points
//   kissm batch PAIRS.tsv --voxel V --out RESULTS.jsonl [--jobs N] [--resume]   many pairs, one JSON line each
//   kissm simulate OUTDIR --scans N [--seed S] [--spacing M]   a long simulated drive with loops, as a scan set
//   kissm align SCANS.tsv --voxel V --out POSES.tsv [--pairs all|sequence|FILE] [--map M.ply] [--g2o G.g2o]
//       many scans into one frame: pairs registered as batch does, then a pose graph
//
// Exit status: 0 success, 1 the registration ran but gave no trustworthy pose, 2 usage or input error
// (with one "kissm: ..." line on stderr).
#include <cstdio>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_args.hpp"
#include "commands.hpp"
#include "near_match.hpp"

namespace kissm_cli {
namespace {

void print_usage(std::FILE *out) {
    std::fprintf(out,
                 "kissm %s: fast, deterministic global 3D point cloud registration\n"
                 "\n"
                 "usage:\n"
                 "  kissm register SOURCE TARGET --voxel V [options]   (or --preset NAME instead of --voxel)\n"
                 "      Find the rigid transform that maps SOURCE into TARGET's frame, with no initial guess.\n"
                 "      Reads PLY, PCD, KITTI .bin, raw float32 xyz .bin, .npy and xyz text files.\n"
                 "      --refine gicp|point-to-plane refines the global pose on the voxelised clouds.\n"
                 "  kissm refine SOURCE TARGET --initial T.txt --voxel V [options]\n"
                 "      Refine a known pose (4 rows of 4 numbers, as register --out-transform writes) by\n"
                 "      GICP or point-to-plane ICP, without the global search.\n"
                 "  kissm demo [--out DIR] [--threads N] [--seed S] [--voxel V] [--json]\n"
                 "      Simulate two LiDAR scans of a synthetic street, register them, report the error against\n"
                 "      the ground truth and write PLY files and a top-view picture into DIR.\n"
                 "  kissm ground IN --voxel V [--out-ground G.ply] [--out-rest R.ply] [options]\n"
                 "      Label the ground points of a scan (the model of register --suppression ground) and\n"
                 "      write them and the other points as PLY files.\n"
                 "  kissm batch PAIRS.tsv --voxel V --out RESULTS.jsonl [--jobs N] [--resume] [options]\n"
                 "      Register every pair of a tab-separated pairs file (source, target, optional gt),\n"
                 "      describing each cloud once; one JSON line per pair, appended as it finishes.\n"
                 "  kissm simulate OUTDIR --scans N [--seed S] [--spacing M] [--threads T] [-q]\n"
                 "      Simulate a long LiDAR drive with loops through a synthetic city: the scans, their exact\n"
                 "      poses and the true loop closures, as a multi-scan set (scans.tsv, gt_poses.txt).\n"
                 "  kissm align SCANS.tsv --voxel V --out POSES.tsv [--pairs all|sequence|FILE] [--jobs N]\n"
                 "              [--resume] [--map MAP.ply] [--g2o G.g2o] [options]\n"
                 "      Put many scans into the first one's frame with no initial guess: register the pairs as\n"
                 "      batch does, then optimise a pose graph of the valid ones; one pose per scan. Exit 1\n"
                 "      when some scans are not placed (the outputs are still written).\n"
                 "  kissm help [COMMAND]      this text, or a command's options (same as COMMAND --help)\n"
                 "  kissm --version           print the version\n"
                 "\n"
                 "Exit status: 0 success, 1 registration ran but the pose is not valid (batch: some pairs are\n"
                 "errors), 2 usage or input error.\n",
                 kissm_version_string());
}

int run(const std::vector<std::string> &args) {
    if (args.empty()) throw UsageError("missing command (try 'kissm --help')");
    const std::string &command = args[0];
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (command == "-h" || command == "--help" || command == "help") {
        if (rest.empty() || (command != "help")) {
            print_usage(stdout);
            return kExitOk;
        }
        if (rest[0] == "register") {
            print_register_help(stdout);
        } else if (rest[0] == "refine") {
            print_refine_help(stdout);
        } else if (rest[0] == "demo") {
            print_demo_help(stdout);
        } else if (rest[0] == "ground") {
            print_ground_help(stdout);
        } else if (rest[0] == "batch") {
            print_batch_help(stdout);
        } else if (rest[0] == "simulate") {
            print_simulate_help(stdout);
        } else if (rest[0] == "align") {
            print_align_help(stdout);
        } else {
            std::vector<std::string> commands;
            for (const auto &entry : command_helps()) commands.push_back(entry.first);
            throw UsageError("no help for unknown command '" + one_line(rest[0]) + "'" +
                             did_you_mean(rest[0], commands) + " (try 'kissm --help')");
        }
        return kExitOk;
    }
    if (command == "--version" || command == "-V" || command == "version") {
        std::printf("kissm %s\n", kissm_version_string());
        return kExitOk;
    }
    if (command == "register") return run_register(rest);
    if (command == "refine") return run_refine(rest);
    if (command == "demo") return run_demo(rest);
    if (command == "ground") return run_ground(rest);
    if (command == "batch") return run_batch(rest);
    if (command == "simulate") return run_simulate(rest);
    if (command == "align") return run_align(rest);
    std::vector<std::string> commands;
    for (const auto &entry : command_helps()) commands.push_back(entry.first);
    if (!command.empty() && command[0] == '-') {
        throw UsageError("unknown option '" + one_line(command) + "'" + did_you_mean(command, {"--help", "--version"}) +
                         " (try 'kissm --help')");
    }
    throw UsageError("unknown command '" + one_line(command) + "'" + did_you_mean(command, commands) +
                     " (try 'kissm --help')");
}

} // namespace
} // namespace kissm_cli

int main(int argc, char **argv) {
    const std::vector<std::string> args(argv + 1, argv + argc);
    try {
        return kissm_cli::run(args);
    } catch (const kissm_cli::UsageError &e) {
        std::fflush(stdout);
        std::fprintf(stderr, "kissm: %s\n", kissm_cli::one_line(e.what()).c_str());
    } catch (const std::bad_alloc &) {
        std::fflush(stdout);
        std::fprintf(stderr, "kissm: out of memory\n");
    } catch (const std::exception &e) {
        std::fflush(stdout);
        std::fprintf(stderr, "kissm: %s\n", kissm_cli::one_line(e.what()).c_str());
    }
    return kissm_cli::kExitUsage;
}
