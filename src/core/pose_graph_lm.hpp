// SPDX-License-Identifier: MIT
// Weighted Levenberg-Marquardt over a pose graph: minimises sum_e w_e xi_e^T I_e xi_e over the nodes with a
// variable, the others held where they are, on Eigen's sparse LDL^T of the normal equations.
#pragma once

#include <atomic>
#include <cstddef>
#include <vector>

#include "pose_graph.hpp"

KISSM_DETAIL_BEGIN

struct LmOptions {
    int max_iterations = 100;
    double relative_tolerance = 1e-10; // stop when an accepted step lowers the cost by less than this share...
    // ...and moves no node by more than this (radians, and the translations' unit): along a chain that few edges pin
    // down the cost is flat, and a step that lowers it by 1e-10 of itself can still move poses by millimetres.
    double step_tolerance = 1e-6;
};

// variable[n] is the node's variable number (0, 1, ...) or -1 when it stays fixed; an edge with weight 0 or with
// both nodes fixed is skipped. Updates poses in place; returns the final cost. Throws Failure(Cancelled).
double levenberg_marquardt(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
                           const std::vector<long> &variable, std::vector<Rigid> &poses, const LmOptions &options,
                           const std::atomic<int> *cancel);

KISSM_DETAIL_END
