// SPDX-License-Identifier: MIT
#include "pose_graph_lm.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "failure.hpp"

KISSM_DETAIL_BEGIN

namespace {

// The relative rounding of a cost summed over thousands of edges: changes below it are noise, not progress.
constexpr double kCostRounding = 1e-14;

void check_cancel(const std::atomic<int> *cancel) {
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed) != 0)
        fail(ErrorKind::Cancelled, "the optimisation was cancelled");
}

// The error xi = Log(inv(T) inv(X_t) X_s) of an edge.
Vector6d edge_error(const PoseGraphEdge &e, const std::vector<Rigid> &poses) {
    return se3_log(e.measured.inverse() * (poses[e.target].inverse() * poses[e.source]));
}

// The weighted cost sum_e w_e xi_e^T I_e xi_e, summed in the edges' order; each counted edge's error is kept in
// errors for the linearisation at the same poses (the logarithm is the dearest part of both). With `every`, the
// errors of the edges that do not count (weight 0, both nodes fixed) are kept too, for a caller that weighs them.
double total_cost(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
                  const std::vector<long> &variable, const std::vector<Rigid> &poses, std::vector<Vector6d> &errors,
                  bool every) {
    errors.resize(edges.size());
    double cost = 0.0;
    for (std::size_t i = 0; i < edges.size(); ++i) {
        const PoseGraphEdge &e = edges[i];
        const bool counted = weights[i] != 0.0 && (variable[e.source] >= 0 || variable[e.target] >= 0);
        if (!counted && !every) continue;
        errors[i] = edge_error(e, poses);
        if (counted) cost += weights[i] * errors[i].dot(e.information * errors[i]);
    }
    return cost;
}

// The same cost from errors already known at the poses.
double known_cost(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
                  const std::vector<long> &variable, const std::vector<Vector6d> &errors) {
    double cost = 0.0;
    for (std::size_t i = 0; i < edges.size(); ++i) {
        const PoseGraphEdge &e = edges[i];
        if (weights[i] == 0.0 || (variable[e.source] < 0 && variable[e.target] < 0)) continue;
        cost += weights[i] * errors[i].dot(e.information * errors[i]);
    }
    return cost;
}

// The pattern of the normal equations: one off-diagonal block per pair of variable nodes joined by an edge of
// non-zero weight (edges between the same two nodes share it). The weights may change while the pattern stays, as
// long as every edge of non-zero weight has its block: an edge that falls to 0 keeps its block as explicit zeros
// (the graduated rounds, the final solves' rejections reuse the analysis), and the analysis is redone only when an
// edge of weight 0 takes part again without one (the consensus's edges taken back at the end). Leaving out the edges
// the consensus set aside thins the fill: on the benchmark's 10,000-node drive with 30% wrong closures, without its
// 315 set aside a factorisation takes 140,364 block products instead of 414,690 (docs/pose-graph.md).
void prepare(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
             const std::vector<long> &variable, long num_vars, LmWorkspace &ws) {
    auto joins = [&](std::size_t i) {
        const long vs = variable[edges[i].source], vt = variable[edges[i].target];
        return vs >= 0 && vt >= 0 && vs != vt;
    };
    if (ws.num_edges == edges.size() && ws.variable == variable) {
        bool covered = true;
        for (std::size_t i = 0; i < edges.size() && covered; ++i)
            covered = weights[i] == 0.0 || ws.edge_pair[i] >= 0 || !joins(i);
        if (covered) return;
    }
    ws.variable.clear();                      // until the analysis below has succeeded (it can throw std::bad_alloc)
    std::vector<std::pair<long, long>> keyed; // (min, max) per edge joining two variables
    std::vector<std::size_t> by_key;
    for (std::size_t i = 0; i < edges.size(); ++i) {
        if (!joins(i)) continue;
        const long vs = variable[edges[i].source], vt = variable[edges[i].target];
        keyed.emplace_back(std::min(vs, vt), std::max(vs, vt));
        by_key.push_back(i);
    }
    std::vector<std::size_t> sorted(keyed.size());
    for (std::size_t k = 0; k < sorted.size(); ++k) sorted[k] = k;
    std::sort(sorted.begin(), sorted.end(),
              [&](std::size_t a, std::size_t b) { return keyed[a] != keyed[b] ? keyed[a] < keyed[b] : a < b; });
    // A block for each pair that an edge of non-zero weight joins, shared by every edge between the two nodes.
    std::vector<std::pair<long, long>> pairs;
    ws.edge_pair.assign(edges.size(), -1);
    for (std::size_t begin = 0, end = 0; begin < sorted.size(); begin = end) {
        bool weighed = false;
        for (end = begin; end < sorted.size() && keyed[sorted[end]] == keyed[sorted[begin]]; ++end)
            weighed = weighed || weights[by_key[sorted[end]]] != 0.0;
        if (!weighed) continue;
        pairs.push_back(keyed[sorted[begin]]);
        for (std::size_t k = begin; k < end; ++k) ws.edge_pair[by_key[sorted[k]]] = static_cast<long>(pairs.size()) - 1;
    }
    ws.ldlt.analyse(num_vars, pairs);
    ws.diagonal.assign(static_cast<std::size_t>(num_vars), Matrix6d::Zero());
    ws.damped.assign(static_cast<std::size_t>(num_vars), Matrix6d::Zero());
    ws.off.assign(pairs.size(), Matrix6d::Zero());
    ws.num_edges = edges.size();
    ws.variable = variable;
}

// The normal equations H d = -b at the poses, into the workspace's blocks (pair (a, b) holds H_ab) and b; the edges
// are summed in the order they were added.
void assemble(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
              const std::vector<long> &variable, const std::vector<Rigid> &poses, const std::vector<Vector6d> &errors,
              LmWorkspace &ws, Eigen::VectorXd &b) {
    for (Matrix6d &block : ws.diagonal) block.setZero();
    for (Matrix6d &block : ws.off) block.setZero();
    b.setZero();
    for (std::size_t i = 0; i < edges.size(); ++i) {
        const PoseGraphEdge &e = edges[i];
        const long vs = variable[e.source], vt = variable[e.target];
        if ((vs < 0 && vt < 0) || weights[i] == 0.0) continue; // a weight of 0 adds nothing
        // The Jacobians for right perturbations X <- X Exp(d): J_s = J_r^-1(xi), J_t = -J_s Ad(inv(X_s) X_t). With
        // H_ss = J_s^T W J_s, the other blocks follow by the adjoint alone: H_st = -H_ss Ad, H_tt = Ad^T H_ss Ad,
        // and b_t = -Ad^T b_s (two 6x6 products fewer per edge than forming J_t).
        const Vector6d &error = errors[i];
        const Matrix6d jri = se3_right_jacobian_inverse(error);
        const Matrix6d adjoint = se3_adjoint(poses[e.source].inverse() * poses[e.target]);
        const Matrix6d wi = weights[i] * e.information;
        if (vs == vt) { // both ends on one node: its Jacobian is the sum
            const Matrix6d j = jri - jri * adjoint;
            const Matrix6d jtw = j.transpose() * wi;
            ws.diagonal[vs].noalias() += jtw * j;
            b.segment<6>(6 * vs).noalias() += jtw * error;
            continue;
        }
        Matrix6d jtw, hss, n;
        jtw.noalias() = jri.transpose() * wi;
        hss.noalias() = jtw * jri;
        const Vector6d gs = jtw * error;
        if (vs >= 0) {
            ws.diagonal[vs] += hss;
            b.segment<6>(6 * vs) += gs;
        }
        n.noalias() = hss * adjoint; // -H_st
        if (vt >= 0) {
            ws.diagonal[vt].noalias() += adjoint.transpose() * n;
            b.segment<6>(6 * vt).noalias() -= adjoint.transpose() * gs;
        }
        if (vs >= 0 && vt >= 0) {
            // The pair is stored as (smaller, larger) variable: H_{min,max}.
            if (vs < vt)
                ws.off[ws.edge_pair[i]] -= n;
            else
                ws.off[ws.edge_pair[i]] -= n.transpose();
        }
    }
}

} // namespace

double levenberg_marquardt(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
                           const std::vector<long> &variable, std::vector<Rigid> &poses, const LmOptions &options,
                           LmWorkspace &ws, const std::atomic<int> *cancel, EdgeErrors *known) {
    const long num_vars = variable.empty() ? 0 : *std::max_element(variable.begin(), variable.end()) + 1;
    const bool every = known != nullptr;
    std::vector<Vector6d> own_errors;
    std::vector<Vector6d> &errors = every ? known->xi : own_errors, &trial_errors = ws.trial_errors;
    double cost = every && known->current ? known_cost(edges, weights, variable, errors)
                                          : total_cost(edges, weights, variable, poses, errors, every);
    if (every) known->current = true; // from here on errors always hold the errors at poses
    if (num_vars <= 0) return cost;
    const Eigen::Index n = 6 * num_vars;
    prepare(edges, weights, variable, num_vars, ws);
    Eigen::VectorXd b(n), diagonal(n), step(n);
    double lambda = ws.lambda;
    std::vector<Rigid> &trial = ws.trial;
    for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
        check_cancel(cancel);
        assemble(edges, weights, variable, poses, errors, ws, b);
        for (long v = 0; v < num_vars; ++v) diagonal.segment<6>(6 * v) = ws.diagonal[v].diagonal();
        bool stepped = false;
        for (int attempt = 0; attempt < 30 && !stepped; ++attempt) {
            check_cancel(cancel);
            // A node whose every edge carries weight 0 (rejected loops) has no information: it stays where it is.
            for (long v = 0; v < num_vars; ++v) {
                ws.damped[v] = ws.diagonal[v];
                for (int r = 0; r < 6; ++r) {
                    const double h = diagonal[6 * v + r];
                    ws.damped[v](r, r) += h <= 0.0 ? lambda + 1.0 : lambda * h;
                }
            }
            if (!ws.ldlt.factorize(ws.damped, ws.off)) {
                lambda *= 10.0;
                continue;
            }
            step = -b;
            ws.ldlt.solve(step);
            trial = poses;
            for (std::size_t node = 0; node < variable.size(); ++node)
                if (variable[node] >= 0) trial[node] = poses[node] * se3_exp(step.segment<6>(6 * variable[node]));
            const double trial_cost = total_cost(edges, weights, variable, trial, trial_errors, every);
            if (trial_cost <= cost) {
                const double gain = cost - trial_cost;
                poses.swap(trial);
                errors.swap(trial_errors);
                cost = trial_cost;
                lambda = std::max(lambda / 10.0, 1e-12);
                ws.lambda = lambda;
                stepped = true;
                const double moved = step.lpNorm<Eigen::Infinity>();
                if ((gain <= options.relative_tolerance * std::max(cost, 1e-300) && moved <= options.step_tolerance) ||
                    gain <= kCostRounding * cost || moved < 1e-14)
                    return cost;
            } else if (trial_cost - cost <= kCostRounding * cost) {
                return cost; // a step within the cost's rounding: a minimum to the precision of doubles
            } else {
                lambda *= 10.0;
            }
        }
        if (!stepped) return cost; // no step lowers the cost: a minimum to the precision of doubles
    }
    return cost;
}

KISSM_DETAIL_END
