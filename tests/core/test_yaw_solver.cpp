// SPDX-License-Identifier: MIT
// The 4-DoF (yaw about `up`) solver against ground truth on synthetic correspondences (yaw_problem.hpp).
#include <cmath>
#include <cstring>
#include <limits>

#include "core/yaw_solver.hpp"
#include "harness.h"
#include "yaw_problem.hpp"

using namespace kissm::detail;

static const double kPi = 3.14159265358979323846;
static const Eigen::Vector3d kUps[2] = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0.3, -0.2, 0.9).normalized()};

static bool same_bits(const SolverOutput &x, const SolverOutput &y) {
    return std::memcmp(x.rotation.data(), y.rotation.data(), sizeof(double) * 9) == 0 &&
           std::memcmp(x.translation.data(), y.translation.data(), sizeof(double) * 3) == 0 && x.inlier == y.inlier &&
           x.rotation_inlier == y.rotation_inlier && x.iterations == y.iterations;
}

// The returned rotation is a proper rotation exactly about `up` (to rounding): R up == up and R^T up == up, so
// it has no roll or pitch relative to `up`.
static void check_about_up(const Eigen::Matrix3d &R, const Eigen::Vector3d &up) {
    CHECK_MSG((R * up - up).norm() < 1e-12, "|R up - up| = %g", (R * up - up).norm());
    CHECK_MSG((R.transpose() * up - up).norm() < 1e-12, "|R^T up - up| = %g", (R.transpose() * up - up).norm());
    CHECK((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-12);
    CHECK(std::fabs(R.determinant() - 1.0) < 1e-12);
}

// The pipeline's path: compatibility graph, max k-core, TIMs from the core's edges. Yaws from -180 to 180
// degrees, both `up`s, 50 to 95% outliers.
static void test_accuracy_over_yaws_and_outliers() {
    for (double rate : {0.5, 0.7, 0.9, 0.95}) {
        for (int i = 0; i <= 8; ++i) {
            const double yaw = -kPi + kPi * i / 4.0;
            for (int u = 0; u < 2; ++u) {
                YawProblem q(static_cast<std::uint64_t>(100 * i + u + 1), 400, rate, yaw, kUps[u]);
                RunContext ctx(2, nullptr, Hooks());
                SolverParams p;
                p.noise_bound = q.noise_bound;
                std::vector<IndexPair> pairs = q.prune(ctx, p.max_tims);
                const SolverOutput out = solve_pose_yaw(q.a, q.b, pairs, q.up, p, ctx);
                REQUIRE(out.solved);
                CHECK_MSG(rotation_error_deg(out.rotation, q.R) < 0.1, "rate %g yaw %g up %d: %g deg", rate,
                          yaw * 180 / kPi, u, rotation_error_deg(out.rotation, q.R));
                CHECK_MSG((out.translation - q.t).norm() < 0.05, "rate %g yaw %g up %d: %g m", rate, yaw * 180 / kPi, u,
                          (out.translation - q.t).norm());
                check_about_up(out.rotation, q.up);
                std::size_t true_inliers = 0, agree = 0;
                for (std::size_t k = 0; k < q.inl.size(); ++k)
                    true_inliers += q.inl[k], agree += q.inl[k] && out.inlier[k];
                CHECK(agree >= true_inliers * 95 / 100);
                CHECK(out.num_inliers <= true_inliers + 3);
            }
        }
    }
}

// rotation_about is Rodrigues: a rotation about the axis for any angle, matching Eigen's AngleAxis.
static void test_rotation_about() {
    for (const Eigen::Vector3d &up : kUps) {
        for (double angle : {-kPi, -2.0, -1e-9, 0.0, 0.3, kPi / 2, 3.0, kPi}) {
            const Eigen::Matrix3d R = rotation_about(up, angle);
            check_about_up(R, up);
            CHECK((R - YawProblem::about(up, angle)).norm() < 1e-14);
        }
    }
}

static void test_same_bits_for_any_thread_count() {
    // Strided TIMs from 3000 correspondences: 20000 measurements, about ten chunks of partial sums.
    YawProblem q(7, 3000, 0.7, 2.5, kUps[1]);
    SolverParams p;
    p.noise_bound = q.noise_bound;
    RunContext one(1, nullptr, Hooks());
    const SolverOutput x = solve_pose_yaw(q.a, q.b, {}, q.up, p, one);
    REQUIRE(x.solved);
    CHECK(rotation_error_deg(x.rotation, q.R) < 0.1);
    CHECK(x.iterations > 0); // the GNC loop ran, so its sums were split into chunks
    for (int threads : {2, 3}) {
        RunContext ctx(threads, nullptr, Hooks());
        const SolverOutput y = solve_pose_yaw(q.a, q.b, {}, q.up, p, ctx);
        CHECK_MSG(same_bits(x, y), "%d threads", threads);
        const double tx = residual_tilt(q.a, q.b, {}, x, q.up, p, one),
                     ty = residual_tilt(q.a, q.b, {}, y, q.up, p, ctx);
        CHECK(std::memcmp(&tx, &ty, sizeof(double)) == 0);
    }
}

static void test_too_few_or_bad_input() {
    RunContext ctx(2, nullptr, Hooks());
    SolverParams p;
    p.noise_bound = 0.2;
    for (std::size_t n : {0, 1, 2}) {
        YawProblem q(3, n, 0.0, 1.0, kUps[0]);
        const SolverOutput out = solve_pose_yaw(q.a, q.b, {}, q.up, p, ctx);
        CHECK(!out.solved);
        CHECK_EQ_INT(out.inlier.size(), n);
        CHECK(std::isnan(residual_tilt(q.a, q.b, {}, out, q.up, p, ctx)));
    }
    // Three correspondences that agree on nothing: no two TIMs agree, so no pose.
    {
        std::vector<Eigen::Vector3d> a = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}}, b = {{0, 0, 0}, {0, 0, 5}, {3, 0, -7}};
        const SolverOutput out = solve_pose_yaw(a, b, {}, kUps[0], p, ctx);
        CHECK(!out.solved);
    }
    // `up` zero or not finite: refused, not a crash or a NaN pose.
    YawProblem q(4, 100, 0.5, 1.0, kUps[0]);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const Eigen::Vector3d &up :
         {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(nan, 0, 1), Eigen::Vector3d(0, 1e300 * 1e300, 0)}) {
        const SolverOutput out = solve_pose_yaw(q.a, q.b, {}, up, p, ctx);
        CHECK(!out.solved);
        CHECK(out.rotation == Eigen::Matrix3d::Identity());
        CHECK(std::isnan(residual_tilt(q.a, q.b, {}, out, up, p, ctx)));
    }
    // A non-unit `up` is normalised.
    const SolverOutput scaled = solve_pose_yaw(q.a, q.b, {}, 3.0 * q.up, p, ctx);
    REQUIRE(scaled.solved);
    CHECK(rotation_error_deg(scaled.rotation, q.R) < 0.1);
}

// A pair whose relative pitch is not zero: residual_tilt measures it (well above kTiltThreshold), while pairs
// with zero tilt stay far below it. Both `up`s, 50 and 90% outliers, several seeds.
static void test_residual_tilt_separates_tilted_pairs() {
    double max_zero = 0.0, min_tilted = 1e9;
    for (double rate : {0.5, 0.9}) {
        for (std::uint64_t seed = 1; seed <= 6; ++seed) {
            for (double pitch_deg : {0.0, 5.0, 10.0, 30.0}) {
                const Eigen::Vector3d &up = kUps[seed % 2];
                YawProblem q(seed, 300, rate, -3.0 + static_cast<double>(seed), up, pitch_deg * kPi / 180.0);
                RunContext ctx(2, nullptr, Hooks());
                SolverParams p;
                p.noise_bound = q.noise_bound;
                std::vector<IndexPair> pairs = q.prune(ctx, p.max_tims);
                const SolverOutput out = solve_pose_yaw(q.a, q.b, pairs, q.up, p, ctx);
                const double tilt = residual_tilt(q.a, q.b, pairs, out, q.up, p, ctx);
                if (pitch_deg == 0.0) {
                    REQUIRE(out.solved);
                    CHECK_MSG(tilt < 0.1 * kTiltThreshold, "seed %d rate %g: zero tilt measured %g deg", (int)seed,
                              rate, tilt * 180 / kPi);
                    max_zero = std::max(max_zero, tilt);
                } else {
                    // The yaw pose is wrong here (solved or not); the tilt says so, and says how much.
                    CHECK_MSG(tilt > 3.0 * kTiltThreshold, "seed %d rate %g pitch %g: tilt %g deg", (int)seed, rate,
                              pitch_deg, tilt * 180 / kPi);
                    CHECK_MSG(std::fabs(tilt * 180 / kPi - pitch_deg) < 0.2, "seed %d rate %g pitch %g: tilt %g deg",
                              (int)seed, rate, pitch_deg, tilt * 180 / kPi);
                    min_tilted = std::min(min_tilted, tilt);
                }
            }
        }
    }
    std::printf("residual_tilt: zero-tilt max %.4f deg, tilted (5-30 deg) min %.4f deg, threshold %.1f deg\n",
                max_zero * 180 / kPi, min_tilted * 180 / kPi, kTiltThreshold * 180 / kPi);
}

// Upstream keeps the noise bound in function-local statics (the first call's bound wins); ours reads params
// on every call. Noise up to 0.2 m: a 0.1 m bound keeps part of the inliers, a 0.4 m bound all of them.
static void test_noise_bound_is_per_call() {
    // Noise up to 0.2 m.
    const YawProblem q(11, 400, 0.5, 0.7, kUps[1], 0.0, 0.4);
    RunContext ctx(2, nullptr, Hooks());
    SolverParams tight, loose;
    tight.noise_bound = 0.1, loose.noise_bound = 0.4;
    const SolverOutput t1 = solve_pose_yaw(q.a, q.b, {}, q.up, tight, ctx);
    const SolverOutput l1 = solve_pose_yaw(q.a, q.b, {}, q.up, loose, ctx);
    const SolverOutput t2 = solve_pose_yaw(q.a, q.b, {}, q.up, tight, ctx);
    const SolverOutput l2 = solve_pose_yaw(q.a, q.b, {}, q.up, loose, ctx);
    REQUIRE(t1.solved && l1.solved);
    CHECK(same_bits(t1, t2));
    CHECK(same_bits(l1, l2));
    CHECK_MSG(l1.num_inliers >= q.num_inliers() * 98 / 100 && t1.num_inliers + 20 < l1.num_inliers,
              "true %zu, loose %zu, tight %zu", q.num_inliers(), l1.num_inliers, t1.num_inliers);
    // Each call's inliers obey its own bound.
    for (std::size_t k = 0; k < q.a.size(); ++k) {
        CHECK(!t1.inlier[k] || (t1.rotation * q.a[k] + t1.translation - q.b[k]).norm() <= tight.noise_bound);
        CHECK(!l1.inlier[k] || (l1.rotation * q.a[k] + l1.translation - q.b[k]).norm() <= loose.noise_bound);
    }
}

// One TIM fixes a rotation about `up`, none fixes SO(3): on the same correspondences, with GNC seeing the
// strided TIMs directly (no k-core in front), the yaw solver succeeds at outlier rates where solve_pose fails.
static void test_needs_fewer_inliers_than_3dof() {
    int yaw_ok = 0, free_ok = 0, runs = 0;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
        YawProblem q(seed, 100, 0.9, -kPi + 0.3 * static_cast<double>(seed), kUps[seed % 2]);
        RunContext ctx(2, nullptr, Hooks());
        SolverParams p;
        p.noise_bound = q.noise_bound;
        const SolverOutput y = solve_pose_yaw(q.a, q.b, {}, q.up, p, ctx);
        const SolverOutput f = solve_pose(q.a, q.b, {}, p, ctx);
        yaw_ok += y.solved && rotation_error_deg(y.rotation, q.R) < 1.0 && (y.translation - q.t).norm() < 0.3;
        free_ok += f.solved && rotation_error_deg(f.rotation, q.R) < 1.0 && (f.translation - q.t).norm() < 0.3;
        ++runs;
    }
    std::printf("90%% outliers, 100 correspondences, strided TIMs: yaw %d/%d, 3-DoF %d/%d\n", yaw_ok, runs, free_ok,
                runs);
    CHECK(yaw_ok >= 17);
    CHECK(yaw_ok >= free_ok + 5);
}

int main() {
    RUN_TEST(test_rotation_about);
    RUN_TEST(test_accuracy_over_yaws_and_outliers);
    RUN_TEST(test_same_bits_for_any_thread_count);
    RUN_TEST(test_too_few_or_bad_input);
    RUN_TEST(test_residual_tilt_separates_tilted_pairs);
    RUN_TEST(test_noise_bound_is_per_call);
    RUN_TEST(test_needs_fewer_inliers_than_3dof);
    return TEST_SUMMARY();
}
