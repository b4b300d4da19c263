// SPDX-License-Identifier: MIT
#include "report.hpp"

#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "cli_args.hpp"
#include "pose_math.hpp"

namespace kissm_cli {
using namespace kissm_pose; // src/common/pose_math.hpp

void print_matrix(std::FILE *out, const double T[16], const char *indent) {
    for (int r = 0; r < 4; ++r) {
        std::fprintf(out, "%s[ %12.6f %12.6f %12.6f %12.6f ]\n", indent, T[4 * r], T[4 * r + 1], T[4 * r + 2],
                     T[4 * r + 3]);
    }
}

namespace {

void row2(std::FILE *out, const char *label, uint64_t a, uint64_t b) {
    std::fprintf(out, "  %-22s%11" PRIu64 " %11" PRIu64 "\n", label, a, b);
}

void row1(std::FILE *out, const char *label, uint64_t a) { std::fprintf(out, "  %-22s%11" PRIu64 "\n", label, a); }

} // namespace

bool refinement_ran(const kissm_result &r) {
    for (double v : r.information) {
        if (!std::isnan(v)) return true;
    }
    return false;
}

namespace {

// A number for the summary, "-" when it is NaN (not measured) and "unbounded" when infinite.
struct NumberText {
    char text[40];
};
NumberText number_text(double v, const char *format) {
    NumberText t{};
    if (std::isnan(v)) {
        std::snprintf(t.text, sizeof t.text, "-");
    } else if (std::isinf(v)) {
        std::snprintf(t.text, sizeof t.text, "unbounded");
    } else {
        std::snprintf(t.text, sizeof t.text, format, v);
    }
    return t;
}

void print_refinement(std::FILE *out, const kissm_result &r, ResultKind kind) {
    std::fprintf(out, "refinement: %d iterations, %s; %" PRIu64 " correspondences\n", r.refine_iterations,
                 r.refine_converged ? "converged" : "stopped at the iteration cap", r.num_refine_correspondences);
    // rmse is NaN when no correspondence was left; the inlier coverage needs the solver's inliers.
    std::fprintf(out, "  overlap %.4f, ", r.overlap);
    if (kind == ResultKind::Global)
        std::fprintf(out, "inlier coverage %s, ", number_text(r.inlier_coverage, "%.4f").text);
    std::fprintf(out, "rmse %s, condition %.4g\n", number_text(r.refine_rmse, "%.4g").text, r.refine_condition);
    if (r.degenerate) {
        std::fprintf(out, "  degenerate: %d free direction%s (rotation [rad], translation [m], source frame)\n",
                     r.num_weak_directions, r.num_weak_directions == 1 ? "" : "s");
        for (int i = 0; i < r.num_weak_directions; ++i) {
            const double *v = r.weak_directions + 6 * i;
            std::fprintf(out, "    (%.3f %.3f %.3f | %.3f %.3f %.3f)\n", v[0], v[1], v[2], v[3], v[4], v[5]);
        }
    }
    if (matrix_is_finite(r.coarse_transform) && matrix_is_finite(r.transform)) {
        std::fprintf(out, "  moved the %s pose by %.4f deg, %.4g\n", kind == ResultKind::Global ? "coarse" : "initial",
                     rotation_error_deg(r.coarse_transform, r.transform),
                     translation_error(r.coarse_transform, r.transform));
    }
}

} // namespace

void print_result_summary(std::FILE *out, const kissm_result &r, ResultKind kind) {
    const bool global = kind == ResultKind::Global;
    std::fprintf(out, "valid: %s", r.valid ? "yes" : "no");
    if (!r.valid) std::fprintf(out, " (reason: %s)", kissm_reason_string(r.reason));
    // The probability that the pose is within the success tolerance (docs/design/accuracy.md, "Confidence").
    std::fprintf(out, "; confidence %s\n", number_text(r.confidence, "%.3f").text);
    std::fprintf(out, "counts                       source      target\n");
    row2(out, "points", r.num_source_points, r.num_target_points);
    if (r.num_source_nonfinite || r.num_target_nonfinite) {
        row2(out, "non-finite (dropped)", r.num_source_nonfinite, r.num_target_nonfinite);
    }
    row2(out, "voxels", r.num_source_voxels, r.num_target_voxels);
    if (global) {
        // Voxels the suppression kept from becoming keypoints (all zero when it is off).
        if (r.num_source_suppressed || r.num_target_suppressed || r.time_suppression_ms > 0.0) {
            row2(out, "suppressed (ground)", r.num_source_suppressed, r.num_target_suppressed);
        }
        row2(out, "keypoints", r.num_source_keypoints, r.num_target_keypoints);
        row1(out, "initial matches", r.num_initial_correspondences);
        char label[64];
        std::snprintf(label, sizeof label, "pruned (max %" PRIu64 "-core)", r.max_core_number);
        row1(out, label, r.num_pruned_correspondences);
        row1(out, "rotation inliers", r.num_rotation_inliers);
        row1(out, "final inliers", r.num_final_inliers);
        std::fprintf(out, "inlier ratio: %.4f\n", r.inlier_ratio);
        if (std::isfinite(r.residual_rms)) {
            std::fprintf(out, "residual rms: %.4g (noise bound %.4g)\n", r.residual_rms, r.noise_bound);
        } else {
            std::fprintf(out, "residual rms: - (noise bound %.4g)\n", r.noise_bound);
        }
        // How well the inliers pin the solver's rotation down (radians in the JSON, degrees for people).
        std::fprintf(out, "rotation uncertainty: %s\n",
                     number_text(rad_to_deg(r.rotation_uncertainty), "%.4g deg").text);
        // The best distinct competing pose's support over this one's (0: one answer; 1: a repetitive scene).
        std::fprintf(out, "ambiguity: %s\n", number_text(r.ambiguity, "%.3f").text);
        // Only measured with rotation_dof = 1: how far the best free rotation on the inliers turns `up`.
        if (!std::isnan(r.tilt)) std::fprintf(out, "tilt: %s\n", number_text(rad_to_deg(r.tilt), "%.4g deg").text);
    }
    if (refinement_ran(r)) print_refinement(out, r, kind);
    if (global) {
        std::fprintf(out,
                     "time (ms): voxelize %.1f, features %.1f (suppression %.1f), matching %.1f, pruning %.1f, solver "
                     "%.1f, refine %.1f, total %.1f\n",
                     r.time_voxelize_ms, r.time_features_ms, r.time_suppression_ms, r.time_matching_ms,
                     r.time_pruning_ms, r.time_solver_ms, r.time_refine_ms, r.time_total_ms);
    } else {
        std::fprintf(out, "time (ms): voxelize %.1f, normals %.1f, refine %.1f, total %.1f\n", r.time_voxelize_ms,
                     r.time_features_ms, r.time_refine_ms, r.time_total_ms);
    }
}

void add_result_json(JsonWriter &json, const kissm_result &r, int32_t refine_mode, const double *initial_transform,
                     bool with_times) {
    json.field("valid", r.valid != 0);
    json.field("reason", kissm_reason_string(r.reason));
    json.field("reason_code", r.reason);
    if (initial_transform) json.field_matrix("initial_transform", initial_transform, 4, 4);
    json.field_matrix("transform", r.transform, 4, 4);
    json.field_matrix("rotation", r.rotation, 3, 3);
    json.field_vector("translation", r.translation, 3);
    json.field_matrix("coarse_transform", r.coarse_transform, 4, 4);
    json.field("refine", refine_mode_name(refine_mode));
    if (refinement_ran(r)) {
        json.field_matrix("information", r.information, 6, 6);
    } else {
        json.key("information");
        json.null();
    }
    json.field("overlap", r.overlap);
    json.field("refine_rmse", r.refine_rmse);
    json.field("refine_condition", r.refine_condition);
    json.field("degenerate", r.degenerate != 0);
    json.field_matrix("weak_directions", r.weak_directions, r.num_weak_directions, 6);
    json.field("inlier_coverage", r.inlier_coverage);
    json.field("refine_iterations", r.refine_iterations);
    json.field("refine_converged", r.refine_converged != 0);
    json.field("final_inliers", r.num_final_inliers);
    json.field("voxel_size_used", r.voxel_size_used);
    json.key("counts");
    json.begin_object();
    json.field("source_points", r.num_source_points);
    json.field("target_points", r.num_target_points);
    json.field("source_nonfinite", r.num_source_nonfinite);
    json.field("target_nonfinite", r.num_target_nonfinite);
    json.field("source_voxels", r.num_source_voxels);
    json.field("target_voxels", r.num_target_voxels);
    json.field("source_keypoints", r.num_source_keypoints);
    json.field("target_keypoints", r.num_target_keypoints);
    json.field("initial_correspondences", r.num_initial_correspondences);
    json.field("pruned_correspondences", r.num_pruned_correspondences);
    json.field("max_core_number", r.max_core_number);
    json.field("rotation_inliers", r.num_rotation_inliers);
    json.field("final_inliers", r.num_final_inliers);
    json.field("refine_correspondences", r.num_refine_correspondences);
    json.field("source_suppressed", r.num_source_suppressed);
    json.field("target_suppressed", r.num_target_suppressed);
    json.end_object();
    json.field("inlier_ratio", r.inlier_ratio);
    json.field("residual_rms", r.residual_rms);
    json.field("noise_bound", r.noise_bound);
    json.field_vector("inlier_extent", r.inlier_extent, 3);
    json.field("rotation_uncertainty", r.rotation_uncertainty);
    json.field("tilt", r.tilt);
    json.field("ambiguity", r.ambiguity);
    json.field("confidence", r.confidence);
    if (!with_times) return;
    json.key("time_ms");
    json.begin_object();
    json.field("voxelize", r.time_voxelize_ms);
    json.field("features", r.time_features_ms);
    json.field("suppression", r.time_suppression_ms);
    json.field("matching", r.time_matching_ms);
    json.field("pruning", r.time_pruning_ms);
    json.field("solver", r.time_solver_ms);
    json.field("refine", r.time_refine_ms);
    json.field("total", r.time_total_ms);
    json.end_object();
}

std::string library_error(int32_t status, const std::string &path) {
    const char *message = kissm_last_error_message();
    std::string text = (message && *message) ? message : kissm_status_string(status);
    // The tool already says which call and which file failed: drop a leading "kissm_function: " and
    // "path: " from the library's message.
    if (text.compare(0, 6, "kissm_") == 0) {
        size_t i = 6;
        while (i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) || text[i] == '_')) ++i;
        if (text.compare(i, 2, ": ") == 0) text.erase(0, i + 2);
    }
    if (!path.empty() && text.compare(0, path.size() + 2, path + ": ") == 0) text.erase(0, path.size() + 2);
    return one_line(text);
}

} // namespace kissm_cli
