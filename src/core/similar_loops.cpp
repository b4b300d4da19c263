// SPDX-License-Identifier: MIT
#include "similar_loops.hpp"

#include <limits>
#include <utility>

KISSM_DETAIL_BEGIN

std::vector<ScanPair> similar_candidates(const double *signatures, std::size_t size,
                                         const std::vector<std::int64_t> &piece, std::size_t gap,
                                         std::size_t per_scan) {
    const std::size_t n = piece.size();
    std::vector<ScanPair> out;
    if (gap == 0 || per_scan == 0 || n == 0) return out;
    std::vector<std::pair<double, std::size_t>> near;
    for (std::size_t j = gap; j < n; ++j) {
        const double *sj = signatures + size * j;
        near.clear();
        for (std::size_t i = 0; i + gap <= j; ++i) {
            if (piece[i] == piece[j]) continue;
            const double *si = signatures + size * i;
            double distance = 0.0;
            for (std::size_t c = 0; c < size; ++c) {
                const double d = si[c] - sj[c];
                distance += d * d;
            }
            // NaN or infinity (a scan without a signature, or an overflow): no candidate either way.
            if (distance < std::numeric_limits<double>::infinity()) near.push_back({distance, i});
        }
        append_nearest(near, per_scan, j, out);
    }
    return out;
}

KISSM_DETAIL_END
