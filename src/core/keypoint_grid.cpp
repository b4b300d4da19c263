// SPDX-License-Identifier: MIT
#include "keypoint_grid.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

KISSM_DETAIL_BEGIN

namespace {

constexpr std::int64_t kBias = std::int64_t(1) << 30;

bool column_of(double v, double inverse, std::int64_t &out) {
    const double c = std::floor(v * inverse);
    if (!(std::abs(c) < static_cast<double>(kBias - 2))) return false; // NaN fails too
    out = static_cast<std::int64_t>(c);
    return true;
}

std::uint64_t key_of(std::int64_t x, std::int64_t y) {
    return (static_cast<std::uint64_t>(x + kBias) << 32) | static_cast<std::uint64_t>(y + kBias);
}

} // namespace

KeypointGrid::KeypointGrid(const std::vector<Vec3f> &points, const std::vector<std::uint32_t> &keypoint, double column)
    : inverse_(1.0 / column) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
    keyed.reserve(keypoint.size());
    for (std::size_t k = 0; k < keypoint.size(); ++k) {
        const Vec3f &p = points[keypoint[k]];
        std::int64_t x, y;
        if (column_of(p[0], inverse_, x) && column_of(p[1], inverse_, y) && std::isfinite(p[2]))
            keyed.emplace_back(key_of(x, y), static_cast<std::uint32_t>(k));
    }
    std::sort(keyed.begin(), keyed.end()); // by column, then index: a function of the data alone
    order_.reserve(keyed.size());
    for (std::size_t i = 0; i < keyed.size(); ++i) {
        if (i == 0 || keyed[i].first != keyed[i - 1].first)
            columns_.push_back(Column{keyed[i].first, static_cast<std::uint32_t>(i)});
        order_.push_back(keyed[i].second);
    }
}

std::vector<std::uint32_t> KeypointGrid::select(const std::vector<Vec3f> &points,
                                                const std::vector<std::uint32_t> &keypoint, double scale,
                                                const double lo[3], const double hi[3]) const {
    std::vector<std::uint32_t> out;
    if (order_.empty() || !(scale > 0.0)) return out;
    // The columns the box touches, one column of margin each way against rounding (the exact test below
    // decides); clamped to the occupied columns, so a huge box costs no more than the grid.
    std::int64_t col_lo[2], col_hi[2];
    const std::int64_t first_x = static_cast<std::int64_t>(columns_.front().key >> 32) - kBias;
    const std::int64_t last_x = static_cast<std::int64_t>(columns_.back().key >> 32) - kBias;
    for (int d = 0; d < 2; ++d) {
        const double a = std::floor(lo[d] / scale * inverse_) - 1.0, b = std::floor(hi[d] / scale * inverse_) + 1.0;
        if (!(a <= b)) return out; // NaN bounds select nothing
        col_lo[d] = static_cast<std::int64_t>(std::max(a, static_cast<double>(-kBias)));
        col_hi[d] = static_cast<std::int64_t>(std::min(b, static_cast<double>(kBias - 1)));
    }
    col_lo[0] = std::max(col_lo[0], first_x);
    col_hi[0] = std::min(col_hi[0], last_x);
    for (std::int64_t x = col_lo[0]; x <= col_hi[0]; ++x) {
        const std::uint64_t from = key_of(x, col_lo[1]), to = key_of(x, col_hi[1]);
        auto it = std::lower_bound(columns_.begin(), columns_.end(), from,
                                   [](const Column &c, std::uint64_t k) { return c.key < k; });
        for (; it != columns_.end() && it->key <= to; ++it) {
            const std::size_t end =
                it + 1 != columns_.end() ? static_cast<std::size_t>((it + 1)->begin) : order_.size();
            for (std::size_t i = it->begin; i < end; ++i) {
                const Vec3f &p = points[keypoint[order_[i]]];
                const double px = static_cast<double>(p[0]) * scale, py = static_cast<double>(p[1]) * scale,
                             pz = static_cast<double>(p[2]) * scale;
                if (px >= lo[0] && px < hi[0] && py >= lo[1] && py < hi[1] && pz >= lo[2] && pz < hi[2])
                    out.push_back(order_[i]);
            }
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

KISSM_DETAIL_END
