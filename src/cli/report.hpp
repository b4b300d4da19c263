// SPDX-License-Identifier: MIT
// Presenting a kissm_result: the human summary, the JSON fields, and the transform file.
#pragma once

#include <cstdio>
#include <string>

#include <kissm.h>

#include "json_writer.hpp"

namespace kissm_cli {

// "  [ a b c d ]" rows with fixed precision, for people.
void print_matrix(std::FILE *out, const double T[16], const char *indent);
// Valid, reason, counts per stage, inlier ratio, residual, per-stage times.
void print_result_summary(std::FILE *out, const kissm_result &result);
// Adds the result's fields to the open JSON object: valid, reason, reason_code, transform, rotation,
// translation, final_inliers, counts, inlier_ratio, residual_rms, noise_bound, inlier_extent, time_ms.
void add_result_json(JsonWriter &json, const kissm_result &result);

// Four lines of four "%.17g" numbers. Returns false and sets *error on failure.
bool write_transform_file(const std::string &path, const double T[16], std::string *error);

// The library's message for the last failure on this thread (or the status string when it is empty),
// without a leading "kissm_function: " or "path: ", which the caller's own message already gives.
std::string library_error(int32_t status, const std::string &path = std::string());

} // namespace kissm_cli
