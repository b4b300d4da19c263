// SPDX-License-Identifier: MIT
// Stage 4b: maximum k-core of the compatibility graph (Batagelj-Zaversnik peeling, O(V + E)).
// Paper: Sec. III-D (\label{subsec:robin}): the correspondences outside the maximum k-core are the gross
// outliers O of Eq. (2); it numbers no equation for the k-core itself.
#pragma once

#include "compat_graph.hpp"
#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// Core number of every vertex.
// Vertices with excluded[v] != 0 (when given) are left out of the graph: core number 0, their edges ignored.
std::vector<std::uint32_t> core_numbers(const CsrGraph &g, const std::vector<std::uint8_t> *excluded = nullptr);

// Vertices whose core number is the maximum, ascending; `max_core` receives that maximum (0 for an
// empty graph, in which case no vertex is returned).
std::vector<std::uint32_t> max_kcore(const CsrGraph &g, std::uint32_t &max_core,
                                     const std::vector<std::uint8_t> *excluded = nullptr);

KISSM_DETAIL_END
