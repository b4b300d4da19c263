// SPDX-License-Identifier: MIT
#include "pose_graph_tree.hpp"

#include <numeric>
#include <utility>

KISSM_DETAIL_BEGIN

std::size_t union_find_root(std::vector<std::size_t> &parent, std::size_t i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

std::vector<std::uint64_t> components(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges,
                                      const std::vector<std::uint8_t> &use) {
    std::vector<std::size_t> parent(num_nodes);
    std::iota(parent.begin(), parent.end(), std::size_t{0});
    for (std::size_t e = 0; e < edges.size(); ++e) {
        if (!use[e]) continue;
        std::size_t a = union_find_root(parent, edges[e].source), b = union_find_root(parent, edges[e].target);
        if (a == b) continue;
        if (b < a) std::swap(a, b);
        parent[b] = a; // the smaller root stays: every root is its component's smallest node
    }
    std::vector<std::uint64_t> label(num_nodes);
    for (std::size_t i = 0; i < num_nodes; ++i) label[i] = union_find_root(parent, i);
    return label;
}

KISSM_DETAIL_END
