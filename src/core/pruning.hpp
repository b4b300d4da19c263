// SPDX-License-Identifier: MIT
// Stage 4: the correspondences that agree with each other. Vertices are correspondences, edges join pairs whose
// distances a rigid motion preserves (compat_graph.hpp); the maximum k-core (kcore.hpp) is the set kept, and the
// solver's translation-invariant measurements are edges of the core's induced graph (mostly inlier-inlier).
// Paper: Sec. III-D (\label{subsec:robin}), ROBIN's max-core pruning.
#pragma once

#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "gnc_solver.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

struct PrunedMatches {
    std::vector<std::uint32_t> core;     // indices of the kept correspondences, ascending
    std::uint32_t max_core_number = 0;   // the core's k
    std::vector<IndexPair> measurements; // core edges, renumbered to positions in `core`; at most about max
    // The maximum k-core of the graph without the core's vertices: the next structure that agrees with itself
    // (a symmetric part's twin, the right pose where a symmetry won), for the ambiguity stage.
    std::vector<std::uint32_t> second_core;
    std::vector<IndexPair> second_measurements;
};

// a[k] -> b[k] are the matched points; `noise_bound` the distance agreement of an edge.
PrunedMatches prune_matches(const std::vector<Vec3f> &a, const std::vector<Vec3f> &b, double noise_bound,
                            std::size_t max_measurements, RunContext &ctx);

KISSM_DETAIL_END
