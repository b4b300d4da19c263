// SPDX-License-Identifier: MIT
#include "radius_search.hpp"

#include <algorithm>
#include <cmath>

#include "radix_sort.hpp"
#include "simd_level.hpp"
#include "uninitialized.hpp"

// SSE2 is part of every x86-64 target (see pair_features.cpp for why not 32-bit x86).
#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__))
#  define KISSM_NEIGHBORS_SSE2 1
#  include <emmintrin.h>
#  include <immintrin.h>
#else
#  define KISSM_NEIGHBORS_SSE2 0
#endif

KISSM_DETAIL_BEGIN

namespace {

// Cell coordinates are offset by one so that the -1 neighbour of cell 0 is still a valid unsigned key.
constexpr std::uint64_t kBits = 21;
constexpr std::uint64_t kMask = (std::uint64_t(1) << kBits) - 1;

std::uint64_t pack(std::uint64_t x, std::uint64_t y, std::uint64_t z) { return (x << (2 * kBits)) | (y << kBits) | z; }

// Appends the indices of the points within the run that are strictly closer than sqrt(r2) to q, in run
// order; returns how many. The distance is evaluated as (dx^2 + dy^2) + dz^2 in every path, so the
// vector and scalar tests agree bit for bit (and the lists stay symmetric: the same test both ways).
KISSM_ALWAYS_INLINE std::size_t append_within(const float *px, const float *py, const float *pz,
                                              const std::uint32_t *index, std::size_t len, const Vec3f &q, float r2,
                                              std::uint32_t *out) {
    const float qx = q.x(), qy = q.y(), qz = q.z();
    std::size_t count = 0, s = 0;
#if KISSM_NEIGHBORS_SSE2
    const __m128 vx = _mm_set1_ps(qx), vy = _mm_set1_ps(qy), vz = _mm_set1_ps(qz), vr2 = _mm_set1_ps(r2);
    for (; s + 4 <= len; s += 4) {
        const __m128 dx = _mm_sub_ps(_mm_loadu_ps(px + s), vx);
        const __m128 dy = _mm_sub_ps(_mm_loadu_ps(py + s), vy);
        const __m128 dz = _mm_sub_ps(_mm_loadu_ps(pz + s), vz);
        const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
        unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(d2, vr2)));
        while (mask != 0) {
            const unsigned lane = static_cast<unsigned>(__builtin_ctz(mask));
            out[count++] = index[s + lane];
            mask &= mask - 1;
        }
    }
#endif
    for (; s < len; ++s) {
        const float dx = px[s] - qx, dy = py[s] - qy, dz = pz[s] - qz;
        out[count] = index[s];
        count += dx * dx + dy * dy + dz * dz < r2;
    }
    return count;
}

// The runs of a point's cell neighbourhood: where its candidates lie in the sorted arrays.
constexpr int kRuns = 9;
struct SortedPoints {
    const float *x, *y, *z;
    const std::uint32_t *index;
};

// Appends the neighbours of q from its kRuns runs (r: pairs of sorted positions); returns how many.
std::size_t append_neighbours(const SortedPoints &p, const std::uint32_t *r, const Vec3f &q, float r2,
                              std::uint32_t *out) {
    std::size_t used = 0;
    for (int k = 0; k < kRuns; ++k) {
        const std::uint32_t s0 = r[2 * k], s1 = r[2 * k + 1];
        used += append_within(p.x + s0, p.y + s0, p.z + s0, p.index + s0, s1 - s0, q, r2, out + used);
    }
    return used;
}

#if KISSM_NEIGHBORS_SSE2 && KISSM_HAVE_AVX2_KERNELS
// append_neighbours eight points at a time (simd_level.hpp): the same test lane by lane, then append_within for
// each run's last few.
KISSM_TARGET_AVX2 std::size_t append_neighbours_avx2(const SortedPoints &p, const std::uint32_t *r, const Vec3f &q,
                                                     float r2, std::uint32_t *out) {
    const __m256 vx = _mm256_set1_ps(q.x()), vy = _mm256_set1_ps(q.y()), vz = _mm256_set1_ps(q.z());
    const __m256 vr2 = _mm256_set1_ps(r2);
    std::size_t count = 0;
    for (int k = 0; k < kRuns; ++k) {
        std::size_t s = r[2 * k];
        const std::size_t end = r[2 * k + 1];
        for (; s + 8 <= end; s += 8) {
            const __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(p.x + s), vx);
            const __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(p.y + s), vy);
            const __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(p.z + s), vz);
            const __m256 d2 =
                _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
            unsigned mask = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(d2, vr2, _CMP_LT_OS)));
            while (mask != 0) {
                const unsigned lane = static_cast<unsigned>(__builtin_ctz(mask));
                out[count++] = p.index[s + lane];
                mask &= mask - 1;
            }
        }
        count += append_within(p.x + s, p.y + s, p.z + s, p.index + s, end - s, q, r2, out + count);
    }
    return count;
}
#endif

// Per thread: the scratch list of the chunk it runs, kept for its next chunk. A list per chunk (grown by
// doubling) was the largest share of a description's page faults wherever freed memory goes straight back to
// the system, as in a Dask worker (docs/design/performance.md, "Buffers kept across chunks and iterations").
thread_local UninitVector<std::uint32_t> t_chunk_scratch;

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
    const std::size_t num_cells = cell_keys.size();
    // Points in cell order, as structure of arrays: a run of three z-adjacent cells is one contiguous
    // stretch, scanned four points at a time.
    std::vector<float> sx(n), sy(n), sz(n);
    std::vector<std::uint32_t> sorted_index(n), cell_of_point(n);
    for (std::size_t c = 0; c < num_cells; ++c) {
        for (std::uint32_t s = cell_start[c]; s < cell_start[c + 1]; ++s) {
            const std::uint32_t i = entries[s].index;
            const Vec3f &p = points[i];
            sx[s] = p.x(), sy[s] = p.y(), sz[s] = p.z();
            sorted_index[s] = i;
            cell_of_point[i] = static_cast<std::uint32_t>(c);
        }
    }
    std::vector<KeyIndex>().swap(entries);

    // The 9 runs of a cell's 3 x 3 x 3 neighbourhood (ranges of sorted positions), found once per occupied
    // cell rather than once per point: all points of a cell scan the same runs.
    std::vector<std::uint32_t> runs(num_cells * kRuns * 2);
    ctx.parallel_for(num_cells, 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t c = b; c < e; ++c) {
            const std::uint64_t key = cell_keys[c];
            const std::uint64_t cx = key >> (2 * kBits), cy = (key >> kBits) & kMask, cz = key & kMask;
            std::uint32_t *r = &runs[c * kRuns * 2];
            for (std::uint64_t dx = cx - 1; dx <= cx + 1; ++dx) {
                for (std::uint64_t dy = cy - 1; dy <= cy + 1; ++dy) {
                    // z is the fastest-varying part of the key: the three z cells are one contiguous run.
                    const std::uint64_t first = pack(dx, dy, cz - 1), last = pack(dx, dy, cz + 1);
                    auto lo_it = std::lower_bound(cell_keys.begin(), cell_keys.end(), first);
                    auto hi_it = std::upper_bound(lo_it, cell_keys.end(), last);
                    *r++ = cell_start[static_cast<std::size_t>(lo_it - cell_keys.begin())];
                    *r++ = cell_start[static_cast<std::size_t>(hi_it - cell_keys.begin())];
                }
            }
        }
    });

    const float r2 = radius * radius;
    constexpr std::size_t kChunk = Neighborhoods::kBlockRows;
    std::vector<std::uint32_t> counts(n, 0);

    // The pool's threads end with the call; the caller's scratch goes when this returns or throws, so that a
    // library call keeps no memory after it.
    struct ReleaseScratch {
        ~ReleaseScratch() { UninitVector<std::uint32_t>().swap(t_chunk_scratch); }
    } release_scratch;

    // One block per chunk, indexed by chunk.
    nb.blocks = ctx.map_chunks(n, kChunk, [&](std::size_t b, std::size_t e) {
        // The chunk's rows go to a scratch list first (its final length is known only at the end), then
        // into the block at its exact size.
        UninitVector<std::uint32_t> &idx = t_chunk_scratch;
        std::size_t used = 0;
        const SortedPoints sorted{sx.data(), sy.data(), sz.data(), sorted_index.data()};
#if KISSM_NEIGHBORS_SSE2 && KISSM_HAVE_AVX2_KERNELS
        const auto neighbours_of = use_avx2() ? append_neighbours_avx2 : append_neighbours;
#else
        const auto neighbours_of = append_neighbours;
#endif
        for (std::size_t i = b; i < e; ++i) {
            const Vec3f &q = points[i];
            const std::uint32_t *r = &runs[static_cast<std::size_t>(cell_of_point[i]) * kRuns * 2];
            std::size_t candidates = 0;
            for (int k = 0; k < kRuns; ++k) candidates += r[2 * k + 1] - r[2 * k];
            if (idx.size() < used + candidates) idx.resize(std::max(2 * idx.size(), used + candidates));
            const std::size_t found = neighbours_of(sorted, r, q, r2, idx.data() + used);
            used += found;
            counts[i] = static_cast<std::uint32_t>(found);
        }
        return std::vector<std::uint32_t>(idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(used));
    });

    for (std::size_t i = 0; i < n; ++i) nb.offsets[i + 1] = nb.offsets[i] + counts[i];
    return nb;
}

KISSM_DETAIL_END
