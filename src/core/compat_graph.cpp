// SPDX-License-Identifier: MIT
#include "compat_graph.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "radix_sort.hpp"

KISSM_DETAIL_BEGIN

CsrGraph build_compat_graph(const std::vector<Vec3f> &a, const std::vector<Vec3f> &b, float noise_bound,
                            RunContext &ctx) {
    const std::size_t n = a.size();
    CsrGraph g;
    g.offsets.assign(n + 1, 0);
    if (n < 2) return g;

    // Structure of arrays so the inner loop vectorises.
    std::vector<float> ax(n), ay(n), az(n), bx(n), by(n), bz(n);
    for (std::size_t i = 0; i < n; ++i) {
        ax[i] = a[i].x(), ay[i] = a[i].y(), az[i] = a[i].z();
        bx[i] = b[i].x(), by[i] = b[i].y(), bz[i] = b[i].z();
    }

    // Upper triangle, rows in small chunks (row lengths shrink, so small chunks balance the threads). Each
    // chunk records its edges (i < j) in row order; merged below in chunk order.
    constexpr std::size_t kRows = 32;
    std::vector<std::vector<std::uint32_t>> edges = ctx.map_chunks(n, kRows, [&](std::size_t begin, std::size_t end) {
        std::vector<std::uint32_t> out; // built locally, stored once: neighbouring vectors share cache lines
        std::vector<unsigned char> ok(n);
        for (std::size_t i = begin; i < end; ++i) {
            const float pax = ax[i], pay = ay[i], paz = az[i], pbx = bx[i], pby = by[i], pbz = bz[i];
            const std::size_t m = n - i - 1;
            const float *qax = &ax[i + 1], *qay = &ay[i + 1], *qaz = &az[i + 1];
            const float *qbx = &bx[i + 1], *qby = &by[i + 1], *qbz = &bz[i + 1];
            for (std::size_t j = 0; j < m; ++j) {
                const float dax = qax[j] - pax, day = qay[j] - pay, daz = qaz[j] - paz;
                const float dbx = qbx[j] - pbx, dby = qby[j] - pby, dbz = qbz[j] - pbz;
                const float da = std::sqrt(dax * dax + day * day + daz * daz);
                const float db = std::sqrt(dbx * dbx + dby * dby + dbz * dbz);
                ok[j] = std::fabs(da - db) <= noise_bound;
            }
            for (std::size_t j = 0; j < m; ++j) {
                if (ok[j]) {
                    out.push_back(static_cast<std::uint32_t>(i));
                    out.push_back(static_cast<std::uint32_t>(i + 1 + j));
                }
            }
        }
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
