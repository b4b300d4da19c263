// SPDX-License-Identifier: MIT
#include "pose_graph_consensus.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include <Eigen/Cholesky>

#include "../common/splitmix64.h"
#include "failure.hpp"
#include "pose_graph_tree.hpp"

KISSM_DETAIL_BEGIN

namespace {

// Trees are drawn until one whose robust edges are all right was drawn with this probability (by the agreeing share
// seen so far), up to kMaxTrees or kMaxChecks edge checks in all (a large graph whose trusted edges leave many robust
// ones in every tree gets the ordered tree and a few random ones, then the rounds of the optimisation).
constexpr double kConfidence = 0.999;
constexpr std::size_t kMaxTrees = 1000;
constexpr std::size_t kMaxChecks = 2'000'000;
constexpr std::uint64_t kSeed = 0x6b69736d2d706731ULL; // fixed: the same graph gives the same trees

struct EdgeModel {
    Matrix6d covariance;         // inverse information: the measured pose's right perturbation
    Matrix6d inverse_covariance; // the same for inv(measured): Ad(T) cov Ad(T)^T
    double order_key = 0.0;      // log-determinant of the information (the ordered tree's priority)
};

EdgeModel model_of(const PoseGraphEdge &e) {
    EdgeModel m;
    const Eigen::LLT<Matrix6d> llt(e.information);
    m.covariance = llt.solve(Matrix6d::Identity());
    m.covariance = 0.5 * (m.covariance + m.covariance.transpose()).eval();
    const Matrix6d ad = se3_adjoint(e.measured);
    m.inverse_covariance = ad * m.covariance * ad.transpose();
    m.order_key = 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
    return m;
}

class TreeEvaluator {
public:
    TreeEvaluator(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges, const std::vector<EdgeModel> &models,
                  std::size_t anchor)
        : n_(num_nodes), edges_(edges), models_(models), anchor_(anchor), adjacency_(num_nodes) {}

    // Kruskal over the edges in `order` (trusted ones first by the caller): in_tree marks the tree's edges.
    void build(const std::vector<std::size_t> &order) {
        parent_.resize(n_);
        std::iota(parent_.begin(), parent_.end(), std::size_t{0});
        in_tree.assign(edges_.size(), 0);
        for (auto &list : adjacency_) list.clear();
        for (std::size_t e : order) {
            const std::size_t a = union_find_root(parent_, edges_[e].source),
                              b = union_find_root(parent_, edges_[e].target);
            if (a == b) continue;
            parent_[std::max(a, b)] = std::min(a, b);
            in_tree[e] = 1;
            adjacency_[edges_[e].source].push_back(e);
            adjacency_[edges_[e].target].push_back(e);
        }
        place();
    }

    // The squared error of edge e against the tree's poses, with the covariance of the edge and of both nodes'
    // placements relative to the tree path's turning point (their lowest common ancestor): the part of the path
    // both share cancels out of their relative pose, so a loop closure along a long drive is checked against the
    // odometry between its two ends, not against everything from the root.
    double chi2(std::size_t e) const {
        const PoseGraphEdge &edge = edges_[e];
        const std::size_t turn = common_ancestor(edge.source, edge.target);
        const Rigid q = poses[edge.target].inverse() * poses[edge.source];
        const Vector6d xi = se3_log(edge.measured.inverse() * q);
        const Matrix6d ad = se3_adjoint(q.inverse());
        const Matrix6d c =
            models_[e].covariance + ad * below(edge.target, turn) * ad.transpose() + below(edge.source, turn);
        const Eigen::LLT<Matrix6d> llt(0.5 * (c + c.transpose()));
        if (llt.info() != Eigen::Success) return 0.0; // a covariance without a scale cannot contradict
        return xi.dot(llt.solve(xi));
    }

    std::vector<std::uint8_t> in_tree;
    std::vector<Rigid> poses;
    std::vector<std::uint8_t> reached; // the anchor's component

private:
    std::size_t common_ancestor(std::size_t a, std::size_t b) const {
        while (depth_[a] > depth_[b]) a = up_[a];
        while (depth_[b] > depth_[a]) b = up_[b];
        while (a != b) a = up_[a], b = up_[b];
        return a;
    }

    // The covariance of node's placement relative to its ancestor: the root-relative one less the ancestor's,
    // moved into the node's frame (the propagation in place() is linear, so this is what a walk from the ancestor
    // would have summed).
    Matrix6d below(std::size_t node, std::size_t ancestor) const {
        if (node == ancestor) return Matrix6d::Zero();
        const Matrix6d ad = se3_adjoint((poses[ancestor].inverse() * poses[node]).inverse());
        return covariance_[node] - ad * covariance_[ancestor] * ad.transpose();
    }

    // Poses and covariances along the tree from each component's root: the anchor's component from the anchor, the
    // others from their smallest node. A child c of p through measured pose P (X_c = X_p P) inherits p's
    // uncertainty moved into its frame, Ad(inv P) cov_p Ad(inv P)^T, plus the edge's own.
    void place() {
        poses.assign(n_, Rigid{});
        covariance_.assign(n_, Matrix6d::Zero());
        up_.assign(n_, 0);
        depth_.assign(n_, 0);
        std::vector<std::uint8_t> seen(n_, 0);
        std::vector<std::size_t> queue;
        auto walk = [&](std::size_t root) {
            seen[root] = 1;
            up_[root] = root;
            queue.assign(1, root);
            for (std::size_t k = 0; k < queue.size(); ++k) {
                const std::size_t p = queue[k];
                for (std::size_t e : adjacency_[p]) {
                    const PoseGraphEdge &edge = edges_[e];
                    const bool child_is_source = edge.target == p;
                    const std::size_t c = child_is_source ? edge.source : edge.target;
                    if (seen[c]) continue;
                    seen[c] = 1;
                    up_[c] = p;
                    depth_[c] = depth_[p] + 1;
                    const Rigid step = child_is_source ? edge.measured : edge.measured.inverse();
                    const Matrix6d ad = se3_adjoint(step.inverse());
                    poses[c] = poses[p] * step;
                    covariance_[c] = ad * covariance_[p] * ad.transpose() +
                                     (child_is_source ? models_[e].covariance : models_[e].inverse_covariance);
                    queue.push_back(c);
                }
            }
        };
        walk(anchor_);
        reached = seen;
        for (std::size_t i = 0; i < n_; ++i)
            if (!seen[i]) walk(i);
    }

    std::size_t n_;
    const std::vector<PoseGraphEdge> &edges_;
    const std::vector<EdgeModel> &models_;
    std::size_t anchor_;
    std::vector<std::vector<std::size_t>> adjacency_;
    std::vector<std::size_t> parent_;
    std::vector<Matrix6d> covariance_; // of each placement relative to its tree's root
    std::vector<std::size_t> up_, depth_;
};

// How many trees make one with only right robust edges likely, when `share` of the robust edges are right and a
// tree holds `in_tree` of them.
std::size_t trees_needed(double share, std::size_t in_tree) {
    const double all_right = std::pow(share, static_cast<double>(in_tree));
    if (all_right >= 1.0) return 1;
    if (all_right <= 0.0) return kMaxTrees;
    const double needed = std::ceil(std::log(1.0 - kConfidence) / std::log1p(-all_right));
    return needed >= static_cast<double>(kMaxTrees) ? kMaxTrees : static_cast<std::size_t>(needed);
}

} // namespace

Consensus edge_consensus(std::size_t num_nodes, const std::vector<PoseGraphEdge> &edges, std::size_t anchor,
                         double gate, const std::atomic<int> *cancel) {
    const std::size_t m = edges.size();
    std::vector<EdgeModel> models;
    models.reserve(m);
    for (const PoseGraphEdge &e : edges) models.push_back(model_of(e));

    std::vector<std::size_t> trusted, robust;
    for (std::size_t e = 0; e < m; ++e) (edges[e].robust ? robust : trusted).push_back(e);
    // The first tree: robust edges by information, most informative first (ties by edge number).
    std::vector<std::size_t> ordered = robust;
    std::stable_sort(ordered.begin(), ordered.end(),
                     [&](std::size_t a, std::size_t b) { return models[a].order_key > models[b].order_key; });

    TreeEvaluator tree(num_nodes, edges, models, anchor);
    Consensus best;
    std::size_t best_agreeing = 0;
    double best_error = 0.0;
    std::vector<std::size_t> order;
    std::vector<std::pair<double, std::size_t>> keyed(robust.size());
    std::uint64_t state = kSeed;
    std::size_t needed = 1, checks = 0;
    for (std::size_t k = 0; k < needed && k < kMaxTrees && (k == 0 || checks < kMaxChecks); ++k) {
        if (cancel && cancel->load(std::memory_order_relaxed))
            fail(ErrorKind::Cancelled, "the optimisation was cancelled");
        order = trusted;
        if (k == 0) {
            order.insert(order.end(), ordered.begin(), ordered.end());
        } else {
            for (std::size_t i = 0; i < robust.size(); ++i) keyed[i] = {splitmix64_uniform(&state), robust[i]};
            std::sort(keyed.begin(), keyed.end());
            for (const auto &item : keyed) order.push_back(item.second);
        }
        tree.build(order);
        std::size_t agreeing = 0, robust_in_tree = 0;
        double error = 0.0;
        std::vector<std::uint8_t> agrees(m, 0);
        for (std::size_t e = 0; e < m; ++e) {
            if (!edges[e].robust || tree.in_tree[e]) {
                agrees[e] = 1;
                robust_in_tree += edges[e].robust ? 1 : 0;
                continue;
            }
            const double r2 = tree.chi2(e);
            ++checks;
            if (r2 <= gate) agrees[e] = 1, ++agreeing, error += r2;
        }
        // The most agreeing edges win; among equals the smaller total error, then the earlier tree.
        if (k == 0 || agreeing > best_agreeing || (agreeing == best_agreeing && error < best_error)) {
            best_agreeing = agreeing, best_error = error;
            best.agrees = std::move(agrees);
            best.poses = tree.poses;
            best.reached = tree.reached;
        }
        const double share =
            robust.empty() ? 1.0
                           : static_cast<double>(best_agreeing + robust_in_tree) / static_cast<double>(robust.size());
        needed = trees_needed(share, robust_in_tree);
        best.trees = k + 1;
    }
    return best;
}

KISSM_DETAIL_END
