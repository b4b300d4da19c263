// SPDX-License-Identifier: MIT
// What `kissm register` and `kissm refine` share: their options (files, formats, voxel, threads, refinement
// settings, outputs), the configuration they make, and the run itself (read, register or refine, write the
// files, print the summary or the JSON object).
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <kissm.h>

#include "commands.hpp"

namespace kissm_cli {

enum class PairCommand { Register, Refine };

class ArgCursor;

// The settings `register` and `ground` share: --preset (0 = none), applied to kissm_config_init's values
// first, then every option given explicitly, whatever the order on the command line (with a preset --voxel
// is optional: every preset gives one); and the ground model's and yaw solver's --suppression, --rotation-dof,
// --up, --sensor-height. Unset ones keep the preset's or kissm_config_init's values; the library checks the
// ranges.
struct GroundUpOptions {
    int32_t preset = 0;
    int32_t suppression = -1; // -1 = unset
    bool have_rotation_dof = false;
    int32_t rotation_dof = 0;
    bool have_up = false;
    double up[3] = {0.0, 0.0, 0.0};
    bool have_sensor_height = false;
    double sensor_height = 0.0;
};
// When the cursor stands on --preset, --up or --sensor-height (and, with `solver`, --suppression or
// --rotation-dof): reads its value into *opt and returns true.
bool take_ground_up_option(ArgCursor &cur, bool solver, GroundUpOptions *opt);
// kissm_config_init's defaults with opt.preset applied (a UsageError naming --preset when the library refuses
// it), the base the command's explicit options then change; apply_ground_up writes the others.
kissm_config config_with_preset(int32_t preset);
void apply_ground_up(const GroundUpOptions &opt, kissm_config *config);
// The last settings every command shares (--drop-nonfinite, -v), then kissm_config_validate: a value out of
// range is a UsageError with the library's message after the option that set the field.
kissm_config validated_config(kissm_config config, bool drop_nonfinite, bool verbose);
double elapsed_ms(std::chrono::steady_clock::time_point since);

struct PairOptions {
    std::vector<std::string> files;
    int32_t source_format = KISSM_FORMAT_AUTO;
    int32_t target_format = KISSM_FORMAT_AUTO;
    bool have_voxel = false;
    double voxel = 0.0;
    bool voxel_auto = false; // --voxel auto: the library's suggestion for the pair (voxel then reports it)
    int32_t threads = 0;
    bool have_threads = false;        // --threads given (batch's default is 1 per job, not all)
    int32_t min_inliers = -1;         // register only; -1: library default
    int32_t max_correspondences = -1; // register only; -1: library default
    // The validity rules' settings (register only: kissm_refine has no solver inliers to judge); unset ones
    // keep kissm_config_init's values and the library checks the ranges.
    bool have_max_rotation_uncertainty = false;
    double max_rotation_uncertainty = 0.0; // radians
    bool have_max_ambiguity = false;
    double max_ambiguity = 0.0;
    bool have_min_inlier_coverage = false;
    double min_inlier_coverage = 0.0;
    bool have_refine_min_inliers = false;
    int32_t refine_min_inliers = 0;
    GroundUpOptions ground_up; // register only
    bool drop_nonfinite = false;
    bool viewpoint_center = false;
    int32_t viewpoint_mode = -1; // --viewpoint, -1 = the default
    bool json = false;
    bool verbose = false;
    int32_t refine_mode = KISSM_REFINE_NONE; // the command's default until --refine
    // Refinement settings; unset ones keep kissm_config_init's values. Ranges are the library's to check.
    bool have_refine_iterations = false;
    int32_t refine_iterations = 0;
    bool have_refine_distance = false;
    double refine_distance = 0.0;
    bool have_min_overlap = false;
    double min_overlap = 0.0;
    // kissm_refine's rule and refinement too: the refined pose's least condition, and the radius (in voxels)
    // of the planes refinement aligns.
    bool have_min_refine_condition = false;
    double min_refine_condition = 0.0;
    bool have_max_refine_rmse = false; // and the refined clouds' largest residual, in voxels
    bool allow_degenerate = false;     // --allow-degenerate
    double max_refine_rmse_gain = 0.0;
    bool have_refine_normal_radius = false;
    double refine_normal_radius_gain = 0.0;
    std::string initial; // refine only: the initial transform file
    std::string out_transform;
    std::string out_aligned;
    std::string out_topview;
};

// When the cursor stands on one of the command's options (with_outputs: also --json and the --out-* files):
// reads it into *opt and returns true. Positional arguments and -h are the caller's.
bool take_pair_option(PairCommand command, ArgCursor &cur, bool with_outputs, PairOptions *opt);
// A UsageError "COMMAND needs --voxel V ..." unless --voxel or a --preset gave a voxel size.
void require_voxel(const char *command, const PairOptions &opt);
// Parses a pair command's arguments into *opt. Returns false when it printed the help (-h, --help).
bool parse_pair_options(PairCommand command, const std::vector<std::string> &args, PairOptions *opt);
// kissm_config_init's defaults (the help shows them; nothing in the tool writes a default of its own).
kissm_config config_defaults();
// The option that set the config field the library's message names, before that message ("invalid --up:
// config.up is ..."), or "invalid settings: ..." when no option set it.
std::string settings_error(int32_t status);
// kissm_config_init's defaults (with --preset first) with the options applied, checked by kissm_config_validate: a
// value out of range is a UsageError with the library's message, prefixed by the option that set the field.
kissm_config pair_config(PairCommand command, const PairOptions &opt);
// Reads the files, registers or refines, writes the output files, prints; returns the exit status.
int run_pair(PairCommand command, const PairOptions &opt);
// Reads a point file (`role` names it in the error: "cannot read source '...': ..."), a UsageError on failure.
CloudPtr read_cloud(const char *role, const std::string &path, int32_t format);
// The cloud's points view for the library's calls.
kissm_points points_of(const kissm_cloud *cloud, const char *role);
// Both: parse_pair_options, then run_pair (or 0 after the help).
int run_pair_command(PairCommand command, const std::vector<std::string> &args);

// Both commands' help, in one shape: `intro` (usage and what the command does), the input files, the
// command's own settings (printed by `settings` with kissm_config_init's defaults), refinement, outputs, then
// `exit_status`.
void print_pair_help(std::FILE *out, PairCommand command, const char *intro,
                     void (*settings)(std::FILE *out, const kissm_config &defaults), const char *exit_status);

} // namespace kissm_cli
