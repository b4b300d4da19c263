// SPDX-License-Identifier: MIT
#include "kcore.hpp"

#include <algorithm>

KISSM_DETAIL_BEGIN

std::vector<std::uint32_t> core_numbers(const CsrGraph &g, const std::vector<std::uint8_t> *excluded) {
    const std::size_t n = g.num_vertices();
    std::vector<std::uint32_t> deg(n);
    std::uint32_t max_deg = 0;
    for (std::size_t v = 0; v < n; ++v) {
        if (excluded) {
            std::uint32_t d = 0;
            if (!(*excluded)[v])
                for (std::uint64_t k = g.offsets[v]; k < g.offsets[v + 1]; ++k) d += (*excluded)[g.adj[k]] == 0;
            deg[v] = d;
        } else {
            deg[v] = static_cast<std::uint32_t>(g.offsets[v + 1] - g.offsets[v]);
        }
        max_deg = std::max(max_deg, deg[v]);
    }
    // Bin sort of vertices by degree: bin_start[d] = first position of degree d in `order`.
    std::vector<std::uint32_t> bin_start(static_cast<std::size_t>(max_deg) + 2, 0);
    for (std::size_t v = 0; v < n; ++v) ++bin_start[deg[v] + 1];
    for (std::size_t d = 1; d < bin_start.size(); ++d) bin_start[d] += bin_start[d - 1];
    std::vector<std::uint32_t> order(n), pos(n);
    {
        std::vector<std::uint32_t> next(bin_start.begin(), bin_start.end() - 1);
        for (std::size_t v = 0; v < n; ++v) {
            pos[v] = next[deg[v]]++;
            order[pos[v]] = static_cast<std::uint32_t>(v);
        }
    }
    // Peel in order of current degree; removing v lowers the degree of its higher-degree neighbours, which
    // move to the front of their bin.
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t v = order[i];
        if (excluded && (*excluded)[v]) continue; // not in the graph: it lowers no neighbour's degree
        for (std::uint64_t k = g.offsets[v]; k < g.offsets[v + 1]; ++k) {
            const std::uint32_t u = g.adj[k];
            if (deg[u] > deg[v]) {
                const std::uint32_t du = deg[u];
                const std::uint32_t pu = pos[u], pw = bin_start[du];
                const std::uint32_t w = order[pw];
                if (u != w) {
                    order[pu] = w;
                    pos[w] = pu;
                    order[pw] = u;
                    pos[u] = pw;
                }
                ++bin_start[du];
                --deg[u];
            }
        }
    }
    return deg;
}

std::vector<std::uint32_t> max_kcore(const CsrGraph &g, std::uint32_t &max_core,
                                     const std::vector<std::uint8_t> *excluded) {
    const std::vector<std::uint32_t> core = core_numbers(g, excluded);
    max_core = 0;
    for (std::uint32_t c : core) max_core = std::max(max_core, c);
    std::vector<std::uint32_t> out;
    if (max_core == 0) return out;
    for (std::size_t v = 0; v < core.size(); ++v)
        if (core[v] == max_core) out.push_back(static_cast<std::uint32_t>(v));
    return out;
}

KISSM_DETAIL_END
