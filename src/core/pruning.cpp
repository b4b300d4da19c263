// SPDX-License-Identifier: MIT
#include "pruning.hpp"

#include "compat_graph.hpp"
#include "kcore.hpp"

KISSM_DETAIL_BEGIN

PrunedMatches prune_matches(const std::vector<Vec3f> &a, const std::vector<Vec3f> &b, double noise_bound,
                            std::size_t max_measurements, RunContext &ctx) {
    PrunedMatches out;
    const CsrGraph graph = build_compat_graph(a, b, static_cast<float>(noise_bound), ctx);
    out.core = max_kcore(graph, out.max_core_number);
    // Two independent tasks, side by side when there are threads (each is serial, and neither reads what the
    // other writes): the first core's measurements, and the next core with its own. The next core is the graph's
    // maximum k-core once the first core's vertices are taken out (one more peeling, O(V + E); the graph is the
    // costly part, and it is built once); a fifth of the measurements: the ambiguity stage solves it only to place
    // a competitor.
    ctx.parallel_for(2, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t task = begin; task < end; ++task) {
            if (task == 0) {
                out.measurements = sample_induced_edges(graph, out.core, max_measurements);
                continue;
            }
            std::vector<std::uint8_t> excluded(graph.num_vertices(), 0);
            for (std::uint32_t v : out.core) excluded[v] = 1;
            std::uint32_t next_core_number = 0;
            out.second_core = max_kcore(graph, next_core_number, &excluded);
            out.second_measurements = sample_induced_edges(graph, out.second_core, max_measurements / 5);
        }
    });
    return out;
}

KISSM_DETAIL_END
