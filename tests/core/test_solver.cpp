// SPDX-License-Identifier: MIT
#include <Eigen/Geometry>
#include <cmath>
#include <cstring>

#include "core/compat_graph.hpp"
#include "core/gnc_solver.hpp"
#include "core/kcore.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;
using kissm::detail::Vec3f;

static double rotation_error_deg(const Eigen::Matrix3d &a, const Eigen::Matrix3d &b) {
    const double c = ((a.transpose() * b).trace() - 1.0) / 2.0;
    return std::acos(std::max(-1.0, std::min(1.0, c))) * 180.0 / 3.14159265358979323846;
}

static void make_problem(std::uint64_t seed, std::size_t n, double outlier_fraction, double noise, Eigen::Matrix3d &R,
                         Eigen::Vector3d &t, std::vector<Eigen::Vector3d> &a, std::vector<Eigen::Vector3d> &b,
                         std::vector<bool> &is_inlier) {
    TestRng rng(seed);
    R = Eigen::AngleAxisd(rng.uniform(0.5, 3.1), Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal()).normalized())
            .toRotationMatrix();
    t = Eigen::Vector3d(rng.uniform(-20, 20), rng.uniform(-20, 20), rng.uniform(-5, 5));
    a.clear(), b.clear(), is_inlier.clear();
    for (std::size_t i = 0; i < n; ++i) {
        Eigen::Vector3d p(rng.uniform(-30, 30), rng.uniform(-30, 30), rng.uniform(-3, 3));
        a.push_back(p);
        const bool inlier = rng.uniform() >= outlier_fraction;
        is_inlier.push_back(inlier);
        if (inlier)
            b.push_back(R * p + t + noise * Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal()) / std::sqrt(3.0));
        else
            b.push_back(Eigen::Vector3d(rng.uniform(-30, 30), rng.uniform(-30, 30), rng.uniform(-3, 3)));
    }
}

// The paper's back end: compatibility graph, max k-core, then GNC-TLS on measurements drawn from the
// core's edges. 90% of the correspondences are outliers.
static void test_gnc_with_90_percent_outliers() {
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        std::vector<Eigen::Vector3d> a, b;
        std::vector<bool> inl;
        make_problem(seed, 1000, 0.9, 0.05, R, t, a, b, inl);
        SolverParams p;
        p.noise_bound = 0.2;
        std::vector<Vec3f> af, bf;
        for (std::size_t i = 0; i < a.size(); ++i) af.push_back(a[i].cast<float>()), bf.push_back(b[i].cast<float>());
        RunContext ctx(2, nullptr, Hooks());
        const CsrGraph g = build_compat_graph(af, bf, 0.2f, ctx);
        std::uint32_t k = 0;
        const std::vector<std::uint32_t> core = max_kcore(g, k);
        std::vector<Eigen::Vector3d> ca, cb;
        std::vector<bool> cinl;
        for (auto v : core) ca.push_back(a[v]), cb.push_back(b[v]), cinl.push_back(inl[v]);
        a = ca, b = cb, inl = cinl;
        const SolverOutput out = solve_pose(a, b, sample_induced_edges(g, core, p.max_tims), p, ctx);
        REQUIRE(out.solved);
        CHECK_MSG(rotation_error_deg(out.rotation, R) < 0.5, "seed %d: %g deg", (int)seed,
                  rotation_error_deg(out.rotation, R));
        CHECK_MSG((out.translation - t).norm() < 0.1, "seed %d: %g m", (int)seed, (out.translation - t).norm());
        std::size_t true_inliers = 0, agree = 0;
        for (std::size_t i = 0; i < inl.size(); ++i) {
            true_inliers += inl[i];
            agree += inl[i] && out.inlier[i];
        }
        CHECK(agree >= true_inliers * 95 / 100);
        CHECK(out.num_inliers <= true_inliers + 5);
    }
}

static void test_rotation_only_gnc() {
    // The rotation solver alone, on translation-free vectors with 70% outliers.
    TestRng rng(12);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
    std::vector<Eigen::Vector3d> a, b;
    for (int i = 0; i < 500; ++i) {
        Eigen::Vector3d v(rng.normal(), rng.normal(), rng.normal());
        v *= 10.0;
        a.push_back(v);
        b.push_back(i % 10 < 3 ? R * v : Eigen::Vector3d(10 * rng.normal(), 10 * rng.normal(), 10 * rng.normal()));
    }
    SolverParams p;
    p.noise_bound = 0.1;
    Eigen::Matrix3d est;
    std::vector<double> w;
    int iterations = 0;
    RunContext ctx(2, nullptr, Hooks());
    REQUIRE(gnc_tls_rotation(a, b, 0.1, p, est, w, iterations, ctx));
    CHECK(rotation_error_deg(est, R) < 1e-6);
    CHECK(iterations > 0 && iterations <= p.max_iterations);
    CHECK(std::abs(est.determinant() - 1.0) < 1e-12);
}

// A problem with noise 0.05 and noise bound 0.2.
struct Problem {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    std::vector<Eigen::Vector3d> a, b;
    std::vector<bool> inl;
    SolverParams p;
    Problem(std::uint64_t seed, std::size_t n, double outliers) {
        make_problem(seed, n, outliers, 0.05, R, t, a, b, inl);
        p.noise_bound = 0.2;
    }
};

static void test_order_independence() {
    const Problem q(21, 400, 0.5);
    const auto &a = q.a, &b = q.b;
    const SolverParams &p = q.p;
    RunContext ctx(2, nullptr, Hooks());
    const SolverOutput x = solve_pose(a, b, {}, p, ctx);
    // The solver's contract: the answer depends only on the order's content; reversing it must still
    // give the same pose to numerical precision.
    std::vector<Eigen::Vector3d> ra(a.rbegin(), a.rend()), rb(b.rbegin(), b.rend());
    const SolverOutput y = solve_pose(ra, rb, {}, p, ctx);
    REQUIRE(x.solved && y.solved);
    CHECK(rotation_error_deg(x.rotation, y.rotation) < 1e-6);
    CHECK((x.translation - y.translation).norm() < 1e-6);
    CHECK_EQ_INT(x.num_inliers, y.num_inliers);
}

static void test_same_bits_for_any_thread_count() {
    // Enough measurements for several fixed chunks of partial sums.
    const Problem q(22, 3000, 0.7);
    RunContext one(1, nullptr, Hooks());
    const SolverOutput x = solve_pose(q.a, q.b, {}, q.p, one);
    REQUIRE(x.solved);
    CHECK(rotation_error_deg(x.rotation, q.R) < 0.5);
    for (int threads : {2, 3, 8}) {
        RunContext ctx(threads, nullptr, Hooks());
        const SolverOutput y = solve_pose(q.a, q.b, {}, q.p, ctx);
        CHECK_MSG(std::memcmp(x.rotation.data(), y.rotation.data(), sizeof(double) * 9) == 0 &&
                      std::memcmp(x.translation.data(), y.translation.data(), sizeof(double) * 3) == 0 &&
                      x.num_inliers == y.num_inliers && x.iterations == y.iterations,
                  "%d threads", threads);
    }
}

static void test_scalar_tls() {
    // 30 values near 5, 40 spread widely: TLS picks the cluster mean.
    TestRng rng(13);
    std::vector<double> v;
    double sum = 0.0;
    for (int i = 0; i < 30; ++i) {
        const double x = 5.0 + rng.uniform(-0.1, 0.1);
        v.push_back(x);
        sum += x;
    }
    for (int i = 0; i < 40; ++i) v.push_back(rng.uniform(-100, 100));
    const double est = scalar_tls(v, 0.3);
    CHECK_NEAR(est, sum / 30.0, 0.05);
    CHECK_NEAR(scalar_tls({1.0}, 0.1), 1.0, 0.0);
}

int main() {
    RUN_TEST(test_gnc_with_90_percent_outliers);
    RUN_TEST(test_rotation_only_gnc);
    RUN_TEST(test_order_independence);
    RUN_TEST(test_same_bits_for_any_thread_count);
    RUN_TEST(test_scalar_tls);
    return TEST_SUMMARY();
}
