// SPDX-License-Identifier: MIT
// Which robust edges agree with each other, before the optimisation weighs them. Graduated non-convexity starts
// from the least-squares poses of every edge; when all edges are candidates (every pair of a few tens of scans) and
// the wrong ones are confident, that start is bent beyond what the rounds can undo. So first a consensus: spanning
// trees (trusted edges always in them, robust ones in an order by their information, then in random orders) each
// place the nodes, and every other robust edge is checked against the cycle it closes (its error against the
// uncertainty of the edge and of both nodes' placements along the tree). The tree that the most edges agree with
// wins, as in RANSAC, with the number of trees chosen from the agreeing share. Wrong edges with random poses disagree
// with any tree of right ones by orders of magnitude, so the check can be loose (see kConsensusSlack in the .cpp).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pose_graph.hpp"

KISSM_DETAIL_BEGIN

struct Consensus {
    std::vector<std::uint8_t> agrees;  // per edge: trusted, in the winning tree, or consistent with it
    std::vector<Rigid> poses;          // the winning tree's poses (each tree component's root at the identity)
    std::vector<std::uint8_t> reached; // the nodes any edges join to the anchor
    std::size_t trees = 0;             // spanning trees tried
};

// `gate`: the squared error (against the propagated covariance) above which an edge disagrees.
// Throws Failure(Cancelled) when *cancel becomes non-zero (checked once per tree); cancel may be null.
Consensus edge_consensus(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges, std::size_t anchor,
                         double gate, const std::atomic<int> *cancel);

KISSM_DETAIL_END
