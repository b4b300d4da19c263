// SPDX-License-Identifier: MIT
#include "pose_graph.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pose_graph_consensus.hpp"
#include "pose_graph_lm.hpp"
#include "pose_graph_tree.hpp"

KISSM_DETAIL_BEGIN

namespace {

// Graduated non-convexity: mu starts where the surrogate is convex over the largest residual and grows by
// kMuGrowth per round; the rounds end when every weight is 0 or 1 (or after kMaxRounds). 1.6 instead of 1.4 took
// 3 rounds fewer of 16 but rejected more right closures on 8 of 39 drives (no wrong one accepted; where half the
// closures are wrong, a stretch that loses one moved by up to 29 m; docs/pose-graph.md).
constexpr double kMuGrowth = 1.4;
constexpr int kMaxRounds = 200;
// One Levenberg-Marquardt step per round, each round starting where the last ended: mu grows by 1.4 per round, so
// the weights move little from one round to the next and a step on the new weights is all a round needs. Before
// the consensus start (pose_graph_consensus.cpp), 2 steps per round left the map unsettled when the weights turned
// binary (a run of 17 right closures rejected on a 10,000-node drive) and rounds ran to convergence, up to 10
// steps each; from the consensus start one step per round accepts the same edges on every drive and shared set
// tried, with half the factorisations (docs/pose-graph.md).
constexpr int kRoundIterations = 1;
// The least-squares start (every edge that agrees with the consensus, wrong ones among them) only has to bring the
// right closures' errors down to where the wrong ones stand out: it stops at a gain below 1e-3 of the cost (5 to 7
// steps on the benchmark's 10,000-node drives with wrong closures, where it used to run 10). A fixed 3 steps changed
// which edges were accepted on 2 of 39 drives; 4 did not, nor this rule.
constexpr int kStartIterations = 10;
constexpr double kStartTolerance = 1e-3;
constexpr int kFinalPasses = 20; // final solves at most
// The consensus (pose_graph_consensus.cpp) calls an edge disagreeing above this multiple of the bound: its errors
// compose the edges' own uncertainties along tree paths, which real registrations understate (docs/pose-graph.md).
constexpr double kConsensusSlack = 10.0;

// The truncated least-squares weight of a squared error r2 at continuation mu (Yang et al. 2020, eq. 14).
double tls_weight(double r2, double bound, double mu) {
    if (r2 >= (mu + 1.0) / mu * bound) return 0.0;
    if (r2 <= mu / (mu + 1.0) * bound) return 1.0;
    return std::sqrt(bound * mu * (mu + 1.0) / r2) - mu;
}

std::vector<long> variables_of(const std::vector<std::uint8_t> &member, std::size_t anchor) {
    std::vector<long> variable(member.size(), -1);
    long next = 0;
    for (std::size_t i = 0; i < member.size(); ++i)
        if (member[i] && i != anchor) variable[i] = next++;
    return variable;
}

} // namespace

double edge_chi2(const PoseGraphEdge &edge, const std::vector<Rigid> &poses) {
    const Vector6d xi = se3_log(edge.measured.inverse() * (poses[edge.target].inverse() * poses[edge.source]));
    return xi.dot(edge.information * xi);
}

PoseGraphSolution optimize_pose_graph(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges,
                                      std::size_t anchor, double bound, const std::atomic<int> *cancel) {
    const std::size_t m = edges.size();
    PoseGraphSolution out;
    Consensus consensus = edge_consensus(num_nodes, edges, anchor, kConsensusSlack * bound, cancel);
    out.poses = std::move(consensus.poses);
    const std::vector<std::uint8_t> &reached = consensus.reached;

    // Every edge inside the anchor's reach that agrees with the consensus takes part; the robust ones are weighed.
    // The others wait until the end, when those that fit the solution after all are taken back.
    std::vector<double> weight(m, 0.0);
    std::vector<std::uint8_t> screened(m, 0);
    for (std::size_t e = 0; e < m; ++e) {
        if (!reached[edges[e].source]) continue;
        weight[e] = consensus.agrees[e] ? 1.0 : 0.0;
        screened[e] = consensus.agrees[e] ? 0 : 1;
    }
    std::vector<long> variable = variables_of(reached, anchor);
    LmOptions options;
    // One analysis for the start and every graduated round, on the edges that agree with the consensus; again when
    // the placed nodes change or edges set aside are taken back (pose_graph_lm.hpp).
    LmWorkspace workspace;
    // The least-squares start of the robust rounds need not be converged (with wrong edges in it, it crawls);
    // without wrong edges the accepted edges' optimum below finishes it.
    LmOptions start = options;
    start.max_iterations = kStartIterations;
    start.relative_tolerance = kStartTolerance;
    start.step_tolerance = std::numeric_limits<double>::infinity();
    // Each solve up to the last round leaves every edge's error at its poses: the weights are computed from them,
    // and the next round's solve starts from them, so that each round takes one logarithm per edge, not three.
    EdgeErrors errors;
    levenberg_marquardt(edges, weight, variable, out.poses, start, workspace, cancel, &errors);

    std::vector<double> r2(m, 0.0);
    auto residuals = [&] {
        for (std::size_t e = 0; e < m; ++e)
            r2[e] = reached[edges[e].source] ? errors.xi[e].dot(edges[e].information * errors.xi[e]) : 0.0;
    };
    residuals();
    double worst = 0.0;
    for (std::size_t e = 0; e < m; ++e)
        if (edges[e].robust && reached[edges[e].source] && !screened[e]) worst = std::max(worst, r2[e]);
    if (worst > bound) {
        double mu = bound / (2.0 * worst - bound);
        LmOptions round = options;
        round.max_iterations = kRoundIterations;
        round.relative_tolerance = 1e-6;
        round.step_tolerance = std::numeric_limits<double>::infinity();
        for (int k = 0; k < kMaxRounds; ++k) {
            bool binary = true;
            for (std::size_t e = 0; e < m; ++e) {
                if (!edges[e].robust || !reached[edges[e].source] || screened[e]) continue;
                weight[e] = tls_weight(r2[e], bound, mu);
                binary = binary && (weight[e] == 0.0 || weight[e] == 1.0);
            }
            levenberg_marquardt(edges, weight, variable, out.poses, round, workspace, cancel, &errors);
            residuals();
            if (binary) break;
            mu *= kMuGrowth;
        }
        for (std::size_t e = 0; e < m; ++e)
            if (edges[e].robust) weight[e] = weight[e] >= 0.5 ? 1.0 : 0.0;
    }

    // The accepted edges' own optimum over the nodes they place, so that no edge that is not accepted weighs on it;
    // an accepted robust edge that ends above the bound after all is rejected (the worst first) and the rest
    // re-solved, and after kFinalPasses every one still above it goes at once.
    std::vector<std::uint8_t> use(m);
    auto solve_accepted = [&] {
        for (std::size_t e = 0; e < m; ++e) use[e] = weight[e] > 0.0 || !edges[e].robust ? 1 : 0;
        out.component = components(num_nodes, edges, use);
        out.placed.assign(num_nodes, 0);
        for (std::size_t i = 0; i < num_nodes; ++i) out.placed[i] = out.component[i] == out.component[anchor] ? 1 : 0;
        variable = variables_of(out.placed, anchor);
        levenberg_marquardt(edges, weight, variable, out.poses, options, workspace, cancel);
    };
    auto settle = [&] {
        for (int pass = 0;; ++pass) {
            solve_accepted();
            std::size_t worst_edge = m;
            double worst_r2 = bound;
            auto judged = [&](std::size_t e) {
                return edges[e].robust && weight[e] > 0.0 && out.placed[edges[e].source] && out.placed[edges[e].target];
            };
            for (std::size_t e = 0; e < m; ++e) {
                if (!judged(e)) continue;
                const double v = edge_chi2(edges[e], out.poses);
                if (v > worst_r2) worst_r2 = v, worst_edge = e;
            }
            if (worst_edge == m) return;
            if (pass + 1 >= kFinalPasses) {
                for (std::size_t e = 0; e < m; ++e)
                    if (judged(e) && edge_chi2(edges[e], out.poses) > bound) weight[e] = 0.0;
                solve_accepted();
                return;
            }
            weight[worst_edge] = 0.0;
        }
    };
    settle();
    // An edge the consensus set aside that fits the solution within the bound is taken back (the consensus judged
    // it against tree poses, not against the optimum), and the rest settles again.
    bool taken_back = false;
    for (std::size_t e = 0; e < m; ++e) {
        if (!screened[e] || !out.placed[edges[e].source] || !out.placed[edges[e].target]) continue;
        if (edge_chi2(edges[e], out.poses) <= bound) weight[e] = 1.0, taken_back = true;
    }
    if (taken_back) settle();

    out.accepted.assign(m, 0);
    out.residual.assign(m, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t e = 0; e < m; ++e) {
        const bool placed = out.placed[edges[e].source] && out.placed[edges[e].target];
        if (!placed) continue;
        out.accepted[e] = weight[e] > 0.0 ? 1 : 0;
        out.residual[e] = edge_chi2(edges[e], out.poses);
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (std::size_t i = 0; i < num_nodes; ++i)
        if (!out.placed[i]) out.poses[i] = Rigid{Eigen::Matrix3d::Constant(nan), Eigen::Vector3d::Constant(nan)};
    return out;
}

KISSM_DETAIL_END
