// SPDX-License-Identifier: MIT
#include "input.hpp"

#include <algorithm>
#include <limits>

#include "failure.hpp"

KISSM_DETAIL_BEGIN

namespace {

struct ChunkSummary {
    std::size_t finite = 0;
    std::uint64_t first_nonfinite = std::numeric_limits<std::uint64_t>::max();
    Vec3d min = Vec3d::Constant(std::numeric_limits<double>::infinity());
    Vec3d max = Vec3d::Constant(-std::numeric_limits<double>::infinity());
};

} // namespace

InputCloud gather_points(const PointsView &view, NonFinitePolicy policy, const std::string &name, RunContext &ctx) {
    InputCloud cloud;
    cloud.view = view;
    cloud.num_given = view.count;
    const std::size_t n = static_cast<std::size_t>(view.count);
    if (n == 0) return cloud;
    constexpr std::size_t kChunk = 16384;
    // Each chunk's summary is accumulated locally and stored once by map_fold: neighbouring summaries share
    // cache lines, so updating them in place from two threads makes the threads fight over them
    // (docs/design/performance.md, "Input scan"). The fold reads them in chunk order, so the first non-finite point
    // reported is the lowest-numbered one.
    const std::size_t finite = ctx.map_fold(
        n, kChunk, std::size_t(0),
        [&](std::size_t b, std::size_t e) {
            ChunkSummary s;
            cloud.for_each_point(b, e, [&s](std::size_t i, const Vec3d &v) {
                if (!InputCloud::finite(v)) {
                    if (s.first_nonfinite == std::numeric_limits<std::uint64_t>::max()) s.first_nonfinite = i;
                    return;
                }
                s.min = s.min.cwiseMin(v);
                s.max = s.max.cwiseMax(v);
                ++s.finite;
            });
            return s;
        },
        [&](std::size_t &finite_so_far, ChunkSummary &&s) {
            if (s.first_nonfinite != std::numeric_limits<std::uint64_t>::max() && policy == NonFinitePolicy::Reject)
                fail(ErrorKind::NonFinite, name + " point " + std::to_string(s.first_nonfinite) +
                                               " has a non-finite coordinate (set nonfinite_policy to "
                                               "KISSM_NONFINITE_DROP to skip such points)");
            if (s.finite > 0) {
                if (finite_so_far == 0) cloud.min = s.min, cloud.max = s.max;
                cloud.min = cloud.min.cwiseMin(s.min);
                cloud.max = cloud.max.cwiseMax(s.max);
            }
            finite_so_far += s.finite;
        });
    cloud.num_nonfinite = view.count - finite;
    cloud.skip_nonfinite = finite < n;
    return cloud;
}

KISSM_DETAIL_END
