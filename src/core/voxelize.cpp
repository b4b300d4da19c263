#include "voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "failure.hpp"
#include "radix_sort.hpp"

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

namespace {

std::uint64_t cells_for(double extent, double voxel_size) {
    const double n = std::floor(extent / voxel_size) + 1.0;
    return n >= static_cast<double>(kMaxVoxelsPerAxis) + 1.0 ? kMaxVoxelsPerAxis + 1 : static_cast<std::uint64_t>(n);
}

} // namespace

VoxelCloud voxelize(const InputCloud &input, double voxel_size, const std::string &name, RunContext &ctx) {
    VoxelCloud out;
    const std::size_t n = input.points.size();
    if (n == 0) return out;
    out.origin = 0.5 * (input.min + input.max);

    const Vec3d extent = input.max - input.min;
    std::uint64_t cells[3];
    for (int a = 0; a < 3; ++a) {
        cells[a] = cells_for(extent[a], voxel_size);
        if (cells[a] > kMaxVoxelsPerAxis) {
            std::ostringstream msg;
            msg.precision(6);
            msg << "voxel_size " << voxel_size << " is too small for the " << name << "'s extent of " << extent[a]
                << " along " << "xyz"[a] << " (at most " << kMaxVoxelsPerAxis
                << " voxels per axis; use a voxel size of at least "
                << extent[a] / static_cast<double>(kMaxVoxelsPerAxis - 1) << ")";
            fail(ErrorKind::VoxelRange, msg.str());
        }
    }

    const auto &pts = input.points;
    std::vector<KeyIndex> keyed(n);
    const double inv = 1.0 / voxel_size;
    ctx.parallel_for(n, 8192, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const Vec3d rel = (input.points[i] - input.min) * inv;
            std::uint64_t c[3];
            for (int a = 0; a < 3; ++a) {
                // rel >= 0 by construction; the clamp guards the top face against rounding.
                const double f = std::floor(rel[a]);
                const std::uint64_t ci = f <= 0.0 ? 0 : static_cast<std::uint64_t>(f);
                c[a] = ci < cells[a] ? ci : cells[a] - 1;
            }
            keyed[i].key = (c[0] * cells[1] + c[1]) * cells[2] + c[2];
            keyed[i].index = static_cast<std::uint32_t>(i);
        }
    });

    // By key, then (within a voxel) by coordinates, so that the centroid sums run in an order that does not
    // depend on the input order.
    radix_sort_by_key(keyed);
    const auto by_xyz = [&](const KeyIndex &a, const KeyIndex &b) {
        const Vec3d &pa = pts[a.index], &pb = pts[b.index];
        if (pa.x() != pb.x()) return pa.x() < pb.x();
        if (pa.y() != pb.y()) return pa.y() < pb.y();
        return pa.z() < pb.z();
    };
    for (std::size_t i = 0; i < n;) {
        std::size_t j = i + 1;
        while (j < n && keyed[j].key == keyed[i].key) ++j;
        if (j - i > 1) std::sort(keyed.begin() + static_cast<std::ptrdiff_t>(i), keyed.begin() + static_cast<std::ptrdiff_t>(j), by_xyz);
        i = j;
    }

    std::size_t voxels = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (i == 0 || keyed[i].key != keyed[i - 1].key) ++voxels;
    out.points.reserve(voxels);
    for (std::size_t i = 0; i < n;) {
        std::size_t j = i;
        Vec3d sum = Vec3d::Zero();
        while (j < n && keyed[j].key == keyed[i].key) {
            sum += pts[keyed[j].index] - out.origin;
            ++j;
        }
        out.points.push_back((sum / static_cast<double>(j - i)).cast<float>());
        i = j;
    }
    return out;
}

} // namespace detail
} // namespace v0_1
} // namespace kissm
