// SPDX-License-Identifier: MIT
// Stage 5c against scenes whose competing poses are known: a row of identical units (a period shift matches as
// well), a symmetric object (a half turn matches as well), and the same scenes with the competitor's matches few
// (one answer). The matches go through the pipeline's own pruning, solver and polish, as in register_described.
#include <Eigen/Geometry>
#include <cmath>
#include <cstring>

#include "core/ambiguity.hpp"
#include "core/params.hpp"
#include "core/pruning.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

namespace {

constexpr double kVoxel = 0.3;

struct Scene {
    std::vector<Vec3f> source_voxels, target_voxels;
    std::vector<Eigen::Vector3d> a, b; // matches: source, target
};

Eigen::Isometry3d pose(double yaw_deg, const Eigen::Vector3d &t) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() =
        Eigen::AngleAxisd(yaw_deg * 3.14159265358979323846 / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = t;
    return T;
}

// One unit: 60 points in a 3 m box, the same pattern every time (a facade, a pillar with its fittings).
std::vector<Eigen::Vector3d> unit_pattern() {
    TestRng rng(77);
    std::vector<Eigen::Vector3d> out;
    for (int i = 0; i < 60; ++i) out.emplace_back(rng.uniform(0, 3), rng.uniform(0, 3), rng.uniform(0, 3));
    return out;
}

// Target voxels: `units` (their offsets) of the pattern; source voxels: those within `radius` of `centre`, seen
// from the source's frame (p_target = T p_source).
void make_voxels(const std::vector<Eigen::Vector3d> &units, const Eigen::Isometry3d &T, const Eigen::Vector3d &centre,
                 double radius, Scene &s) {
    const std::vector<Eigen::Vector3d> pattern = unit_pattern();
    for (const Eigen::Vector3d &u : units)
        for (const Eigen::Vector3d &p : pattern) {
            const Eigen::Vector3d q = u + p;
            s.target_voxels.push_back(q.cast<float>());
            if ((q - centre).norm() < radius) s.source_voxels.push_back((T.inverse() * q).cast<float>());
        }
}

// `n` matches that pose T explains (source voxels and their images, 2 cm of noise), drawn from the source voxels.
void add_matches(Scene &s, const Eigen::Isometry3d &T, std::size_t n, std::uint64_t seed) {
    TestRng rng(seed);
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d p =
            s.source_voxels[static_cast<std::size_t>(rng.next() % s.source_voxels.size())].cast<double>();
        s.a.push_back(p);
        s.b.push_back(T * p + 0.02 * Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal()));
    }
}

// Matches that agree with nothing.
void add_junk(Scene &s, std::size_t n, std::uint64_t seed) {
    TestRng rng(seed);
    for (std::size_t i = 0; i < n; ++i) {
        s.a.push_back(s.source_voxels[static_cast<std::size_t>(rng.next() % s.source_voxels.size())].cast<double>());
        s.b.push_back(s.target_voxels[static_cast<std::size_t>(rng.next() % s.target_voxels.size())].cast<double>());
    }
}

struct Outcome {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    Ambiguity ambiguity;
};

// The pipeline's stages 4, 5 and 5c on the scene's matches.
Outcome measure(const Scene &s, int threads) {
    Params params;
    params.voxel_size = kVoxel;
    const PoseSolver solver(params);
    RunContext ctx(threads, nullptr, Hooks());
    std::vector<Vec3f> af, bf;
    for (std::size_t k = 0; k < s.a.size(); ++k) af.push_back(s.a[k].cast<float>()), bf.push_back(s.b[k].cast<float>());
    const PrunedMatches pruned = prune_matches(af, bf, params.prune_noise_bound(), solver.max_measurements(), ctx);
    std::vector<Eigen::Vector3d> ca, cb;
    for (std::uint32_t k : pruned.core) ca.push_back(af[k].cast<double>()), cb.push_back(bf[k].cast<double>());
    PoseSolution sol = solver.solve(ca, cb, pruned.measurements, ctx);
    CHECK(sol.solver.solved);
    std::vector<Eigen::Vector3d> a, b;
    for (std::size_t k = 0; k < af.size(); ++k) a.push_back(af[k].cast<double>()), b.push_back(bf[k].cast<double>());
    std::vector<std::uint8_t> inlier;
    const std::size_t inliers = solver.polish(a, b, sol.solver.rotation, sol.solver.translation, inlier);
    Normals normals; // no normals: every voxel is read
    normals.normal.assign(s.source_voxels.size(), Vec3f::Zero());
    normals.valid.assign(s.source_voxels.size(), 0);
    const AmbiguityInput in{&a,
                            &b,
                            &pruned.core,
                            &pruned.measurements,
                            &pruned.second_core,
                            &pruned.second_measurements,
                            inliers,
                            &s.source_voxels,
                            &s.target_voxels,
                            &normals,
                            kVoxel};
    return {sol.solver.rotation, sol.solver.translation,
            measure_ambiguity(in, solver, sol.solver.rotation, sol.solver.translation, ctx)};
}

double error_deg(const Eigen::Matrix3d &R, const Eigen::Matrix3d &truth) {
    return std::acos(std::max(-1.0, std::min(1.0, ((R.transpose() * truth).trace() - 1.0) / 2.0))) * 180.0 /
           3.14159265358979323846;
}

// A row of identical units every 10 m on both sides of a street, seen from the source at T, with 40 matches for T
// and `shifted` for the pose one period along.
Scene street_scene(const Eigen::Isometry3d &T, std::size_t shifted) {
    std::vector<Eigen::Vector3d> units;
    for (int k = -5; k <= 5; ++k) units.emplace_back(10.0 * k, 5.0, 0.0), units.emplace_back(10.0 * k, -8.0, 0.0);
    Scene s;
    make_voxels(units, T, Eigen::Vector3d(3, 0, 0), 25.0, s);
    add_matches(s, T, 40, 1);
    add_matches(s, Eigen::Translation3d(10.0, 0.0, 0.0) * T, shifted, 2);
    add_junk(s, 300, 3);
    return s;
}

// The pose and the pose one period along matched by 40 and 36 matches: the competitor is found and rated close to
// the winner, whichever the solver took; with 6 matches one period along, one answer.
void test_period_shift_is_ambiguous() {
    const Eigen::Isometry3d T = pose(20.0, Eigen::Vector3d(3.0, 1.0, 0.2));
    const Outcome o = measure(street_scene(T, 36), 2);
    const bool right =
        error_deg(o.R, T.linear()) < 1.0 &&
        ((o.t - T.translation()).norm() < 0.3 || (o.t - T.translation() - Eigen::Vector3d(10, 0, 0)).norm() < 0.3);
    CHECK_MSG(right, "the solver took neither pose: %g deg", error_deg(o.R, T.linear()));
    CHECK_MSG(o.ambiguity.value >= 0.85 && o.ambiguity.value <= 1.0, "ambiguity %.3f", o.ambiguity.value);
    CHECK(o.ambiguity.candidates > 0);

    const Outcome u = measure(street_scene(T, 6), 2);
    CHECK(error_deg(u.R, T.linear()) < 1.0 && (u.t - T.translation()).norm() < 0.3);
    CHECK_MSG(u.ambiguity.value < 0.5, "ambiguity %.3f", u.ambiguity.value);
}

// An object symmetric under a half turn about the vertical through its centre, its matches split between the two
// poses (their descriptors are the same): the half-turned pose is found exactly, however the solver chose.
void test_half_turn_is_ambiguous() {
    const std::vector<Eigen::Vector3d> pattern = unit_pattern();
    Scene s;
    const Eigen::Isometry3d T = pose(35.0, Eigen::Vector3d(0.5, -0.3, 0.1));
    for (const Eigen::Vector3d &p : pattern) {
        const Eigen::Vector3d q = p - Eigen::Vector3d(1.5, 1.5, 0.0), turned(-q.x(), -q.y(), q.z());
        for (const Eigen::Vector3d &v : {q, turned}) {
            s.target_voxels.push_back(v.cast<float>());
            s.source_voxels.push_back((T.inverse() * v).cast<float>());
        }
    }
    const Eigen::Isometry3d half = pose(180.0, Eigen::Vector3d::Zero()) * T; // the same object, turned
    add_matches(s, T, 30, 4);
    add_matches(s, half, 26, 5);
    add_junk(s, 150, 6);
    const Outcome o = measure(s, 2);
    CHECK_MSG(error_deg(o.R, T.linear()) < 1.0 || error_deg(o.R, half.linear()) < 1.0, "%g deg",
              error_deg(o.R, T.linear()));
    CHECK_MSG(o.ambiguity.value >= 0.85, "ambiguity %.3f", o.ambiguity.value);

    Scene one = s;
    one.a.resize(30), one.b.resize(30); // the half-turned pose's matches gone
    add_junk(one, 150, 6);
    const Outcome u = measure(one, 2);
    CHECK(error_deg(u.R, T.linear()) < 1.0);
    CHECK_MSG(u.ambiguity.value < 0.5, "ambiguity %.3f", u.ambiguity.value);
}

// Only near-duplicates of the winner (its own matches, moved by a noise bound): no distinct competitor.
void test_the_winner_again_is_no_competitor() {
    std::vector<Eigen::Vector3d> units = {Eigen::Vector3d(0, 0, 0)};
    const Eigen::Isometry3d T = pose(-50.0, Eigen::Vector3d(1.0, 2.0, 0.0));
    Scene s;
    make_voxels(units, T, Eigen::Vector3d::Zero(), 100.0, s);
    add_matches(s, T, 40, 7);
    add_matches(s, Eigen::Translation3d(0.3, 0.0, 0.0) * T, 30, 8);
    const Outcome o = measure(s, 1);
    CHECK_MSG(o.ambiguity.value < 0.5, "ambiguity %.3f", o.ambiguity.value);
}

// The same bits at every thread count.
void test_threads_change_nothing() {
    std::vector<Eigen::Vector3d> units;
    for (int k = -5; k <= 5; ++k) units.emplace_back(10.0 * k, 5.0, 0.0);
    const Eigen::Isometry3d T = pose(-10.0, Eigen::Vector3d(2.0, 0.0, 0.0));
    Scene s;
    make_voxels(units, T, Eigen::Vector3d(2, 0, 0), 25.0, s);
    add_matches(s, T, 40, 9);
    add_matches(s, Eigen::Translation3d(-10.0, 0.0, 0.0) * T, 30, 10);
    add_junk(s, 200, 11);
    const Outcome one = measure(s, 1), four = measure(s, 4);
    CHECK(std::memcmp(&one.ambiguity.value, &four.ambiguity.value, sizeof(double)) == 0);
    CHECK(one.ambiguity.candidates == four.ambiguity.candidates);
}

} // namespace

int main() {
    RUN_TEST(test_period_shift_is_ambiguous);
    RUN_TEST(test_half_turn_is_ambiguous);
    RUN_TEST(test_the_winner_again_is_no_competitor);
    RUN_TEST(test_threads_change_nothing);
    return TEST_SUMMARY();
}
