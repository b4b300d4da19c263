// SPDX-License-Identifier: MIT
#include "loop_candidates.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

KISSM_DETAIL_BEGIN

namespace {

// a @ b for row-major 4x4s as numpy's matmul computes them here (OpenBLAS's dgemm kernel: each entry a fused
// multiply-add chain over the inner index, starting from 0).
void matmul_like_numpy(const double a[16], const double b[16], double out[16]) {
    double c[16];
    for (int r = 0; r < 4; ++r) {
        for (int col = 0; col < 4; ++col) {
            double s = 0.0;
            for (int m = 0; m < 4; ++m) s = std::fma(a[4 * r + m], b[4 * m + col], s);
            c[4 * r + col] = s;
        }
    }
    std::copy(c, c + 16, out);
}

void set_identity(double pose[16]) {
    for (int i = 0; i < 16; ++i) pose[i] = i % 5 == 0 ? 1.0 : 0.0;
}

} // namespace

ScanPlaces dead_reckoned(const std::vector<const double *> &steps, std::size_t scans) {
    ScanPlaces d;
    d.positions.assign(3 * scans, 0.0);
    d.path.assign(scans, 0.0);
    d.piece.assign(scans, 0);
    d.poses.assign(16 * scans, 0.0);
    double pose[16];
    set_identity(pose);
    if (scans > 0) std::copy(pose, pose + 16, d.poses.begin());
    for (std::size_t k = 0; k + 1 < scans; ++k) {
        const double *step = k < steps.size() ? steps[k] : nullptr;
        if (step) {
            matmul_like_numpy(pose, step, pose);
            const double x = step[3], y = step[7], z = step[11];
            d.path[k + 1] = d.path[k] + std::sqrt(x * x + y * y + z * z);
            d.piece[k + 1] = d.piece[k];
        } else {
            set_identity(pose);
            d.piece[k + 1] = d.piece[k] + 1;
        }
        for (std::size_t i = 0; i < 3; ++i) d.positions[3 * (k + 1) + i] = pose[4 * i + 3];
        std::copy(pose, pose + 16, d.poses.begin() + static_cast<std::ptrdiff_t>(16 * (k + 1)));
    }
    return d;
}

ScanPlaces prior_places(const double *poses, std::size_t scans) {
    ScanPlaces d;
    d.positions.assign(3 * scans, 0.0);
    d.path.assign(scans, 0.0);
    d.piece.assign(scans, 0);
    for (std::size_t k = 0; k < scans; ++k) {
        const double *m = poses + 16 * k;
        const bool known = std::isfinite(m[3]) && std::isfinite(m[7]) && std::isfinite(m[11]);
        for (std::size_t i = 0; i < 3; ++i)
            d.positions[3 * k + i] = known ? m[4 * i + 3] : std::numeric_limits<double>::quiet_NaN();
    }
    return d;
}

std::vector<ScanPair> loop_candidates(const ScanPlaces &where, double radius, std::size_t gap, std::size_t per_scan,
                                      double drift) {
    const std::size_t n = where.path.size();
    std::vector<std::uint8_t> known(n);
    for (std::size_t k = 0; k < n; ++k) {
        const double *p = &where.positions[3 * k];
        known[k] = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    }
    std::vector<ScanPair> out;
    if (gap == 0 || per_scan == 0) return out;
    std::vector<std::pair<double, std::size_t>> near;
    for (std::size_t j = gap; j < n; ++j) {
        if (!known[j]) continue;
        const double *pj = &where.positions[3 * j];
        near.clear();
        for (std::size_t i = 0; i + gap <= j; ++i) {
            const double *pi = &where.positions[3 * i];
            const double dx = pi[0] - pj[0], dy = pi[1] - pj[1], dz = pi[2] - pj[2];
            const double distance = std::sqrt(dx * dx + dy * dy + dz * dz);
            const double allowed = radius + drift * std::fabs(where.path[j] - where.path[i]);
            if (known[i] && where.piece[i] == where.piece[j] && distance <= allowed) near.push_back({distance, i});
        }
        append_nearest(near, per_scan, j, out);
    }
    return out;
}

void append_nearest(std::vector<std::pair<double, std::size_t>> &near, std::size_t per_scan, std::size_t j,
                    std::vector<ScanPair> &out) {
    if (near.size() > per_scan) {
        std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(per_scan), near.end());
        near.resize(per_scan);
    }
    std::sort(near.begin(), near.end(), [](const auto &a, const auto &b) { return a.second < b.second; });
    for (const auto &c : near) out.push_back({j, c.second});
}

KISSM_DETAIL_END
