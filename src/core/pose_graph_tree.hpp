// SPDX-License-Identifier: MIT
// The graph's shape: a spanning tree from the anchor for the starting poses, and connected components.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "pose_graph.hpp"

KISSM_DETAIL_BEGIN

// Poses composed along a maximum spanning tree from the anchor (trusted edges first, then by the log-determinant
// of the information, ties by edge number); `reached` marks the nodes any edge joins to the anchor.
void spanning_tree_poses(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges, std::size_t anchor,
                         std::vector<Rigid> &poses, std::vector<std::uint8_t> &reached);

// Per node, the smallest node joined to it by the edges with use[e] set.
std::vector<std::uint64_t> components(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges,
                                      const std::vector<std::uint8_t> &use);

KISSM_DETAIL_END
