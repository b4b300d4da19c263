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
    out.measurements = sample_induced_edges(graph, out.core, max_measurements);
    return out;
}

KISSM_DETAIL_END
