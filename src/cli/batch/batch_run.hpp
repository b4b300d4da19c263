// SPDX-License-Identifier: MIT
// `kissm batch`'s run: each distinct cloud described once (kissm_features_compute), every pending pair
// registered from the features (kissm_register_features) by --jobs threads, each with its own matcher, and one
// JSON line appended per pair as it finishes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <kissm.h>

#include "batch_pairs.hpp"

namespace kissm_cli {

struct BatchRun {
    kissm_config config{}; // validated; every job's matcher is made from it
    int32_t source_format = KISSM_FORMAT_AUTO;
    int32_t target_format = KISSM_FORMAT_AUTO;
    std::string pairs_file; // relative cloud and gt paths are resolved against its folder
    bool has_gt_column = false;
    std::vector<PairRow> pending; // in the pairs file's order
    int32_t jobs = 1;
    bool progress = true;                       // the progress line on stderr
    std::string progress_label = "kissm batch"; // what starts it
    std::FILE *out = nullptr;
    std::string out_name; // for messages
};

struct BatchCounts {
    size_t valid = 0, invalid = 0, errors = 0;
};

// Runs the pending pairs and appends their lines to run.out, each flushed as its pair finishes (one pair's
// failure, such as an unreadable cloud, is that pair's "error" line). Throws UsageError when the results
// cannot be written or a matcher cannot be made.
BatchCounts run_batch_pairs(const BatchRun &run);

// The voxel of `--voxel auto` for a batch: kissm_suggest_voxel_size of every cloud `rows` name (read once here), so
// that any two of them match, as kissm.batch's "auto" does; unreadable clouds and clouds without a suggestion of
// their own are left to fail their pairs. 0 (each pair then fails) when no cloud is usable.
double batch_auto_voxel(const BatchRun &run, const std::vector<PairRow> &rows);

// The results line of one pair (with its final newline). The fields depend on the inputs only, never on
// timing, so that a pair's line is the same bytes at any --jobs and after --resume:
// pair, source, target, [gt,] status "ok" with the register --json fields but time_ms (valid, reason, ...,
// transform, ...) [and rotation_error_deg, translation_error_m against gt], or status "error", message,
// valid false, transform null.
std::string batch_line_ok(const PairRow &row, bool has_gt_column, const kissm_result &result, int32_t refine_mode,
                          const double *gt);
std::string batch_line_error(const PairRow &row, bool has_gt_column, const std::string &message);

} // namespace kissm_cli
