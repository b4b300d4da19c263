// SPDX-License-Identifier: MIT
// Turning fuzz bytes into a config and clouds. The first bytes pick the config, the rest become points as
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

inline kissm_config make_config(Bytes &in) {
    kissm_config c;
    kissm_config_init(&c, sizeof c);
    static const double voxels[] = {0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 1e-9, 0.0, -1.0, 1e9};
    const std::uint8_t v = in.u8(), flags = in.u8(), gains = in.u8();
    c.voxel_size = voxels[v % 10];
    if (v >= 250) c.voxel_size = std::numeric_limits<double>::quiet_NaN();
    c.num_threads = 1 + (flags & 1);
    c.nonfinite_policy = (flags & 2) ? KISSM_NONFINITE_DROP : KISSM_NONFINITE_REJECT;
    c.viewpoint_mode = (flags & 4) ? KISSM_VIEWPOINT_CLOUD_CENTER : KISSM_VIEWPOINT_FIXED;
    c.ratio_test = (flags & 8) ? 1.0 : 0.9;
    c.min_inliers = 3 + (flags >> 4);
    c.normal_radius_gain = 1.0 + (gains & 7) * 0.5;
    c.fpfh_radius_gain = c.normal_radius_gain + 1.5 + ((gains >> 3) & 7) * 0.5;
    c.max_correspondences = 3 + (gains >> 6) * 300;
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

// Statuses a registration may return for these inputs (never NULL_ARGUMENT, STRUCT_SIZE, IO, PARSE,
// UNSUPPORTED_FORMAT, FEATURES_MISMATCH (unless the caller mixes configs) or INTERNAL).
inline bool expected_status(int32_t st) {
    return st == KISSM_OK || st == KISSM_ERR_INVALID_ARGUMENT || st == KISSM_ERR_EMPTY_INPUT ||
           st == KISSM_ERR_TOO_FEW_POINTS || st == KISSM_ERR_NONFINITE || st == KISSM_ERR_VOXEL_RANGE ||
           st == KISSM_ERR_OUT_OF_MEMORY || st == KISSM_ERR_CANCELLED;
}

// A valid result has a finite transform whose rotation is orthonormal with det +1; an invalid one reports why.
inline bool result_sane(const kissm_result &r) {
    if (!r.valid) return r.reason != KISSM_REASON_NONE;
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
    return std::fabs(det - 1.0) < 1e-9 && r.num_final_inliers >= 3;
}

inline bool same_result(const kissm_result &a, const kissm_result &b) {
    // Everything but the timings.
    return a.valid == b.valid && a.reason == b.reason &&
           std::memcmp(a.transform, b.transform, sizeof a.transform) == 0 &&
           a.num_final_inliers == b.num_final_inliers &&
           a.num_initial_correspondences == b.num_initial_correspondences &&
           a.num_source_voxels == b.num_source_voxels && a.num_target_voxels == b.num_target_voxels;
}

} // namespace kissm_fuzz
