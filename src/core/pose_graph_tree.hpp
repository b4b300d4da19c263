// SPDX-License-Identifier: MIT
// The graph's shape: union-find over the nodes, and connected components.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "pose_graph.hpp"

KISSM_DETAIL_BEGIN

// The root of i's set in a union-find forest (parent[r] == r at a root), halving the path on the way.
std::size_t union_find_root(std::vector<std::size_t> &parent, std::size_t i);

// Per node, the smallest node joined to it by the edges with use[e] set.
std::vector<std::uint64_t> components(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges,
                                      const std::vector<std::uint8_t> &use);

KISSM_DETAIL_END
