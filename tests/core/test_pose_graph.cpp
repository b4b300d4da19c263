// SPDX-License-Identifier: MIT
// The pose graph core: SE(3)'s exponential, logarithm and right Jacobian against finite differences; the optimum of
// consistent and noisy graphs (exact poses, a vanishing gradient); wrong robust edges rejected without bending the
// map, also when every edge is a candidate; unplaced nodes; the factorisation's pattern following the weights;
// bitwise repeatability; cancellation.
#include <atomic>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <Eigen/LU>

#include "core/failure.hpp"
#include "core/pose_graph.hpp"
#include "core/pose_graph_lm.hpp"
#include "core/se3.hpp"
#include "harness.h"

using namespace kissm::detail;

namespace {

Vector6d random_xi(std::mt19937 &rng, double rot, double trans) {
    std::normal_distribution<double> n(0.0, 1.0);
    Vector6d xi;
    for (int k = 0; k < 3; ++k) xi[k] = rot * n(rng);
    for (int k = 3; k < 6; ++k) xi[k] = trans * n(rng);
    return xi;
}

double pose_distance(const Rigid &a, const Rigid &b) { return se3_log(a.inverse() * b).norm(); }

void test_exp_log_round_trip() {
    std::mt19937 rng(1);
    for (int i = 0; i < 200; ++i) {
        Vector6d xi = random_xi(rng, i < 50 ? 1e-6 : 0.8, 3.0);
        if (xi.head<3>().norm() > 3.0) xi.head<3>() *= 3.0 / xi.head<3>().norm(); // below pi: Log's own range
        const Vector6d back = se3_log(se3_exp(xi));
        CHECK_MSG((back - xi).norm() < 1e-9 * (1.0 + xi.norm()), "round trip %d off by %g", i, (back - xi).norm());
        const Rigid T = se3_exp(xi);
        CHECK((T.R.transpose() * T.R - Eigen::Matrix3d::Identity()).norm() < 1e-12 && T.R.determinant() > 0.0);
    }
}

void test_right_jacobian_inverse_matches_finite_differences() {
    std::mt19937 rng(2);
    for (int i = 0; i < 60; ++i) {
        Vector6d xi = random_xi(rng, i < 20 ? 1e-5 : 0.9, 2.0);
        if (i == 59) xi << 3.0, 0.5, -0.2, 1.0, 2.0, 3.0; // near a half turn
        const Matrix6d J = se3_right_jacobian_inverse(xi);
        const Rigid T = se3_exp(xi);
        const double h = 1e-6;
        Matrix6d numeric;
        for (int k = 0; k < 6; ++k) {
            Vector6d d = Vector6d::Zero();
            d[k] = h;
            numeric.col(k) = (se3_log(T * se3_exp(d)) - se3_log(T * se3_exp(-d))) / (2.0 * h);
        }
        CHECK_MSG((numeric - J).cwiseAbs().maxCoeff() < 1e-6, "xi %d: J_r^-1 off by %g", i,
                  (numeric - J).cwiseAbs().maxCoeff());
    }
}

void test_adjoint() {
    std::mt19937 rng(3);
    const Rigid T = se3_exp(random_xi(rng, 0.7, 2.0));
    const Vector6d xi = random_xi(rng, 0.3, 0.5);
    const Rigid lhs = T * se3_exp(xi) * T.inverse(), rhs = se3_exp(se3_adjoint(T) * xi);
    CHECK(pose_distance(lhs, rhs) < 1e-12);
}

// A loop of n nodes on a circle with every node joined to the next (trusted odometry) and loop closures.
struct Loop {
    std::vector<Rigid> truth;
    std::vector<PoseGraphEdge> edges;
};

PoseGraphEdge between(const std::vector<Rigid> &truth, std::size_t s, std::size_t t, bool robust, const Rigid &noise,
                      double sigma_rot, double sigma_trans) {
    PoseGraphEdge e;
    e.source = s;
    e.target = t;
    e.measured = truth[t].inverse() * truth[s] * noise;
    e.information = Matrix6d::Zero();
    e.information.diagonal() << Vector6d::Constant(1.0 / (sigma_rot * sigma_rot)).head<3>(),
        Vector6d::Constant(1.0 / (sigma_trans * sigma_trans)).head<3>();
    e.robust = robust;
    return e;
}

Loop make_loop(std::size_t n, double noise_rot, double noise_trans, unsigned seed) {
    std::mt19937 rng(seed);
    Loop loop;
    for (std::size_t i = 0; i < n; ++i) {
        const double a = 2.0 * M_PI * static_cast<double>(i) / static_cast<double>(n);
        Vector6d xi;
        xi << 0.05 * std::sin(3.0 * a), 0.03, a, 20.0 * std::cos(a), 20.0 * std::sin(a), 0.5 * std::sin(2.0 * a);
        loop.truth.push_back(se3_exp(xi));
    }
    const double sr = std::max(noise_rot, 1e-3), st = std::max(noise_trans, 1e-2);
    for (std::size_t i = 0; i + 1 < n; ++i)
        loop.edges.push_back(
            between(loop.truth, i + 1, i, false, se3_exp(random_xi(rng, noise_rot, noise_trans)), sr, st));
    for (std::size_t i = 0; i + 5 < n; i += 3)
        loop.edges.push_back(
            between(loop.truth, i, i + 5, true, se3_exp(random_xi(rng, noise_rot, noise_trans)), sr, st));
    loop.edges.push_back(between(loop.truth, n - 1, 0, true, se3_exp(random_xi(rng, noise_rot, noise_trans)), sr, st));
    return loop;
}

// The truth seen from node 0.
Rigid anchored(const Loop &l, std::size_t i) { return l.truth[0].inverse() * l.truth[i]; }

void test_consistent_graph_is_exact() {
    const Loop l = make_loop(30, 0.0, 0.0, 4);
    const PoseGraphSolution s = optimize_pose_graph(30, l.edges, 0, 22.4577, nullptr);
    for (std::size_t i = 0; i < 30; ++i) {
        CHECK(s.placed[i] == 1 && s.component[i] == 0);
        CHECK_MSG(pose_distance(s.poses[i], anchored(l, i)) < 1e-9, "node %zu off by %g", i,
                  pose_distance(s.poses[i], anchored(l, i)));
    }
    for (std::size_t e = 0; e < l.edges.size(); ++e) CHECK(s.accepted[e] == 1 && s.residual[e] < 1e-12);
}

// At the optimum of a noisy graph the cost's gradient vanishes: no small move of a node lowers it.
void test_noisy_graph_is_a_minimum() {
    const Loop l = make_loop(25, 0.01, 0.05, 5);
    const PoseGraphSolution s = optimize_pose_graph(25, l.edges, 0, 1e9, nullptr);
    auto cost = [&](const std::vector<Rigid> &p) {
        double c = 0.0;
        for (const PoseGraphEdge &e : l.edges) c += edge_chi2(e, p);
        return c;
    };
    const double c0 = cost(s.poses);
    double worst = 0.0;
    for (std::size_t node = 1; node < 25; ++node)
        for (int k = 0; k < 6; ++k) {
            Vector6d d = Vector6d::Zero();
            d[k] = 1e-6;
            std::vector<Rigid> plus = s.poses, minus = s.poses;
            plus[node] = plus[node] * se3_exp(d);
            minus[node] = minus[node] * se3_exp(-d);
            worst = std::max(worst, std::abs(cost(plus) - cost(minus)) / 2e-6);
        }
    CHECK_MSG(worst < 1e-4 * (1.0 + c0), "gradient %g at cost %g", worst, c0);
    CHECK(s.poses[0].R.isApprox(Eigen::Matrix3d::Identity(), 0.0) && s.poses[0].t.isZero(0.0));  // the anchor stays
    for (std::size_t i = 0; i < 25; ++i) CHECK(pose_distance(s.poses[i], anchored(l, i)) < 2.0); // the noise's drift
}

// 30% of the loop closures replaced by random poses with confident information: all rejected, and the map where
// the graph without them puts it (not bent).
void test_wrong_loop_closures_are_rejected() {
    Loop dirty = make_loop(40, 0.002, 0.01, 6);
    std::mt19937 rng(7);
    std::vector<std::uint8_t> wrong(dirty.edges.size(), 0);
    std::size_t robust = 0, replaced = 0;
    for (std::size_t e = 0; e < dirty.edges.size(); ++e) {
        if (!dirty.edges[e].robust) continue;
        if (robust++ % 10 < 3) {
            dirty.edges[e].measured = se3_exp(random_xi(rng, 1.0, 10.0));
            wrong[e] = 1;
            ++replaced;
        }
    }
    CHECK(replaced >= 4);
    std::vector<PoseGraphEdge> without;
    for (std::size_t e = 0; e < dirty.edges.size(); ++e)
        if (!wrong[e]) without.push_back(dirty.edges[e]);
    const PoseGraphSolution a = optimize_pose_graph(40, without, 0, 22.4577, nullptr);
    const PoseGraphSolution b = optimize_pose_graph(40, dirty.edges, 0, 22.4577, nullptr);
    for (std::size_t e = 0; e < dirty.edges.size(); ++e)
        CHECK_MSG(b.accepted[e] == (wrong[e] ? 0 : 1), "edge %zu (wrong %d) accepted %d, residual %g", e, wrong[e],
                  b.accepted[e], b.residual[e]);
    for (std::size_t i = 0; i < 40; ++i) {
        CHECK(b.placed[i] == 1);
        const Rigid d = a.poses[i].inverse() * b.poses[i];
        const double angle = se3_log(d).head<3>().norm() * 180.0 / M_PI;
        CHECK_MSG(angle < 0.1 && d.t.norm() < 0.01, "node %zu moved %g deg %g m", i, angle, d.t.norm());
    }
}

// Every edge a candidate, as when every pair of a few tens of scans is registered (a turntable ring: each scan with
// its two next neighbours), and wrong edges with confident information added between random nodes, 30% as many as
// the right ones, over several draws: all rejected, and every pose where the graph without them puts it. The
// least-squares start of the rounds alone was bent by such edges (docs/pose-graph.md, "Consensus").
void test_wrong_candidates_in_an_all_robust_graph() {
    const std::size_t n = 15;
    std::vector<Rigid> truth;
    for (std::size_t i = 0; i < n; ++i) {
        Vector6d xi;
        xi << 0.0, 0.0, 2.0 * M_PI * static_cast<double>(i) / static_cast<double>(n), 0.1, 0.0, 0.02;
        truth.push_back(se3_exp(xi));
    }
    std::mt19937 rng(11);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<PoseGraphEdge> clean;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t step = 1; step <= 2; ++step) {
            // A registration's information: confident, anisotropic and correlated (a random factor of its covariance,
            // rotation sigmas about 1e-3, translation about 1e-4), and a noise drawn from it.
            Matrix6d factor = Matrix6d::Zero();
            for (int r = 0; r < 6; ++r)
                for (int c = 0; c <= r; ++c) factor(r, c) = (r < 3 ? 1e-3 : 1e-4) * (r == c ? 1.0 : 0.5) * normal(rng);
            for (int r = 0; r < 6; ++r) factor(r, r) = std::abs(factor(r, r)) + (r < 3 ? 3e-4 : 3e-5);
            Vector6d z;
            for (int k = 0; k < 6; ++k) z[k] = normal(rng);
            PoseGraphEdge e = between(truth, (i + step) % n, i, true, se3_exp(factor * z), 1.0, 1.0);
            const Matrix6d covariance = factor * factor.transpose();
            e.information = covariance.inverse();
            e.information = (0.5 * (e.information + e.information.transpose())).eval();
            clean.push_back(e);
        }
    const PoseGraphSolution a = optimize_pose_graph(n, clean, 0, 22.4577, nullptr);
    for (unsigned draw = 0; draw < 10; ++draw) {
        std::vector<PoseGraphEdge> dirty = clean;
        std::uniform_int_distribution<std::size_t> node(0, n - 1);
        while (dirty.size() < clean.size() + clean.size() * 3 / 10) {
            const std::size_t s = node(rng), t = node(rng);
            if (s == t) continue;
            PoseGraphEdge e = clean[dirty.size() % clean.size()]; // a right edge's information
            e.source = s, e.target = t;
            e.measured = se3_exp(random_xi(rng, 1.0, 0.5));
            dirty.push_back(e);
        }
        const PoseGraphSolution b = optimize_pose_graph(n, dirty, 0, 22.4577, nullptr);
        for (std::size_t e = 0; e < dirty.size(); ++e)
            CHECK_MSG(b.accepted[e] == (e < clean.size() ? 1 : 0), "draw %u edge %zu accepted %d, residual %g", draw, e,
                      b.accepted[e], b.residual[e]);
        for (std::size_t i = 0; i < n; ++i) {
            CHECK(b.placed[i] == 1);
            const Rigid d = a.poses[i].inverse() * b.poses[i];
            const double angle = se3_log(d).head<3>().norm() * 180.0 / M_PI;
            CHECK_MSG(angle < 0.01 && d.t.norm() < 1e-4, "draw %u node %zu moved %g deg %g m", draw, i, angle,
                      d.t.norm());
        }
    }
}

// A node joined only by a wrong robust edge that contradicts the rest is not placed; an isolated node neither.
void test_unplaced_nodes() {
    Loop l = make_loop(10, 0.0, 0.0, 8);
    std::vector<Rigid> truth = l.truth;
    truth.push_back(se3_exp(Vector6d::Constant(0.1)));
    truth.push_back(se3_exp(Vector6d::Constant(0.2)));
    truth.push_back(se3_exp(Vector6d::Constant(0.3)));
    // node 10: two robust edges that disagree by far; node 11 and 12 joined to each other only (trusted).
    l.edges.push_back(between(truth, 10, 0, true, Rigid{}, 0.001, 0.01));
    l.edges.push_back(between(truth, 10, 5, true, se3_exp(Vector6d::Constant(0.5)), 0.001, 0.01));
    l.edges.push_back(between(truth, 12, 11, false, Rigid{}, 0.001, 0.01));
    const PoseGraphSolution s = optimize_pose_graph(13, l.edges, 0, 22.4577, nullptr);
    for (std::size_t i = 0; i < 10; ++i) CHECK(s.placed[i] == 1);
    CHECK(s.placed[11] == 0 && s.placed[12] == 0 && s.component[11] == 11 && s.component[12] == 11);
    CHECK(std::isnan(s.poses[11].t[0]) && std::isnan(s.poses[12].R(0, 0)));
    const std::size_t last = l.edges.size() - 1;
    CHECK(s.accepted[last] == 0 && std::isnan(s.residual[last]));
    // Node 10: at most one of its two edges accepted (they cannot both hold); when placed, by the one it agrees with.
    CHECK(s.accepted[last - 2] + s.accepted[last - 1] <= 1);
    if (s.placed[10]) CHECK(pose_distance(s.poses[10], truth[0].inverse() * truth[10]) < 1e-6 || s.accepted[last - 1]);
}

// The factorisation's pattern holds the edges of non-zero weight when it is analysed (pose_graph_lm.cpp): a solve
// whose edges of weight 0 take part again on the same workspace must analyse again and land where a new workspace
// lands, bit for bit; an edge whose weight falls to 0 keeps its block and needs no new analysis.
void test_workspace_pattern_follows_the_weights() {
    const Loop l = make_loop(30, 0.01, 0.05, 8);
    const std::size_t m = l.edges.size();
    std::vector<long> variable(30);
    for (std::size_t i = 0; i < 30; ++i) variable[i] = static_cast<long>(i) - 1; // node 0 fixed
    std::vector<Rigid> start(30);
    for (std::size_t i = 1; i < 30; ++i) start[i] = start[i - 1] * l.edges[i - 1].measured.inverse(); // odometry
    std::vector<double> odometry_only(m, 1.0), all(m, 1.0);
    for (std::size_t e = 0; e < m; ++e)
        if (l.edges[e].robust) odometry_only[e] = 0.0;
    const LmOptions options;

    LmWorkspace reused;
    std::vector<Rigid> chain = start;
    levenberg_marquardt(l.edges, odometry_only, variable, chain, options, reused, nullptr);
    const long chain_blocks = reused.ldlt.lower_blocks(); // the odometry's chain alone
    std::vector<Rigid> again = start, fresh_poses = start;
    reused.lambda = 1e-6; // the damping a new workspace starts with
    levenberg_marquardt(l.edges, all, variable, again, options, reused, nullptr);
    CHECK(reused.ldlt.lower_blocks() > chain_blocks);
    LmWorkspace fresh;
    levenberg_marquardt(l.edges, all, variable, fresh_poses, options, fresh, nullptr);
    CHECK(reused.ldlt.lower_blocks() == fresh.ldlt.lower_blocks());
    for (std::size_t i = 0; i < 30; ++i) {
        CHECK(std::memcmp(again[i].R.data(), fresh_poses[i].R.data(), sizeof(double) * 9) == 0);
        CHECK(std::memcmp(again[i].t.data(), fresh_poses[i].t.data(), sizeof(double) * 3) == 0);
    }
    // Weights falling to 0 keep the pattern: the closures' blocks stay as zeros and the odometry's optimum is found.
    std::vector<Rigid> back = start;
    levenberg_marquardt(l.edges, odometry_only, variable, back, options, reused, nullptr);
    CHECK(reused.ldlt.lower_blocks() == fresh.ldlt.lower_blocks());
    for (std::size_t i = 0; i < 30; ++i) CHECK(pose_distance(back[i], chain[i]) < 1e-9);
}

void test_bitwise_repeatable() {
    const Loop l = make_loop(30, 0.01, 0.05, 9);
    const PoseGraphSolution a = optimize_pose_graph(30, l.edges, 3, 22.4577, nullptr);
    const PoseGraphSolution b = optimize_pose_graph(30, l.edges, 3, 22.4577, nullptr);
    for (std::size_t i = 0; i < 30; ++i) {
        CHECK(std::memcmp(a.poses[i].R.data(), b.poses[i].R.data(), sizeof(double) * 9) == 0);
        CHECK(std::memcmp(a.poses[i].t.data(), b.poses[i].t.data(), sizeof(double) * 3) == 0);
    }
    CHECK(std::memcmp(a.residual.data(), b.residual.data(), sizeof(double) * a.residual.size()) == 0);
    CHECK(a.poses[3].t.isZero(0.0)); // the anchor's frame
}

void test_cancelled() {
    const Loop l = make_loop(20, 0.01, 0.05, 10);
    std::atomic<int> cancel{1};
    bool thrown = false;
    try {
        optimize_pose_graph(20, l.edges, 0, 22.4577, &cancel);
    } catch (const Failure &f) {
        thrown = f.kind() == ErrorKind::Cancelled;
    }
    CHECK(thrown);
}

} // namespace

int main() {
    RUN_TEST(test_exp_log_round_trip);
    RUN_TEST(test_right_jacobian_inverse_matches_finite_differences);
    RUN_TEST(test_adjoint);
    RUN_TEST(test_consistent_graph_is_exact);
    RUN_TEST(test_noisy_graph_is_a_minimum);
    RUN_TEST(test_wrong_loop_closures_are_rejected);
    RUN_TEST(test_wrong_candidates_in_an_all_robust_graph);
    RUN_TEST(test_unplaced_nodes);
    RUN_TEST(test_workspace_pattern_follows_the_weights);
    RUN_TEST(test_bitwise_repeatable);
    RUN_TEST(test_cancelled);
    return TEST_SUMMARY();
}
