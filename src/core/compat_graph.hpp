// SPDX-License-Identifier: MIT
// Stage 4a: the pairwise-consistency graph over correspondences, in CSR form.
// Paper: Sec. III-D (\label{subsec:robin}), Eq. (3) (\label{eq:test-p-ref3}), the pairwise invariant
// -2 beta <= |b_j - b_j'| - |a_i - a_i'| <= 2 beta; the CSR form is the paper's too. noise_bound below is
// the paper's 2 beta (the pipeline's prune bound, 1.0 v by default, i.e. beta = 0.5 v against the paper's
// 1.5 v of Sec. IV-B; docs/parameters.md, prune_noise_bound_gain).
#pragma once

#include <utility>

#include "detail_namespace.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// Undirected graph in compressed sparse rows: the neighbours of v are adj[offsets[v] .. offsets[v+1]),
// in ascending order, without self loops.
struct CsrGraph {
    std::vector<std::uint64_t> offsets;
    std::vector<std::uint32_t> adj;
    std::size_t num_vertices() const { return offsets.empty() ? 0 : offsets.size() - 1; }
    std::uint64_t num_edges() const { return adj.size() / 2; }
};

// Vertex k is the correspondence (a[k], b[k]); an edge joins k and l when the distances agree:
// | |b_k - b_l| - |a_k - a_l| | <= noise_bound (rigid motions preserve distances).
CsrGraph build_compat_graph(const std::vector<Vec3f> &a, const std::vector<Vec3f> &b, float noise_bound,
                            RunContext &ctx);

// Edges of the subgraph induced by `vertices` (ascending), renumbered to positions in `vertices`, at most
// about `max_pairs` of them: each vertex contributes up to max_pairs / |vertices| edges spread evenly over
// its sorted neighbour list. Sorted and unique.
std::vector<std::pair<std::uint32_t, std::uint32_t>>
sample_induced_edges(const CsrGraph &g, const std::vector<std::uint32_t> &vertices, std::size_t max_pairs);

KISSM_DETAIL_END
