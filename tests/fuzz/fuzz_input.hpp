// SPDX-License-Identifier: MIT
// Turning fuzz bytes into a config, clouds and rigid (or deliberately not rigid) transforms. The first bytes
// pick the config, the rest become points as
// 16-bit integers scaled to a few tens of metres (so that most inputs reach the later stages instead of
// stopping at the voxel range check), with some bytes turned into NaN, infinities, huge values and
// duplicates. Every input maps to something; nothing here can fail.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "kissm.h"

namespace kissm_fuzz {

class Bytes {
public:
    Bytes(const std::uint8_t *data, std::size_t size) : data_(data), size_(size) {}
    std::uint8_t u8() { return pos_ < size_ ? data_[pos_++] : 0; }
    std::uint16_t u16() { // two statements: the operands of | are unsequenced, and compilers differ
        const unsigned lo = u8();
        const unsigned hi = u8();
        return static_cast<std::uint16_t>(lo | (hi << 8));
    }
    std::size_t left() const { return size_ - pos_; }

private:
    const std::uint8_t *data_;
    std::size_t size_, pos_ = 0;
};

// The refinement and validity settings come from the voxel byte's tens (v / 10): the mode (none, GICP,
// point-to-plane) and one of nine variants, one of them out of range. A voxel byte below 10 (every seed written before
// refinement existed) keeps the defaults, so old seeds decode as they always did.
inline void set_refinement(kissm_config &c, unsigned tens) {
    c.refine_mode = static_cast<int32_t>(tens % 3);
    switch ((tens / 3) % 9) {
    case 1: c.refine_max_iterations = 1; break;
    case 2: c.refine_max_distance_gain = 100.0, c.max_refine_rmse_gain = 1e-3; break; // all in reach, none close
    case 3: c.refine_kernel_gain = 1e-3; break;                                       // every residual an outlier
    case 4: // never converged by the test, only by the cap
        c.refine_rotation_epsilon = 0.0, c.refine_translation_epsilon_gain = 0.0, c.refine_max_iterations = 50;
        break;
    case 5: c.min_overlap = 1.0, c.max_ambiguity = 0.0; break; // every competing pose refuses a solved one
    case 6: c.refine_max_distance_gain = 0.05; break;          // hardly anything within reach
    case 7: c.refine_max_iterations = 0; break;                // out of range: kissm_create refuses it
    case 8: // the validity rules at their loosest: every direction but the strongest counts as weak (degenerate
            // results with their weak directions), and such poses may be valid
        c.max_rotation_uncertainty = 3.15, c.min_inlier_coverage = 0.0, c.refine_min_inliers = 3;
        c.min_overlap = 0.0, c.min_refine_condition = 1.0, c.allow_degenerate = 1, c.max_refine_rmse_gain = 100.0;
        c.max_ambiguity = 1.0;
        break;
    default: break;
    }
}

inline kissm_config make_config(Bytes &in) {
    kissm_config c;
    kissm_config_init(&c, sizeof c);
    static const double voxels[] = {0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 1e-9, 0.0, -1.0, 1e9};
    const std::uint8_t v = in.u8(), flags = in.u8(), gains = in.u8();
    c.voxel_size = voxels[v % 10];
    if (v >= 250) c.voxel_size = std::numeric_limits<double>::quiet_NaN();
    set_refinement(c, v / 10u);
    c.num_threads = 1 + (flags & 1);
    c.nonfinite_policy = (flags & 2) ? KISSM_NONFINITE_DROP : KISSM_NONFINITE_REJECT;
    // Bit 2 leaves the fixed viewpoint; which other mode, the gains byte says.
    static const int32_t other_modes[] = {KISSM_VIEWPOINT_CLOUD_CENTER, KISSM_VIEWPOINT_SIGN_FREE,
                                          KISSM_VIEWPOINT_LOCAL};
    c.viewpoint_mode = (flags & 4) ? other_modes[gains % 3] : KISSM_VIEWPOINT_FIXED;
    c.ratio_test = (flags & 8) ? 1.0 : 0.9;
    c.min_inliers = 3 + (flags >> 4);
    c.normal_radius_gain = 1.0 + (gains & 7) * 0.5;
    c.fpfh_radius_gain = c.normal_radius_gain + 1.5 + ((gains >> 3) & 7) * 0.5;
    c.max_correspondences = (gains >> 6) == 3 ? 0 : 3 + (gains >> 6) * 300; // 0: automatic
    // The ground-vehicle options: suppression, yaw only, the up direction (one zero: refused) and sensor height.
    const std::uint8_t ground = in.u8();
    c.suppression = (ground & 1) ? KISSM_SUPPRESS_GROUND : KISSM_SUPPRESS_NONE;
    c.rotation_dof = (ground & 2) ? 1 : 3;
    static const double ups[4][3] = {{0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}, {0.3, -0.2, 0.9}, {0.0, 0.0, 0.0}};
    for (int i = 0; i < 3; ++i) c.up[i] = ups[(ground >> 2) & 3][i];
    c.sensor_height = (ground >> 4) * 0.25;
    return c;
}

// count triples as float32 or float64 (in the kissm_points' own storage).
struct Cloud {
    std::vector<float> f;
    std::vector<double> d;
    kissm_points view() const {
        kissm_points p;
        std::memset(&p, 0, sizeof p);
        if (!d.empty()) {
            p.data = d.data(), p.count = d.size() / 3, p.scalar_type = KISSM_SCALAR_FLOAT64;
        } else {
            p.data = f.data(), p.count = f.size() / 3, p.scalar_type = KISSM_SCALAR_FLOAT32;
        }
        return p;
    }
};

inline double coordinate(Bytes &in, double scale) {
    const std::uint16_t raw = in.u16();
    switch (raw) { // a few special values
    case 0xFFFF: return std::numeric_limits<double>::quiet_NaN();
    case 0xFFFE: return std::numeric_limits<double>::infinity();
    case 0xFFFD: return -std::numeric_limits<double>::infinity();
    case 0xFFFC: return 1e30;
    case 0xFFFB: return -1e7;
    default: return (static_cast<double>(raw) - 32768.0) * scale;
    }
}

// A head byte (bit 0: float64; bit 1: 1 mm steps, else 0.1 mm times 1 + head / 4, up to ~200 m), a 16-bit
// point count, then the points: at most max_points and what the bytes left hold.
inline Cloud make_cloud(Bytes &in, std::size_t max_points) {
    Cloud c;
    const std::uint8_t head = in.u8();
    const bool as_double = head & 1;
    const double scale = (head & 2) ? 1e-3 : 1e-4 * static_cast<double>(1 + (head >> 2));
    std::size_t n = std::min<std::size_t>(in.u16(), max_points);
    n = std::min<std::size_t>(n, in.left() / 6);
    for (std::size_t i = 0; i < n; ++i) {
        const double x = coordinate(in, scale), y = coordinate(in, scale), z = coordinate(in, scale);
        if (as_double) {
            c.d.insert(c.d.end(), {x, y, z});
        } else {
            c.f.insert(c.f.end(), {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
        }
    }
    return c;
}

// A 4x4 row-major transform for kissm_refine: a kind byte, then what the kind needs. Kinds 0-5 are rigid
// (the identity; a rotation vector of three u16 at 1e-4 rad and a translation of three u16 at 1 mm; the same
// rounded to float and nudged by 3e-4, within the documented 1e-3); the others are what kissm_refine must
// refuse with KISSM_ERR_INVALID_ARGUMENT: NaN or an infinity at a chosen entry, a scaled, sheared or reflected
// rotation block, a wrong last row, a translation beyond 1e9. Returns whether the transform is acceptable.
inline bool make_transform(Bytes &in, double m[16]) {
    for (int i = 0; i < 16; ++i) m[i] = (i % 5 == 0) ? 1.0 : 0.0;
    const std::uint8_t kind = in.u8() % 13;
    if (kind == 0) return true;
    double w[3], t[3];
    for (double &x : w) x = (static_cast<double>(in.u16()) - 32768.0) * 1e-4;
    for (double &x : t) x = (static_cast<double>(in.u16()) - 32768.0) * 1e-3;
    const double angle = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (angle > 0.0) { // Rodrigues
        const double k[3] = {w[0] / angle, w[1] / angle, w[2] / angle}, c = std::cos(angle), s = std::sin(angle);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                const double cross = (i == j) ? 0.0 : (((j - i + 3) % 3 == 1) ? -k[3 - i - j] : k[3 - i - j]);
                m[4 * i + j] = (i == j ? c : 0.0) + (1.0 - c) * k[i] * k[j] + s * cross;
            }
    }
    for (int i = 0; i < 3; ++i) m[4 * i + 3] = t[i];
    const int at = in.u8() % 16;
    switch (kind) {
    case 5: // as a text file would give it: float digits and a small error
        for (int i = 0; i < 12; ++i) m[i] = static_cast<double>(static_cast<float>(m[i]));
        m[4 * (at % 3) + (at / 3) % 3] += 3e-4 * (static_cast<double>(at % 2) * 2.0 - 1.0);
        return true;
    case 6: m[at] = std::numeric_limits<double>::quiet_NaN(); return false;
    case 7: m[at] = (at % 2 ? -1.0 : 1.0) * std::numeric_limits<double>::infinity(); return false;
    case 8: // scaled
        for (int i = 0; i < 12; ++i)
            if (i % 4 != 3) m[i] *= 1.0 + 0.01 * (1 + at);
        return false;
    case 9: m[4 * (at % 3) + (at / 3 + 1) % 3] += 0.05; return false; // sheared
    case 10:                                                          // reflected: one column negated
        for (int i = 0; i < 3; ++i) m[4 * i + at % 3] = -m[4 * i + at % 3];
        return false;
    case 11: m[12 + at % 4] += 0.5; return false;                       // last row
    case 12: m[4 * (at % 3) + 3] = (at % 2 ? -2e9 : 2e9); return false; // beyond 1e9
    default: return true;
    }
}

// Statuses a registration may return for these inputs (never NULL_ARGUMENT, STRUCT_SIZE, IO, PARSE,
// UNSUPPORTED_FORMAT, FEATURES_MISMATCH (unless the caller mixes configs) or INTERNAL).
inline bool expected_status(int32_t st) {
    return st == KISSM_OK || st == KISSM_ERR_INVALID_ARGUMENT || st == KISSM_ERR_EMPTY_INPUT ||
           st == KISSM_ERR_TOO_FEW_POINTS || st == KISSM_ERR_NONFINITE || st == KISSM_ERR_VOXEL_RANGE ||
           st == KISSM_ERR_OUT_OF_MEMORY || st == KISSM_ERR_CANCELLED;
}

inline bool rigid_pose(const kissm_result &r) {
    for (double v : r.transform)
        if (!std::isfinite(v)) return false;
    const double *R = r.rotation;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double dot = 0.0;
            for (int k = 0; k < 3; ++k) dot += R[3 * i + k] * R[3 * j + k];
            if (std::fabs(dot - (i == j ? 1.0 : 0.0)) > 1e-9) return false;
        }
    const double det =
        R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
    return std::fabs(det - 1.0) < 1e-9 && r.transform[12] == 0.0 && r.transform[13] == 0.0 && r.transform[14] == 0.0 &&
           r.transform[15] == 1.0;
}

// The refinement's fields: "not run" (NaN, 0) or in range (information finite and symmetric with a
// non-negative diagonal, overlap and condition in [0, 1], iterations within the cap, the time in the total).
inline bool refine_fields_sane(const kissm_result &r, const kissm_config &c) {
    if (std::isnan(r.overlap)) {
        for (double v : r.information)
            if (!std::isnan(v)) return false;
        for (double v : r.weak_directions)
            if (!std::isnan(v)) return false;
        return std::isnan(r.refine_rmse) && std::isnan(r.refine_condition) && r.time_refine_ms == 0.0 &&
               r.num_refine_correspondences == 0 && r.refine_iterations == 0 && r.refine_converged == 0 &&
               r.degenerate == 0 && r.num_weak_directions == 0;
    }
    // Degenerate exactly when a direction is below the condition threshold; its rows unit vectors, the rest NaN.
    if (r.degenerate != (r.num_weak_directions > 0 ? 1 : 0) || r.num_weak_directions < 0 || r.num_weak_directions > 6)
        return false;
    if ((r.degenerate != 0) != !(r.refine_condition >= c.min_refine_condition)) return false;
    for (int i = 0; i < 6; ++i) {
        double norm2 = 0.0;
        for (int j = 0; j < 6; ++j) norm2 += r.weak_directions[6 * i + j] * r.weak_directions[6 * i + j];
        if (i < r.num_weak_directions ? !(std::fabs(norm2 - 1.0) < 1e-9) : !std::isnan(norm2)) return false;
    }
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
            if (!std::isfinite(r.information[6 * i + j]) || r.information[6 * i + j] != r.information[6 * j + i])
                return false;
    for (int i = 0; i < 6; ++i)
        if (r.information[7 * i] < 0.0) return false;
    if (!(r.overlap >= 0.0 && r.overlap <= 1.0 && r.refine_condition >= 0.0 && r.refine_condition <= 1.0)) return false;
    if (r.num_refine_correspondences > 0 ? !(r.refine_rmse >= 0.0 && std::isfinite(r.refine_rmse))
                                         : !std::isnan(r.refine_rmse))
        return false;
    if (r.refine_iterations < 0 || r.refine_iterations > c.refine_max_iterations) return false;
    if (r.refine_converged != 0 && r.refine_converged != 1) return false;
    if (r.num_refine_correspondences > r.num_source_voxels) return false;
    // A valid refined pose passed the refined rule's dense part (docs/refinement.md).
    if (r.valid && (r.num_refine_correspondences < 6 || !(r.overlap >= c.min_overlap) ||
                    (!c.allow_degenerate && !(r.refine_condition >= c.min_refine_condition)) ||
                    r.refine_converged != 1 || !(r.refine_rmse <= c.max_refine_rmse_gain * r.voxel_size_used)))
        return false;
    return r.time_refine_ms >= 0.0 && r.time_total_ms >= r.time_refine_ms;
}

// A valid registration has a finite transform whose rotation is orthonormal with det +1 and at least 3
// final inliers; an invalid one reports why; either way the refinement's fields are sane.
inline bool result_sane(const kissm_result &r, const kissm_config &c) {
    if (!refine_fields_sane(r, c)) return false;
    // The voxel used: the config's, or under voxel_size 0 (automatic) a suggestion, > 0 and finite.
    if (c.voxel_size != 0.0 ? r.voxel_size_used != c.voxel_size
                            : !(r.voxel_size_used > 0.0 && std::isfinite(r.voxel_size_used)))
        return false;
    // The ambiguity: in [0, 1] when the solver found a pose (its rotation uncertainty is then a number), else NaN.
    if (std::isnan(r.rotation_uncertainty) ? !std::isnan(r.ambiguity) : !(r.ambiguity >= 0.0 && r.ambiguity <= 1.0))
        return false;
    // The confidence: in [0, 1], 0 without a pose.
    if (!(r.confidence >= 0.0 && r.confidence <= 1.0)) return false;
    if (!std::isfinite(r.transform[0]) && r.confidence != 0.0) return false;
    if (!r.valid) return r.reason != KISSM_REASON_NONE && r.reason <= KISSM_REASON_AMBIGUOUS;
    if (!rigid_pose(r) || r.num_final_inliers < 3 || !(r.ambiguity <= c.max_ambiguity)) return false;
    // Valid with refinement: its inliers' part of the rule too; without: the rotation pinned down.
    if (!std::isnan(r.overlap))
        return r.num_final_inliers >= static_cast<std::uint64_t>(c.refine_min_inliers) &&
               r.inlier_coverage >= c.min_inlier_coverage;
    return r.num_final_inliers >= static_cast<std::uint64_t>(c.min_inliers) &&
           r.rotation_uncertainty <= c.max_rotation_uncertainty;
}

// A refinement from the caller's pose (kissm_refine, kissm_refine_features) always ran: valid, or
// LOW_OVERLAP / UNCONSTRAINED / UNCERTAIN_ROTATION / NOT_CONVERGED / LOOSE_ALIGNMENT / LOOSE_AND_WEAK, with a rigid
// pose either way
// and no solver numbers (no rotation uncertainty, coverage or ambiguity);
// coarse_transform is the initial transform made rigid, so within 1e-3 of it.
inline bool refine_result_sane(const kissm_result &r, const kissm_config &c, const double initial[16]) {
    if (!refine_fields_sane(r, c) || std::isnan(r.overlap) || !rigid_pose(r)) return false;
    if (!r.valid && r.reason != KISSM_REASON_LOW_OVERLAP && r.reason != KISSM_REASON_UNCONSTRAINED &&
        r.reason != KISSM_REASON_UNCERTAIN_ROTATION && r.reason != KISSM_REASON_NOT_CONVERGED &&
        r.reason != KISSM_REASON_LOOSE_ALIGNMENT && r.reason != KISSM_REASON_LOOSE_AND_WEAK)
        return false;
    if (!std::isnan(r.rotation_uncertainty) || !std::isnan(r.inlier_coverage) || !std::isnan(r.ambiguity)) return false;
    if (!(r.confidence >= 0.0 && r.confidence <= 1.0)) return false;
    if (r.valid && r.reason != KISSM_REASON_NONE) return false;
    for (int i = 0; i < 16; ++i)
        if (!(std::fabs(r.coarse_transform[i] - initial[i]) <= 1e-3 * (1.0 + std::fabs(initial[i])))) return false;
    return r.num_final_inliers == 0 && r.num_initial_correspondences == 0;
}

// What a failed call leaves: no pose, nothing refined.
inline bool result_reset(const kissm_result &r) {
    if (r.valid != 0) return false;
    for (double v : r.transform)
        if (!std::isnan(v)) return false;
    for (double v : r.coarse_transform)
        if (!std::isnan(v)) return false;
    return std::isnan(r.overlap) && std::isnan(r.rotation_uncertainty) && std::isnan(r.inlier_coverage) &&
           std::isnan(r.confidence) && r.num_refine_correspondences == 0 && r.refine_iterations == 0;
}

inline bool same_bits(const double *a, const double *b, std::size_t n) { return std::memcmp(a, b, n * sizeof *a) == 0; }

inline bool same_result(const kissm_result &a, const kissm_result &b) {
    // Everything but the timings.
    return a.valid == b.valid && a.reason == b.reason && same_bits(a.transform, b.transform, 16) &&
           same_bits(a.coarse_transform, b.coarse_transform, 16) && same_bits(a.information, b.information, 36) &&
           same_bits(&a.overlap, &b.overlap, 1) && same_bits(&a.refine_rmse, &b.refine_rmse, 1) &&
           same_bits(&a.refine_condition, &b.refine_condition, 1) &&
           same_bits(&a.rotation_uncertainty, &b.rotation_uncertainty, 1) &&
           same_bits(&a.inlier_coverage, &b.inlier_coverage, 1) && same_bits(&a.ambiguity, &b.ambiguity, 1) &&
           same_bits(&a.confidence, &b.confidence, 1) && a.num_refine_correspondences == b.num_refine_correspondences &&
           a.refine_iterations == b.refine_iterations && a.refine_converged == b.refine_converged &&
           a.num_final_inliers == b.num_final_inliers &&
           a.num_initial_correspondences == b.num_initial_correspondences &&
           a.num_source_voxels == b.num_source_voxels && a.num_target_voxels == b.num_target_voxels;
}

} // namespace kissm_fuzz
