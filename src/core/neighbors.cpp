#include "neighbors.hpp"

#include <algorithm>
#include <cmath>

#include "radix_sort.hpp"

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

namespace {

// Cell coordinates are offset by one so that the -1 neighbour of cell 0 is still a valid unsigned key.
constexpr std::uint64_t kBits = 21;
constexpr std::uint64_t kMask = (std::uint64_t(1) << kBits) - 1;

std::uint64_t pack(std::uint64_t x, std::uint64_t y, std::uint64_t z) { return (x << (2 * kBits)) | (y << kBits) | z; }

} // namespace

Neighborhoods radius_neighbors(const std::vector<Vec3f> &points, float radius, RunContext &ctx) {
    Neighborhoods nb;
    const std::size_t n = points.size();
    nb.offsets.assign(n + 1, 0);
    if (n == 0) return nb;

    Vec3f lo = points[0];
    for (const auto &p : points) lo = lo.cwiseMin(p);
    const float inv = 1.0f / radius;
    // The voxel stage bounds the extent to 2^21 voxels per axis, hence < 2^19 cells of 5 voxels: 21 bits fit.
    auto cell_of = [&](const Vec3f &p, std::uint64_t c[3]) {
        for (int a = 0; a < 3; ++a) {
            const float f = std::floor((p[a] - lo[a]) * inv);
            const std::uint64_t ci = f <= 0.0f ? 0 : static_cast<std::uint64_t>(f);
            c[a] = std::min<std::uint64_t>(ci + 1, kMask - 1);
        }
    };

    std::vector<KeyIndex> entries(n);
    for (std::size_t i = 0; i < n; ++i) {
        std::uint64_t c[3];
        cell_of(points[i], c);
        entries[i] = {pack(c[0], c[1], c[2]), static_cast<std::uint32_t>(i)};
    }
    radix_sort_by_key(entries); // stable: ties stay in index order
    // Unique cells with their ranges in `entries`.
    std::vector<std::uint64_t> cell_keys;
    std::vector<std::uint32_t> cell_start;
    for (std::size_t i = 0; i < n; ++i) {
        if (i == 0 || entries[i].key != entries[i - 1].key) {
            cell_keys.push_back(entries[i].key);
            cell_start.push_back(static_cast<std::uint32_t>(i));
        }
    }
    cell_start.push_back(static_cast<std::uint32_t>(n));
    // Points in cell order, as structure of arrays: a run of three z-adjacent cells is one contiguous
    // stretch, scanned by a loop the compiler vectorises.
    std::vector<float> sx(n), sy(n), sz(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3f &p = points[entries[i].index];
        sx[i] = p.x(), sy[i] = p.y(), sz[i] = p.z();
    }

    const float r2 = radius * radius;
    constexpr std::size_t kChunk = 1024;
    const std::size_t num_chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::vector<std::uint32_t>> chunk_index(num_chunks);
    std::vector<std::uint32_t> counts(n, 0);

    ctx.parallel_for(n, kChunk, [&](std::size_t b, std::size_t e) {
        auto &idx = chunk_index[b / kChunk];
        std::vector<unsigned char> inside;
        for (std::size_t i = b; i < e; ++i) {
            const Vec3f &q = points[i];
            const float qx = q.x(), qy = q.y(), qz = q.z();
            std::uint64_t c[3];
            cell_of(q, c);
            const std::size_t before = idx.size();
            for (std::uint64_t dx = c[0] - 1; dx <= c[0] + 1; ++dx) {
                for (std::uint64_t dy = c[1] - 1; dy <= c[1] + 1; ++dy) {
                    // z is the fastest-varying part of the key: the three z cells are one contiguous run.
                    const std::uint64_t first = pack(dx, dy, c[2] - 1), last = pack(dx, dy, c[2] + 1);
                    auto lo_it = std::lower_bound(cell_keys.begin(), cell_keys.end(), first);
                    auto hi_it = std::upper_bound(lo_it, cell_keys.end(), last);
                    if (lo_it == hi_it) continue;
                    const std::uint32_t s0 = cell_start[static_cast<std::size_t>(lo_it - cell_keys.begin())];
                    const std::uint32_t s1 = cell_start[static_cast<std::size_t>(hi_it - cell_keys.begin())];
                    const std::size_t len = s1 - s0;
                    inside.resize(len);
                    const float *px = &sx[s0], *py = &sy[s0], *pz = &sz[s0];
                    for (std::size_t s = 0; s < len; ++s) {
                        const float ddx = px[s] - qx, ddy = py[s] - qy, ddz = pz[s] - qz;
                        inside[s] = ddx * ddx + ddy * ddy + ddz * ddz < r2;
                    }
                    for (std::size_t s = 0; s < len; ++s)
                        if (inside[s]) idx.push_back(entries[s0 + s].index);
                }
            }
            counts[i] = static_cast<std::uint32_t>(idx.size() - before);
        }
    });

    for (std::size_t i = 0; i < n; ++i) nb.offsets[i + 1] = nb.offsets[i] + counts[i];
    nb.index.resize(nb.offsets[n]);
    ctx.parallel_for(num_chunks, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t c = b; c < e; ++c) {
            const std::size_t start = nb.offsets[c * kChunk];
            std::copy(chunk_index[c].begin(), chunk_index[c].end(), nb.index.begin() + static_cast<std::ptrdiff_t>(start));
            std::vector<std::uint32_t>().swap(chunk_index[c]);
        }
    });
    return nb;
}

} // namespace detail
} // namespace v0_1
} // namespace kissm
