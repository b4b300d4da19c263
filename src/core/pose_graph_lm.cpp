// SPDX-License-Identifier: MIT
#include "pose_graph_lm.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "failure.hpp"

KISSM_DETAIL_BEGIN

namespace {

// The relative rounding of a cost summed over thousands of edges: changes below it are noise, not progress.
constexpr double kCostRounding = 1e-14;

void check_cancel(const std::atomic<int> *cancel) {
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed) != 0)
        fail(ErrorKind::Cancelled, "the optimisation was cancelled");
}

// The error of an edge and its Jacobians for right perturbations X <- X Exp(d) of its source and target.
struct Linearised {
    Vector6d error;
    Matrix6d d_source, d_target;
};

Linearised linearise(const PoseGraphEdge &e, const std::vector<Rigid> &poses) {
    const Rigid between = poses[e.target].inverse() * poses[e.source]; // inv(X_t) X_s
    Linearised out;
    out.error = se3_log(e.measured.inverse() * between);
    const Matrix6d jri = se3_right_jacobian_inverse(out.error);
    out.d_source = jri;
    out.d_target = -jri * se3_adjoint(between.inverse());
    return out;
}

double total_cost(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
                  const std::vector<long> &variable, const std::vector<Rigid> &poses) {
    double cost = 0.0;
    for (std::size_t i = 0; i < edges.size(); ++i) {
        const PoseGraphEdge &e = edges[i];
        if (weights[i] == 0.0 || (variable[e.source] < 0 && variable[e.target] < 0)) continue;
        cost += weights[i] * edge_chi2(e, poses);
    }
    return cost;
}

} // namespace

double levenberg_marquardt(const std::vector<PoseGraphEdge> &edges, const std::vector<double> &weights,
                           const std::vector<long> &variable, std::vector<Rigid> &poses, const LmOptions &options,
                           const std::atomic<int> *cancel) {
    const long num_vars = variable.empty() ? 0 : *std::max_element(variable.begin(), variable.end()) + 1;
    double cost = total_cost(edges, weights, variable, poses);
    if (num_vars <= 0) return cost;
    const Eigen::Index n = 6 * num_vars;
    // The sparsity pattern holds every edge's blocks, weighted or not, so one symbolic analysis serves all steps.
    std::vector<Eigen::Triplet<double>> triplets;
    Eigen::SparseMatrix<double> H(n, n);
    Eigen::VectorXd b(n), diagonal(n);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
    bool analysed = false;
    double lambda = 1e-6;
    std::vector<Rigid> trial;
    for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
        check_cancel(cancel);
        triplets.clear();
        b.setZero();
        for (std::size_t i = 0; i < edges.size(); ++i) {
            const PoseGraphEdge &e = edges[i];
            const long vs = variable[e.source], vt = variable[e.target];
            if (vs < 0 && vt < 0) continue;
            const double w = weights[i];
            const Linearised lin = linearise(e, poses);
            const Matrix6d wi = w * e.information;
            const long vars[2] = {vs, vt};
            const Matrix6d *jac[2] = {&lin.d_source, &lin.d_target};
            for (int a = 0; a < 2; ++a) {
                if (vars[a] < 0) continue;
                const Eigen::Matrix<double, 6, 6> jtw = jac[a]->transpose() * wi;
                b.segment<6>(6 * vars[a]) += jtw * lin.error;
                for (int c = 0; c < 2; ++c) {
                    if (vars[c] < 0 || vars[c] > vars[a]) continue; // the lower triangle only
                    const Matrix6d block = jtw * *jac[c];
                    for (int r = 0; r < 6; ++r)
                        for (int q = 0; q < 6; ++q)
                            if (vars[a] != vars[c] || q <= r)
                                triplets.emplace_back(6 * vars[a] + r, 6 * vars[c] + q, block(r, q));
                }
            }
        }
        for (Eigen::Index k = 0; k < n; ++k) triplets.emplace_back(k, k, 0.0); // the damping's slots
        H.setFromTriplets(triplets.begin(), triplets.end());
        diagonal = H.diagonal();
        // A node whose every edge carries weight 0 (rejected loops) has no information: it stays where it is.
        for (Eigen::Index k = 0; k < n; ++k)
            if (diagonal[k] <= 0.0) diagonal[k] = 1.0;
        if (!analysed) {
            ldlt.analyzePattern(H);
            analysed = true;
        }
        bool stepped = false;
        for (int attempt = 0; attempt < 30 && !stepped; ++attempt) {
            check_cancel(cancel);
            Eigen::SparseMatrix<double> damped = H;
            for (Eigen::Index k = 0; k < n; ++k)
                damped.coeffRef(k, k) += lambda * diagonal[k] + (H.coeff(k, k) <= 0.0 ? 1.0 : 0.0);
            ldlt.factorize(damped);
            if (ldlt.info() != Eigen::Success) {
                lambda *= 10.0;
                continue;
            }
            const Eigen::VectorXd step = ldlt.solve(-b);
            trial = poses;
            for (std::size_t node = 0; node < variable.size(); ++node)
                if (variable[node] >= 0) trial[node] = poses[node] * se3_exp(step.segment<6>(6 * variable[node]));
            const double trial_cost = total_cost(edges, weights, variable, trial);
            if (trial_cost <= cost) {
                const double gain = cost - trial_cost;
                poses.swap(trial);
                cost = trial_cost;
                lambda = std::max(lambda / 10.0, 1e-12);
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
