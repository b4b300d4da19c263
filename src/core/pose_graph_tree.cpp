// SPDX-License-Identifier: MIT
#include "pose_graph_tree.hpp"

#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <tuple>

#include <Eigen/Cholesky>

KISSM_DETAIL_BEGIN

namespace {

// How much an edge is trusted to place a node: trusted edges before any robust one, then the most informative
// (the log-determinant: the smallest uncertainty volume).
double priority(const PoseGraphEdge &e) {
    if (!e.robust) return std::numeric_limits<double>::infinity();
    const Eigen::LLT<Matrix6d> llt(e.information);
    return 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
}

std::size_t find_root(std::vector<std::size_t> &parent, std::size_t i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

} // namespace

void spanning_tree_poses(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges, std::size_t anchor,
                         std::vector<Rigid> &poses, std::vector<std::uint8_t> &reached) {
    std::vector<std::vector<std::size_t>> incident(num_nodes);
    for (std::size_t e = 0; e < edges.size(); ++e) {
        incident[edges[e].source].push_back(e);
        incident[edges[e].target].push_back(e);
    }
    std::vector<double> prio(edges.size());
    for (std::size_t e = 0; e < edges.size(); ++e) prio[e] = priority(edges[e]);
    poses.assign(num_nodes, Rigid{});
    reached.assign(num_nodes, 0);
    // Prim's algorithm: the highest priority first, the lower edge number on ties (deterministic).
    using Item = std::tuple<double, std::size_t>; // (priority, -edge) ordered as a max-heap
    auto lower = [](const Item &a, const Item &b) {
        if (std::get<0>(a) != std::get<0>(b)) return std::get<0>(a) < std::get<0>(b);
        return std::get<1>(a) > std::get<1>(b);
    };
    std::priority_queue<Item, std::vector<Item>, decltype(lower)> heap(lower);
    auto visit = [&](std::size_t node) {
        reached[node] = 1;
        for (std::size_t e : incident[node]) {
            const std::size_t other = edges[e].source == node ? edges[e].target : edges[e].source;
            if (!reached[other]) heap.emplace(prio[e], e);
        }
    };
    visit(anchor);
    while (!heap.empty()) {
        const std::size_t e = std::get<1>(heap.top());
        heap.pop();
        const PoseGraphEdge &edge = edges[e];
        if (reached[edge.source] && reached[edge.target]) continue;
        if (reached[edge.target]) { // measured = inv(X_t) X_s
            poses[edge.source] = poses[edge.target] * edge.measured;
            visit(edge.source);
        } else {
            poses[edge.target] = poses[edge.source] * edge.measured.inverse();
            visit(edge.target);
        }
    }
}

std::vector<std::uint64_t> components(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges,
                                      const std::vector<std::uint8_t> &use) {
    std::vector<std::size_t> parent(num_nodes);
    std::iota(parent.begin(), parent.end(), std::size_t{0});
    for (std::size_t e = 0; e < edges.size(); ++e) {
        if (!use[e]) continue;
        std::size_t a = find_root(parent, edges[e].source), b = find_root(parent, edges[e].target);
        if (a == b) continue;
        if (b < a) std::swap(a, b);
        parent[b] = a; // the smaller root stays: every root is its component's smallest node
    }
    std::vector<std::uint64_t> label(num_nodes);
    for (std::size_t i = 0; i < num_nodes; ++i) label[i] = find_root(parent, i);
    return label;
}

KISSM_DETAIL_END
