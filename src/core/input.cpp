#include "input.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "failure.hpp"

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

namespace {

template <typename T>
Vec3d load(const unsigned char *p) {
    T xyz[3];
    std::memcpy(xyz, p, sizeof(xyz)); // strides need not be aligned
    return Vec3d(static_cast<double>(xyz[0]), static_cast<double>(xyz[1]), static_cast<double>(xyz[2]));
}

struct ChunkSummary {
    std::size_t finite = 0;
    std::uint64_t first_nonfinite = std::numeric_limits<std::uint64_t>::max();
    Vec3d min = Vec3d::Constant(std::numeric_limits<double>::infinity());
    Vec3d max = Vec3d::Constant(-std::numeric_limits<double>::infinity());
};

} // namespace

InputCloud gather_points(const PointsView &view, NonFinitePolicy policy, const std::string &name, RunContext &ctx) {
    InputCloud cloud;
    cloud.num_given = view.count;
    const std::size_t n = static_cast<std::size_t>(view.count);
    if (n == 0) return cloud;
    // Each chunk packs its finite points at its own start; only when some were dropped does a second pass
    // close the gaps. The usual all-finite cloud is read once.
    constexpr std::size_t kChunk = 16384;
    const std::size_t num_chunks = (n + kChunk - 1) / kChunk;
    std::vector<ChunkSummary> summary(num_chunks);
    std::vector<Vec3d> points(n);
    const auto *base = static_cast<const unsigned char *>(view.data);
    ctx.parallel_for(n, kChunk, [&](std::size_t b, std::size_t e) {
        ChunkSummary &s = summary[b / kChunk];
        std::size_t out = b;
        for (std::size_t i = b; i < e; ++i) {
            const unsigned char *p = base + i * view.stride_bytes;
            const Vec3d v = view.is_double ? load<double>(p) : load<float>(p);
            if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z())) {
                if (s.first_nonfinite == std::numeric_limits<std::uint64_t>::max()) s.first_nonfinite = i;
                continue;
            }
            s.min = s.min.cwiseMin(v);
            s.max = s.max.cwiseMax(v);
            points[out++] = v;
        }
        s.finite = out - b;
    });

    std::size_t finite = 0;
    for (const ChunkSummary &s : summary) {
        if (s.first_nonfinite != std::numeric_limits<std::uint64_t>::max() && policy == NonFinitePolicy::Reject)
            fail(ErrorKind::NonFinite, name + " point " + std::to_string(s.first_nonfinite) +
                                           " has a non-finite coordinate (set nonfinite_policy to "
                                           "KISSM_NONFINITE_DROP to skip such points)");
        if (s.finite > 0) {
            if (finite == 0) cloud.min = s.min, cloud.max = s.max;
            cloud.min = cloud.min.cwiseMin(s.min);
            cloud.max = cloud.max.cwiseMax(s.max);
        }
        finite += s.finite;
    }
    cloud.num_nonfinite = view.count - finite;
    if (finite < n) {
        std::size_t out = 0;
        for (std::size_t c = 0; c < num_chunks; ++c) {
            const std::size_t from = c * kChunk;
            std::copy(points.begin() + static_cast<std::ptrdiff_t>(from),
                      points.begin() + static_cast<std::ptrdiff_t>(from + summary[c].finite),
                      points.begin() + static_cast<std::ptrdiff_t>(out));
            out += summary[c].finite;
        }
        points.resize(finite);
        points.shrink_to_fit();
    }
    cloud.points = std::move(points);
    return cloud;
}

} // namespace detail
} // namespace v0_1
} // namespace kissm
