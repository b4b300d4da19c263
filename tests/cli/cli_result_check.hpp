// SPDX-License-Identifier: MIT
// Checks of the tool's JSON against the CLI JSON contract (keys, order, types) and against the library's own
// result for the same call, bit for bit; and the library call itself (the same files, settings and entry point
// as the tool), for cli_test.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_test_util.hpp"
#include "harness.h"

namespace cli_test {

// The top-level keys of `kissm register --json` in the contract's order; `kissm refine` adds
// "initial_transform" just before "transform".
inline std::vector<std::string> contract_keys(bool refine_command) {
    std::vector<std::string> keys = {"version", "source", "target", "voxel_size",
                                     "threads", "valid",  "reason", "reason_code"};
    if (refine_command) keys.push_back("initial_transform");
    for (const char *k : {"transform",
                          "rotation",
                          "translation",
                          "coarse_transform",
                          "refine",
                          "information",
                          "overlap",
                          "refine_rmse",
                          "refine_condition",
                          "degenerate",
                          "weak_directions",
                          "inlier_coverage",
                          "refine_iterations",
                          "refine_converged",
                          "final_inliers",
                          "voxel_size_used",
                          "counts",
                          "inlier_ratio",
                          "residual_rms",
                          "noise_bound",
                          "inlier_extent",
                          "rotation_uncertainty",
                          "tilt",
                          "ambiguity",
                          "confidence",
                          "time_ms",
                          "read_ms"}) {
        keys.push_back(k);
    }
    return keys;
}

inline const std::vector<std::string> &contract_count_keys() {
    static const std::vector<std::string> keys = {
        "source_points",           "target_points",          "source_nonfinite",  "target_nonfinite",
        "source_voxels",           "target_voxels",          "source_keypoints",  "target_keypoints",
        "initial_correspondences", "pruned_correspondences", "max_core_number",   "rotation_inliers",
        "final_inliers",           "refine_correspondences", "source_suppressed", "target_suppressed"};
    return keys;
}

inline const std::vector<std::string> &contract_time_keys() {
    static const std::vector<std::string> keys = {"voxelize", "features", "suppression", "matching",
                                                  "pruning",  "solver",   "refine",      "total"};
    return keys;
}

inline std::string joined(const std::vector<std::string> &words) {
    std::string out;
    for (const std::string &w : words) out += (out.empty() ? "" : ",") + w;
    return out;
}

inline bool is_number_or_null(const Json &v) { return v.is(Json::Type::Number) || v.is(Json::Type::Null); }

// Keys in order and the type of every value, for both commands.
inline void check_contract(const Json &j, bool refine_command, const char *what) {
    using T = Json::Type;
    CHECK_MSG(j.is(T::Object), "%s: not a JSON object", what);
    CHECK_MSG(j.keys() == contract_keys(refine_command), "%s: keys\n  %s\nexpected\n  %s", what,
              joined(j.keys()).c_str(), joined(contract_keys(refine_command)).c_str());
    CHECK_MSG(j.at("counts").keys() == contract_count_keys(), "%s: counts keys %s", what,
              joined(j.at("counts").keys()).c_str());
    CHECK_MSG(j.at("time_ms").keys() == contract_time_keys(), "%s: time_ms keys %s", what,
              joined(j.at("time_ms").keys()).c_str());
    CHECK_MSG(j.at("valid").is(T::Bool) && j.at("refine_converged").is(T::Bool) && j.at("degenerate").is(T::Bool),
              "%s: valid/refine_converged/degenerate", what);
    // One row of 6 numbers per free direction, none unless degenerate.
    const Json &weak = j.at("weak_directions");
    CHECK_MSG(weak.is(T::Array) && weak.items.size() <= 6 && weak.is_matrix(weak.items.size(), 6, false) &&
                  (weak.items.empty() != j.at("degenerate").boolean),
              "%s: weak_directions", what);
    CHECK_MSG(j.at("reason").is(T::String) && j.at("refine").is(T::String), "%s: reason/refine", what);
    CHECK_MSG(j.at("reason_code").is(T::Number) && j.at("refine_iterations").is(T::Number) &&
                  j.at("final_inliers").is(T::Number),
              "%s: integer fields", what);
    for (const char *m : {"transform", "coarse_transform"}) {
        CHECK_MSG(j.at(m).is_matrix(4, 4, true), "%s: %s is not 4x4", what, m);
    }
    if (refine_command) CHECK_MSG(j.at("initial_transform").is_matrix(4, 4, false), "%s: initial_transform", what);
    CHECK_MSG(j.at("rotation").is_matrix(3, 3, true), "%s: rotation", what);
    const Json &info = j.at("information");
    CHECK_MSG(info.is(T::Null) || info.is_matrix(6, 6, false), "%s: information is neither null nor 6x6", what);
    for (const char *k : {"overlap", "refine_rmse", "refine_condition", "inlier_coverage", "inlier_ratio",
                          "residual_rms", "noise_bound", "rotation_uncertainty", "tilt", "ambiguity", "confidence"}) {
        CHECK_MSG(is_number_or_null(j.at(k)), "%s: %s is not a number or null", what, k);
    }
    for (const std::string &k : contract_count_keys()) {
        CHECK_MSG(j.at("counts").at(k).is(T::Number), "%s: counts.%s", what, k.c_str());
    }
    for (const std::string &k : contract_time_keys()) {
        CHECK_MSG(j.at("time_ms").at(k).is(T::Number), "%s: time_ms.%s", what, k.c_str());
    }
}

// Same bits, or both NaN (the JSON's null).
inline bool same_double(double a, double b) {
    return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
}

// A JSON number against the library's double: the same bits, or null for NaN and for the infinities (which
// the writer also prints as null; rotation_uncertainty is +inf without inliers).
inline void check_scalar(const Json &v, double want, const char *what, const char *key) {
    if (std::isfinite(want)) {
        CHECK_MSG(v.is(Json::Type::Number) && same_double(v.as_double(), want), "%s: %s is %s, the library's %.17g",
                  what, key, v.text.c_str(), want);
    } else {
        CHECK_MSG(v.is(Json::Type::Null), "%s: %s is %s, expected null for the library's %g", what, key, v.text.c_str(),
                  want);
    }
}

inline void check_doubles(const std::vector<double> &got, const double *want, size_t n, const char *what,
                          const char *key) {
    CHECK_MSG(got.size() == n, "%s: %s has %zu numbers, expected %zu", what, key, got.size(), n);
    for (size_t i = 0; i < n && i < got.size(); ++i) {
        CHECK_MSG(same_double(got[i], want[i]), "%s: %s[%zu] is %.17g, the library's %.17g", what, key, i, got[i],
                  want[i]);
    }
}

inline void check_count(const Json &v, uint64_t want, const char *what, const char *key) {
    CHECK_MSG(v.is(Json::Type::Number) && v.text == std::to_string(want), "%s: %s is %s, the library's %llu", what, key,
              v.text.c_str(), static_cast<unsigned long long>(want));
}

// Every result field the JSON holds equals the library's, bit for bit (null for NaN; "information": null
// exactly when all of it is NaN).
inline void check_matches_library(const Json &j, const kissm_result &r, const char *what) {
    CHECK_MSG(j.at("valid").boolean == (r.valid != 0), "%s: valid", what);
    CHECK_MSG(j.at("reason").text == kissm_reason_string(r.reason), "%s: reason", what);
    check_count(j.at("reason_code"), static_cast<uint64_t>(r.reason), what, "reason_code");
    check_doubles(j.at("transform").flat(), r.transform, 16, what, "transform");
    check_doubles(j.at("rotation").flat(), r.rotation, 9, what, "rotation");
    check_doubles(j.at("translation").flat(), r.translation, 3, what, "translation");
    check_doubles(j.at("coarse_transform").flat(), r.coarse_transform, 16, what, "coarse_transform");
    bool all_nan = true;
    for (double v : r.information) all_nan = all_nan && std::isnan(v);
    if (all_nan) {
        CHECK_MSG(j.at("information").is(Json::Type::Null), "%s: information should be null", what);
    } else {
        check_doubles(j.at("information").flat(), r.information, 36, what, "information");
    }
    const struct {
        const char *key;
        double value;
    } scalars[] = {{"overlap", r.overlap},
                   {"refine_rmse", r.refine_rmse},
                   {"refine_condition", r.refine_condition},
                   {"inlier_coverage", r.inlier_coverage},
                   {"inlier_ratio", r.inlier_ratio},
                   {"residual_rms", r.residual_rms},
                   {"noise_bound", r.noise_bound},
                   {"rotation_uncertainty", r.rotation_uncertainty},
                   {"tilt", r.tilt},
                   {"ambiguity", r.ambiguity},
                   {"confidence", r.confidence}};
    for (const auto &s : scalars) check_scalar(j.at(s.key), s.value, what, s.key);
    check_doubles(j.at("inlier_extent").flat(), r.inlier_extent, 3, what, "inlier_extent");
    CHECK_MSG(j.at("degenerate").boolean == (r.degenerate != 0), "%s: degenerate", what);
    check_doubles(j.at("weak_directions").flat(), r.weak_directions, static_cast<size_t>(6 * r.num_weak_directions),
                  what, "weak_directions");
    check_count(j.at("refine_iterations"), static_cast<uint64_t>(r.refine_iterations), what, "refine_iterations");
    CHECK_MSG(j.at("refine_converged").boolean == (r.refine_converged != 0), "%s: refine_converged", what);
    check_count(j.at("final_inliers"), r.num_final_inliers, what, "final_inliers");
    const uint64_t counts[] = {
        r.num_source_points,           r.num_target_points,          r.num_source_nonfinite,  r.num_target_nonfinite,
        r.num_source_voxels,           r.num_target_voxels,          r.num_source_keypoints,  r.num_target_keypoints,
        r.num_initial_correspondences, r.num_pruned_correspondences, r.max_core_number,       r.num_rotation_inliers,
        r.num_final_inliers,           r.num_refine_correspondences, r.num_source_suppressed, r.num_target_suppressed};
    const std::vector<std::string> &keys = contract_count_keys();
    for (size_t i = 0; i < keys.size(); ++i) check_count(j.at("counts").at(keys[i]), counts[i], what, keys[i].c_str());
}

// The library's result for the tool's call: the same files (through kissm_read_points), voxel size and
// refinement mode, every other setting at its default; kissm_refine when initial is given.
// adjust, when given, changes the config further (the tool's other options) after voxel and refine mode.
inline bool library_result(const std::string &source, const std::string &target, double voxel, int32_t refine_mode,
                           const double *initial, kissm_result *result,
                           const std::function<void(kissm_config &)> &adjust = {}) {
    kissm_cloud *clouds[2] = {nullptr, nullptr};
    kissm_matcher *matcher = nullptr;
    bool ok = kissm_read_points(source.c_str(), KISSM_FORMAT_AUTO, &clouds[0]) == KISSM_OK &&
              kissm_read_points(target.c_str(), KISSM_FORMAT_AUTO, &clouds[1]) == KISSM_OK;
    kissm_points points[2] = {};
    kissm_config config{};
    ok = ok && kissm_cloud_points(clouds[0], &points[0]) == KISSM_OK &&
         kissm_cloud_points(clouds[1], &points[1]) == KISSM_OK && kissm_config_init(&config, sizeof config) == KISSM_OK;
    config.voxel_size = voxel;
    config.refine_mode = refine_mode;
    if (adjust) adjust(config);
    ok = ok && kissm_create(&config, &matcher) == KISSM_OK;
    result->struct_size = sizeof *result;
    if (ok) {
        ok = (initial ? kissm_refine(matcher, &points[0], &points[1], initial, result)
                      : kissm_register(matcher, &points[0], &points[1], result)) == KISSM_OK;
    }
    if (!ok) std::fprintf(stderr, "library call failed: %s\n", kissm_last_error_message());
    kissm_destroy(matcher);
    kissm_cloud_destroy(clouds[0]);
    kissm_cloud_destroy(clouds[1]);
    return ok;
}

} // namespace cli_test
