// SPDX-License-Identifier: MIT
#include "compat_graph.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "radix_sort.hpp"
#include "simd_level.hpp"

// SSE2 is part of every x86-64 target (see pair_features.cpp for why not 32-bit x86).
#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__))
#  define KISSM_COMPAT_SSE2 1
#  include <emmintrin.h>
#  include <immintrin.h>
#else
#  define KISSM_COMPAT_SSE2 0
#endif

KISSM_DETAIL_BEGIN

namespace {

// The correspondences as structure of arrays, padded with copies of the last one to a multiple of 8 so that
// the row test reads whole vectors (padding columns are never reported).
struct Columns {
    std::size_t n;
    std::vector<float> ax, ay, az, bx, by, bz;
    Columns(const std::vector<Vec3f> &a, const std::vector<Vec3f> &b) : n(a.size()) {
        const std::size_t padded = (n + 7) & ~std::size_t(7);
        for (auto *v : {&ax, &ay, &az, &bx, &by, &bz}) v->resize(padded);
        for (std::size_t i = 0; i < padded; ++i) {
            const std::size_t k = std::min(i, n - 1);
            ax[i] = a[k].x(), ay[i] = a[k].y(), az[i] = a[k].z();
            bx[i] = b[k].x(), by[i] = b[k].y(), bz[i] = b[k].z();
        }
    }
};

// Whether (i, j) is an edge: | |b_j - b_i| - |a_j - a_i| | <= bound, each length evaluated as
// sqrt((dx^2 + dy^2) + dz^2) in every path, so the vector and scalar tests agree bit for bit.
inline bool is_edge(const Columns &c, std::size_t i, std::size_t j, float bound) {
    const float dax = c.ax[j] - c.ax[i], day = c.ay[j] - c.ay[i], daz = c.az[j] - c.az[i];
    const float dbx = c.bx[j] - c.bx[i], dby = c.by[j] - c.by[i], dbz = c.bz[j] - c.bz[i];
    const float da = std::sqrt(dax * dax + day * day + daz * daz);
    const float db = std::sqrt(dbx * dbx + dby * dby + dbz * dbz);
    return std::fabs(da - db) <= bound;
}

inline void emit(std::vector<std::uint32_t> &out, std::size_t i, std::size_t j) {
    out.push_back(static_cast<std::uint32_t>(i));
    out.push_back(static_cast<std::uint32_t>(j));
}

// Appends the edges (i, j) of row i, j > i in ascending order. GCC does not vectorise the plain loop (the float
// test feeding a byte store), hence the intrinsics.
void append_row_edges(const Columns &c, std::size_t i, float bound, std::vector<std::uint32_t> &out) {
    std::size_t j = i + 1;
#if KISSM_COMPAT_SSE2
    for (; j < c.n && (j & 3) != 0; ++j)
        if (is_edge(c, i, j, bound)) emit(out, i, j);
    const __m128 vax = _mm_set1_ps(c.ax[i]), vay = _mm_set1_ps(c.ay[i]), vaz = _mm_set1_ps(c.az[i]);
    const __m128 vbx = _mm_set1_ps(c.bx[i]), vby = _mm_set1_ps(c.by[i]), vbz = _mm_set1_ps(c.bz[i]);
    const __m128 vbound = _mm_set1_ps(bound), abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
    for (; j < c.n; j += 4) {
        const __m128 dax = _mm_sub_ps(_mm_load_ps(&c.ax[j]), vax), day = _mm_sub_ps(_mm_load_ps(&c.ay[j]), vay);
        const __m128 daz = _mm_sub_ps(_mm_load_ps(&c.az[j]), vaz), dbx = _mm_sub_ps(_mm_load_ps(&c.bx[j]), vbx);
        const __m128 dby = _mm_sub_ps(_mm_load_ps(&c.by[j]), vby), dbz = _mm_sub_ps(_mm_load_ps(&c.bz[j]), vbz);
        const __m128 da =
            _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dax, dax), _mm_mul_ps(day, day)), _mm_mul_ps(daz, daz)));
        const __m128 db =
            _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dbx, dbx), _mm_mul_ps(dby, dby)), _mm_mul_ps(dbz, dbz)));
        int mask = _mm_movemask_ps(_mm_cmple_ps(_mm_and_ps(_mm_sub_ps(da, db), abs_mask), vbound));
        if (c.n - j < 4) mask &= (1 << (c.n - j)) - 1; // padding columns
        for (; mask != 0; mask &= mask - 1) emit(out, i, j + static_cast<std::size_t>(__builtin_ctz(mask)));
    }
#else
    for (; j < c.n; ++j)
        if (is_edge(c, i, j, bound)) emit(out, i, j);
#endif
}

#if KISSM_COMPAT_SSE2 && KISSM_HAVE_AVX2_KERNELS
// append_row_edges eight columns at a time (simd_level.hpp): the same test lane by lane.
KISSM_TARGET_AVX2 void append_row_edges_avx2(const Columns &c, std::size_t i, float bound,
                                             std::vector<std::uint32_t> &out) {
    std::size_t j = i + 1;
    for (; j < c.n && (j & 7) != 0; ++j)
        if (is_edge(c, i, j, bound)) emit(out, i, j);
    const __m256 vax = _mm256_set1_ps(c.ax[i]), vay = _mm256_set1_ps(c.ay[i]), vaz = _mm256_set1_ps(c.az[i]);
    const __m256 vbx = _mm256_set1_ps(c.bx[i]), vby = _mm256_set1_ps(c.by[i]), vbz = _mm256_set1_ps(c.bz[i]);
    const __m256 vbound = _mm256_set1_ps(bound), abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7FFFFFFF));
    for (; j < c.n; j += 8) {
        const __m256 dax = _mm256_sub_ps(_mm256_loadu_ps(&c.ax[j]), vax);
        const __m256 day = _mm256_sub_ps(_mm256_loadu_ps(&c.ay[j]), vay);
        const __m256 daz = _mm256_sub_ps(_mm256_loadu_ps(&c.az[j]), vaz);
        const __m256 dbx = _mm256_sub_ps(_mm256_loadu_ps(&c.bx[j]), vbx);
        const __m256 dby = _mm256_sub_ps(_mm256_loadu_ps(&c.by[j]), vby);
        const __m256 dbz = _mm256_sub_ps(_mm256_loadu_ps(&c.bz[j]), vbz);
        const __m256 da = _mm256_sqrt_ps(
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dax, dax), _mm256_mul_ps(day, day)), _mm256_mul_ps(daz, daz)));
        const __m256 db = _mm256_sqrt_ps(
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dbx, dbx), _mm256_mul_ps(dby, dby)), _mm256_mul_ps(dbz, dbz)));
        int mask =
            _mm256_movemask_ps(_mm256_cmp_ps(_mm256_and_ps(_mm256_sub_ps(da, db), abs_mask), vbound, _CMP_LE_OS));
        if (c.n - j < 8) mask &= (1 << (c.n - j)) - 1; // padding columns
        for (; mask != 0; mask &= mask - 1) emit(out, i, j + static_cast<std::size_t>(__builtin_ctz(mask)));
    }
}
#endif

} // namespace

CsrGraph build_compat_graph(const std::vector<Vec3f> &a, const std::vector<Vec3f> &b, float noise_bound,
                            RunContext &ctx) {
    const std::size_t n = a.size();
    CsrGraph g;
    g.offsets.assign(n + 1, 0);
    if (n < 2) return g;

    const Columns columns(a, b);

    // Upper triangle, rows in small chunks (row lengths shrink, so small chunks balance the threads). Each
    // chunk records its edges (i < j) in row order; merged below in chunk order.
    constexpr std::size_t kRows = 32;
    std::vector<std::vector<std::uint32_t>> edges = ctx.map_chunks(n, kRows, [&](std::size_t begin, std::size_t end) {
        std::vector<std::uint32_t> out; // built locally, stored once: neighbouring vectors share cache lines
#if KISSM_COMPAT_SSE2 && KISSM_HAVE_AVX2_KERNELS
        const auto row_edges = use_avx2() ? append_row_edges_avx2 : append_row_edges;
#else
        const auto row_edges = append_row_edges;
#endif
        for (std::size_t i = begin; i < end; ++i) row_edges(columns, i, noise_bound, out);
        return out;
    });

    std::vector<std::uint64_t> degree(n, 0);
    for (const auto &chunk : edges)
        for (std::size_t e = 0; e < chunk.size(); e += 2) {
            ++degree[chunk[e]];
            ++degree[chunk[e + 1]];
        }
    for (std::size_t v = 0; v < n; ++v) g.offsets[v + 1] = g.offsets[v] + degree[v];
    g.adj.resize(g.offsets[n]);
    std::vector<std::uint64_t> cursor(g.offsets.begin(), g.offsets.end() - 1);
    // Edges arrive sorted by (i, j): every row receives its smaller neighbours first, then its larger
    // ones, each in ascending order, so rows come out sorted.
    for (auto &chunk : edges) {
        for (std::size_t e = 0; e < chunk.size(); e += 2) {
            const std::uint32_t i = chunk[e], j = chunk[e + 1];
            g.adj[cursor[i]++] = j;
            g.adj[cursor[j]++] = i;
        }
        std::vector<std::uint32_t>().swap(chunk);
    }
    return g;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>>
sample_induced_edges(const CsrGraph &g, const std::vector<std::uint32_t> &vertices, std::size_t max_pairs) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    const std::size_t m = vertices.size();
    if (m < 2) return out;
    const std::size_t per_vertex = std::max<std::size_t>(1, max_pairs / m);
    std::vector<std::uint32_t> position(g.num_vertices(), UINT32_MAX);
    for (std::size_t k = 0; k < m; ++k) position[vertices[k]] = static_cast<std::uint32_t>(k);
    std::vector<std::uint32_t> inside;
    std::vector<KeyIndex> keys;
    for (std::size_t k = 0; k < m; ++k) {
        const std::uint32_t v = vertices[k];
        inside.clear();
        for (std::uint64_t e = g.offsets[v]; e < g.offsets[v + 1]; ++e)
            if (position[g.adj[e]] != UINT32_MAX) inside.push_back(position[g.adj[e]]);
        const std::size_t take = std::min(per_vertex, inside.size());
        for (std::size_t s = 0; s < take; ++s) {
            const std::uint64_t l = inside[s * inside.size() / take];
            keys.push_back({std::min<std::uint64_t>(k, l) << 32 | std::max<std::uint64_t>(k, l), 0});
        }
    }
    // Sorted (smaller, larger) pairs without repeats: a radix sort of the pairs as 64-bit keys gives the
    // order std::sort did, in about half the time (docs/design/performance.md, "Radix sort").
    radix_sort_by_key(keys);
    for (std::size_t i = 0; i < keys.size(); ++i)
        if (i == 0 || keys[i].key != keys[i - 1].key)
            out.emplace_back(static_cast<std::uint32_t>(keys[i].key >> 32), static_cast<std::uint32_t>(keys[i].key));
    return out;
}

KISSM_DETAIL_END
