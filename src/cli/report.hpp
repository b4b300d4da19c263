// SPDX-License-Identifier: MIT
// Presenting a kissm_result: the human summary and the JSON fields.
#pragma once

#include <cstdio>
#include <string>

#include <kissm.h>

#include "json_writer.hpp"

namespace kissm_cli {

// Which call made the result: a global registration (kissm_register) or a refinement from a given pose
// (kissm_refine), whose coarse_transform is that pose and whose descriptor and solver fields are empty.
enum class ResultKind { Global, Refine };

// "  [ a b c d ]" rows with fixed precision, for people.
void print_matrix(std::FILE *out, const double T[16], const char *indent);
// True when refinement ran, i.e. the library filled kissm_result.information (it leaves all of it NaN
// otherwise). The JSON writes "information": null exactly when this is false.
bool refinement_ran(const kissm_result &result);
// Valid, reason, counts per stage, inlier ratio, residual, rotation uncertainty (degrees), the refinement's
// numbers when it ran (how far it moved the coarse or initial pose, overlap, inlier coverage, rmse,
// condition, iterations), per-stage times.
void print_result_summary(std::FILE *out, const kissm_result &result, ResultKind kind);
// Adds the result's fields to the open JSON object, in the order of the CLI JSON contract (src/cli/README.md):
// valid, reason, reason_code, [initial_transform,] transform, rotation, translation, coarse_transform,
// refine, information, overlap, refine_rmse, refine_condition, inlier_coverage, refine_iterations,
// refine_converged, final_inliers, counts (... refine_correspondences, source_suppressed, target_suppressed),
// inlier_ratio, residual_rms, noise_bound, inlier_extent, rotation_uncertainty, tilt, ambiguity, confidence, time_ms
// (voxelize, features, suppression, matching, pruning, solver, refine, total). refine_mode: the config's KISSM_REFINE_*
// (the mode used). initial_transform: kissm_refine's, or null. with_times false leaves time_ms out, so that the same
// pair gives the same bytes on every run (batch).
void add_result_json(JsonWriter &json, const kissm_result &result, int32_t refine_mode,
                     const double *initial_transform = nullptr, bool with_times = true);

// The library's message for the last failure on this thread (or the status string when it is empty),
// without a leading "kissm_function: " or "path: ", which the caller's own message already gives.
std::string library_error(int32_t status, const std::string &path = std::string());

} // namespace kissm_cli
