// SPDX-License-Identifier: MIT
// The pose graph (kissm_pose_graph): nodes are scans, edges relative poses T_target_source with a 6x6 information
// (rotation first, source frame). optimize_pose_graph finds each node's pose in an anchor's frame: a spanning tree
// from the anchor to start (pose_graph_tree.cpp), Levenberg-Marquardt on SE(3) (pose_graph_lm.cpp), and for robust
// edges graduated non-convexity with a truncated least-squares cost (Yang, Antonante, Tzoumas, Carlone, "Graduated
// Non-Convexity for Robust Spatial Perception", 2020: the idea of the solver's rotation stage, one level up).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "se3.hpp"

KISSM_DETAIL_BEGIN

struct PoseGraphEdge {
    std::size_t source = 0, target = 0;
    Rigid measured; // T_target_source: states measured = inv(X_target) X_source
    Matrix6d information = Matrix6d::Identity();
    bool robust = true; // a candidate the optimisation may reject
};

struct PoseGraphSolution {
    std::vector<Rigid> poses;             // world (the anchor's frame) from node; meaningless where not placed
    std::vector<std::uint8_t> placed;     // joined to the anchor by accepted edges
    std::vector<std::uint64_t> component; // the smallest node joined by trusted and accepted edges
    std::vector<std::uint8_t> accepted;   // per edge
    std::vector<double> residual;         // per edge: xi^T I xi at the solution, NaN where a node is not placed
};

// The squared error xi^T I xi of an edge at the given poses.
double edge_chi2(const PoseGraphEdge &edge, const std::vector<Rigid> &poses);

// Throws Failure(Cancelled) when *cancel becomes non-zero (checked once per iteration); cancel may be null.
PoseGraphSolution optimize_pose_graph(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges,
                                      std::size_t anchor, double bound, const std::atomic<int> *cancel);

KISSM_DETAIL_END
