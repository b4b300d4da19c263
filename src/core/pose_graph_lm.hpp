// SPDX-License-Identifier: MIT
// Weighted Levenberg-Marquardt over a pose graph: minimises sum_e w_e xi_e^T I_e xi_e over the nodes with a
// variable, the others held where they are, on a sparse LDL^T of the normal equations by 6x6 blocks (block_ldlt.hpp).
#pragma once

#include <atomic>
#include <cstddef>
#include <vector>

#include "block_ldlt.hpp"
#include "pose_graph.hpp"

KISSM_DETAIL_BEGIN

struct LmOptions {
    int max_iterations = 100;
    double relative_tolerance = 1e-10; // stop when an accepted step lowers the cost by less than this share...
    // ...and moves no node by more than this (radians, and the translations' unit): along a chain that few edges pin
    // down the cost is flat, and a step that lowers it by 1e-10 of itself can still move poses by millimetres.
    double step_tolerance = 1e-6;
};

// What a solve keeps for the next one with the same variables and edges: the factorisation's ordering and pattern
// (one analysis serves every step and every graduated round, which change weights only) and the normal equations'
// storage. The pattern holds the edges of non-zero weight when it was analysed; an edge whose weight falls to 0
// later leaves its blocks in it as explicit zeros, and one of weight 0 then that takes part later has the pattern
// analysed again.
struct LmWorkspace {
    std::vector<long> variable;  // the variables the analysis is for (empty: none yet)
    std::size_t num_edges = 0;   // ...and the number of edges
    std::vector<long> edge_pair; // per edge: its off-diagonal block, or -1 (a node fixed, or not in the pattern)
    BlockLdlt ldlt;
    // The damping the last accepted step left: a solve that starts where the last one ended (the next graduated
    // round, the accepted edges' optimum) starts with it rather than at 1e-6, and saves the steps that would shrink it
    // again (65 instead of 71 factorisations on the benchmark's 10,000-node drive with wrong closures;
    // docs/pose-graph.md).
    double lambda = 1e-6;
    std::vector<Matrix6d> diagonal, damped, off; // the normal equations' blocks
    std::vector<Rigid> trial;                    // scratch: a trial step's poses...
    std::vector<Vector6d> trial_errors;          // ...and their errors
};

// Every edge's error Log(inv(T) inv(X_t) X_s) at the poses, kept across solves by a caller that also weighs the
// edges a solve leaves out (the graduated rounds): current says that xi holds them for the poses passed in.
struct EdgeErrors {
    std::vector<Vector6d> xi;
    bool current = false;
};

// variable[n] is the node's variable number (0, 1, ...) or -1 when it stays fixed; an edge with weight 0 or with
// both nodes fixed is skipped. Updates poses in place; returns the final cost. With `errors`, the errors it holds
// are used when current (and not computed again), and on return it holds every edge's error at the returned poses.
// Throws Failure(Cancelled).
double levenberg_marquardt(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
                           const std::vector<long> &variable, std::vector<Rigid> &poses, const LmOptions &options,
                           LmWorkspace &workspace, const std::atomic<int> *cancel, EdgeErrors *errors = nullptr);

KISSM_DETAIL_END
