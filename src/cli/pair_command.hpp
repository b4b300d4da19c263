// SPDX-License-Identifier: MIT
// What `kissm register` and `kissm refine` share: their options (files, formats, voxel, threads, refinement
// settings, outputs), the configuration they make, and the run itself (read, register or refine, write the
// files, print the summary or the JSON object).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <kissm.h>

namespace kissm_cli {

enum class PairCommand { Register, Refine };

struct PairOptions {
    std::vector<std::string> files;
    int32_t source_format = KISSM_FORMAT_AUTO;
    int32_t target_format = KISSM_FORMAT_AUTO;
    bool have_voxel = false;
    double voxel = 0.0;
    int32_t threads = 0;
    int32_t min_inliers = -1;         // register only; -1: library default
    int32_t max_correspondences = -1; // register only; -1: library default
    // The validity rules' settings (register only: kissm_refine has no solver inliers to judge); unset ones
    // keep kissm_config_init's values and the library checks the ranges.
    bool have_max_rotation_uncertainty = false;
    double max_rotation_uncertainty = 0.0; // radians
    bool have_min_inlier_coverage = false;
    double min_inlier_coverage = 0.0;
    bool have_refine_min_inliers = false;
    int32_t refine_min_inliers = 0;
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
    bool have_refine_normal_radius = false;
    double refine_normal_radius_gain = 0.0;
    std::string initial; // refine only: the initial transform file
    std::string out_transform;
    std::string out_aligned;
    std::string out_topview;
};

// Parses a pair command's arguments into *opt. Returns false when it printed the help (-h, --help).
bool parse_pair_options(PairCommand command, const std::vector<std::string> &args, PairOptions *opt);
// kissm_config_init's defaults (the help shows them; nothing in the tool writes a default of its own).
kissm_config config_defaults();
// kissm_config_init's defaults with the options applied, checked by kissm_config_validate: a value out of
// range is a UsageError with the library's message, prefixed by the option that set the field.
kissm_config pair_config(PairCommand command, const PairOptions &opt);
// Reads the files, registers or refines, writes the output files, prints; returns the exit status.
int run_pair(PairCommand command, const PairOptions &opt);
// Both: parse_pair_options, then run_pair (or 0 after the help).
int run_pair_command(PairCommand command, const std::vector<std::string> &args);

// The help's blocks shared by both commands: input files, settings, refinement and output options.
void print_pair_input_help(std::FILE *out);
void print_refinement_help(std::FILE *out, PairCommand command, const kissm_config &defaults);
void print_pair_output_help(std::FILE *out);

} // namespace kissm_cli
