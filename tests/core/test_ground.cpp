// SPDX-License-Identifier: MIT
// Ground segmentation on synthetic voxel clouds whose ground is known: a plane (flat, tilted or stepped)
// sampled like a thinned scan, with boxes, walls and poles standing on it.
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "core/ground.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

namespace {

constexpr double kVoxel = 0.3;
constexpr double kHeight = 1.7; // the sensor above the ground at its foot

struct Scene {
    std::vector<Vec3f> points;
    std::vector<std::uint8_t> ground; // the known labels
    void add(const Eigen::Vector3d &p, bool is_ground) {
        points.push_back(p.cast<float>());
        ground.push_back(is_ground ? 1 : 0);
    }
};

// Ground height at (x, y): a plane through the sensor's foot rising by `slope` along x, with a step of
// `step` metres for x > 12.
double ground_z(double x, double y, double slope, double step) {
    (void)y;
    return -kHeight + slope * x + (x > 12.0 ? step : 0.0);
}

// Samples on a voxel-sized grid (as voxel centroids are), jittered by noise, within 3..40 m of the sensor.
Scene make_scene(double slope, double step, bool objects, std::uint64_t seed) {
    TestRng rng(seed);
    Scene s;
    const double noise = 0.01;
    for (double x = -40.0; x <= 40.0; x += kVoxel)
        for (double y = -40.0; y <= 40.0; y += kVoxel) {
            const double r = std::hypot(x, y);
            if (r < 3.0 || r > 40.0) continue;
            // Thinner far away, as a scan is.
            if (r > 15.0 && rng.uniform() > 15.0 / r) continue;
            s.add(Eigen::Vector3d(x, y, ground_z(x, y, slope, step) + noise * rng.normal()), true);
        }
    if (!objects) return s;
    // Boxes (cars): sides and roof from 0.3 m to 1.5 m above the ground.
    const double boxes[][2] = {{6.0, 3.0}, {-8.0, -5.0}, {15.0, -10.0}, {-20.0, 12.0}, {4.0, -7.0}};
    for (const auto &b : boxes) {
        const double gz = ground_z(b[0], b[1], slope, step);
        for (double u = -2.0; u <= 2.0; u += kVoxel)
            for (double w = -1.0; w <= 1.0; w += kVoxel) s.add(Eigen::Vector3d(b[0] + u, b[1] + w, gz + 1.5), false);
        for (double h = 0.3; h <= 1.5; h += kVoxel)
            for (double u = -2.0; u <= 2.0; u += kVoxel) {
                s.add(Eigen::Vector3d(b[0] + u, b[1] - 1.0, gz + h), false);
                s.add(Eigen::Vector3d(b[0] + u, b[1] + 1.0, gz + h), false);
            }
    }
    // A wall along y at x = -12 and one along x at y = 18, from 0.2 m above the ground to 5 m.
    for (double t = -10.0; t <= 10.0; t += kVoxel)
        for (double h = 0.2; h <= 5.0; h += kVoxel) {
            s.add(Eigen::Vector3d(-12.0, t, ground_z(-12.0, t, slope, step) + h), false);
            s.add(Eigen::Vector3d(t + 2.0, 18.0, ground_z(t + 2.0, 18.0, slope, step) + h), false);
        }
    // Poles.
    const double poles[][2] = {{5.0, 5.0}, {-4.0, 9.0}, {25.0, 3.0}, {-3.0, -20.0}};
    for (const auto &p : poles)
        for (double h = 0.2; h <= 6.0; h += kVoxel)
            s.add(Eigen::Vector3d(p[0], p[1], ground_z(p[0], p[1], slope, step) + h), false);
    return s;
}

GroundParams params(double sensor_height) {
    GroundParams gp;
    gp.sensor_height = sensor_height;
    gp.voxel_size = kVoxel;
    return gp;
}

// Recall over the known ground within the zone model's range, precision over all flagged points.
struct Score {
    double recall, precision;
};
Score score(const Scene &s, const std::vector<std::uint8_t> &flags, const GroundParams &gp) {
    std::size_t truth = 0, hit = 0, flagged = 0, right = 0;
    for (std::size_t i = 0; i < s.points.size(); ++i) {
        const double r = std::hypot(s.points[i].x(), s.points[i].y());
        const bool in_range = r >= gp.min_range && r < gp.max_range;
        if (s.ground[i] && in_range) ++truth, hit += flags[i];
        if (flags[i]) ++flagged, right += s.ground[i];
    }
    return Score{truth ? double(hit) / double(truth) : 1.0, flagged ? double(right) / double(flagged) : 1.0};
}

std::size_t count(const std::vector<std::uint8_t> &flags) {
    std::size_t n = 0;
    for (auto f : flags) n += f;
    return n;
}

} // namespace

static void test_flat_scene_with_objects() {
    const Scene s = make_scene(0.0, 0.0, true, 1);
    RunContext ctx(1, nullptr, Hooks());
    for (double h : {kHeight, 0.0}) { // given, then estimated
        const GroundParams gp = params(h);
        const std::vector<std::uint8_t> flags = segment_ground(s.points, gp, ctx);
        CHECK_EQ_INT(flags.size(), s.points.size());
        const Score sc = score(s, flags, gp);
        CHECK_MSG(sc.recall > 0.97 && sc.precision > 0.97, "height %g: recall %.4f precision %.4f", h, sc.recall,
                  sc.precision);
    }
    CHECK_NEAR(estimate_ground_height(s.points, params(0.0)), -kHeight, 0.03);
}

// The same flags with the sensor height given and estimated, when the estimate is right.
static void test_given_and_estimated_height_agree() {
    const Scene s = make_scene(0.0, 0.0, true, 2);
    RunContext ctx(1, nullptr, Hooks());
    const std::vector<std::uint8_t> given = segment_ground(s.points, params(kHeight), ctx);
    const std::vector<std::uint8_t> estimated = segment_ground(s.points, params(0.0), ctx);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < given.size(); ++i) differ += given[i] != estimated[i];
    CHECK_MSG(differ * 200 < s.points.size(), "%zu of %zu differ", differ, s.points.size());
}

// A slope of 10 degrees (well within the 45-degree uprightness limit) and a 0.3 m step (a kerb).
static void test_slope_and_step() {
    RunContext ctx(1, nullptr, Hooks());
    const Scene slope = make_scene(std::tan(10.0 * M_PI / 180.0), 0.0, true, 3);
    const Score a = score(slope, segment_ground(slope.points, params(kHeight), ctx), params(kHeight));
    CHECK_MSG(a.recall > 0.95 && a.precision > 0.97, "slope: recall %.4f precision %.4f", a.recall, a.precision);
    const Scene step = make_scene(0.0, 0.3, true, 4);
    const Score b = score(step, segment_ground(step.points, params(0.0), ctx), params(0.0));
    CHECK_MSG(b.recall > 0.9 && b.precision > 0.97, "step: recall %.4f precision %.4f", b.recall, b.precision);
}

// The scene and up permuted together (x, y, z) -> (z, x, y): bitwise the same flags, since the zone model's
// axes follow; any other rotation: the same flags but for points on bin edges.
static void test_up_turns_with_the_scene() {
    const Scene s = make_scene(0.0, 0.0, true, 5);
    RunContext ctx(1, nullptr, Hooks());
    const std::vector<std::uint8_t> ref = segment_ground(s.points, params(0.0), ctx);
    std::vector<Vec3f> perm;
    for (const Vec3f &p : s.points) perm.emplace_back(p.z(), p.x(), p.y());
    GroundParams gp = params(0.0);
    gp.up = Eigen::Vector3d(1.0, 0.0, 0.0);
    CHECK(segment_ground(perm, gp, ctx) == ref);

    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.9, Eigen::Vector3d(0.3, -0.8, 0.5).normalized()).toRotationMatrix();
    const Eigen::Vector3d t(3.0, -2.0, 7.0);
    std::vector<Vec3f> moved;
    for (const Vec3f &p : s.points) moved.push_back((R * p.cast<double>() + t).cast<float>());
    gp.up = R.col(2);
    gp.sensor = t; // the sensor moved with the scene
    const std::vector<std::uint8_t> turned = segment_ground(moved, gp, ctx);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < ref.size(); ++i) differ += ref[i] != turned[i];
    CHECK_MSG(differ * 100 < ref.size(), "%zu of %zu differ", differ, ref.size());
}

static void test_thread_count_does_not_matter() {
    const Scene s = make_scene(0.05, 0.2, true, 6);
    RunContext one(1, nullptr, Hooks()), two(2, nullptr, Hooks()), three(3, nullptr, Hooks());
    for (double h : {kHeight, 0.0}) {
        const std::vector<std::uint8_t> a = segment_ground(s.points, params(h), one);
        CHECK(segment_ground(s.points, params(h), two) == a);
        CHECK(segment_ground(s.points, params(h), three) == a);
        CHECK(count(a) > 0);
    }
}

static void test_empty_and_bad_parameters() {
    RunContext ctx(1, nullptr, Hooks());
    CHECK(segment_ground({}, params(0.0), ctx).empty());
    const Scene s = make_scene(0.0, 0.0, false, 7);
    GroundParams gp = params(0.0);
    gp.up = Eigen::Vector3d::Zero();
    std::vector<std::uint8_t> flags = segment_ground(s.points, gp, ctx);
    CHECK(flags.size() == s.points.size() && count(flags) == 0);
    gp.up = Eigen::Vector3d(0.0, std::nan(""), 1.0);
    CHECK(count(segment_ground(s.points, gp, ctx)) == 0);
    gp = params(-1.0);
    CHECK(count(segment_ground(s.points, gp, ctx)) == 0);
    // Non-finite points are never ground and change nothing else.
    std::vector<Vec3f> with_nan = s.points;
    with_nan.emplace_back(std::nanf(""), 1.0f, 1.0f);
    flags = segment_ground(with_nan, params(0.0), ctx);
    CHECK(flags.back() == 0);
    flags.pop_back();
    CHECK(flags == segment_ground(s.points, params(0.0), ctx));
}

// Only walls (no ground), and a flat canopy high above the sensor: nothing is ground. The walls do not meet:
// the feet of two walls in a corner span a level plane, which is ground as far as the points can tell.
static void test_no_ground() {
    RunContext ctx(1, nullptr, Hooks());
    Scene walls;
    for (double t = -15.0; t <= 15.0; t += kVoxel)
        for (double h = -1.7; h <= 6.0; h += kVoxel) {
            walls.add(Eigen::Vector3d(6.0, t, h), false);
            if (t < 3.0) walls.add(Eigen::Vector3d(t, -9.0, h), false);
        }
    for (double h : {kHeight, 0.0}) {
        const std::size_t n = count(segment_ground(walls.points, params(h), ctx));
        CHECK_MSG(n == 0, "height %g: %zu wall points called ground", h, n);
    }
    Scene canopy;
    for (double x = -9.0; x <= 9.0; x += kVoxel)
        for (double y = -9.0; y <= 9.0; y += kVoxel) canopy.add(Eigen::Vector3d(x, y, 2.0), false);
    const std::size_t n = count(segment_ground(canopy.points, params(kHeight), ctx));
    CHECK_MSG(n == 0, "%zu canopy points called ground", n);
}

static void test_all_ground() {
    RunContext ctx(2, nullptr, Hooks());
    const Scene s = make_scene(0.02, 0.0, false, 8);
    for (double h : {kHeight, 0.0}) {
        const Score sc = score(s, segment_ground(s.points, params(h), ctx), params(h));
        CHECK_MSG(sc.recall > 0.99, "height %g: recall %.4f", h, sc.recall);
    }
}

int main() {
    RUN_TEST(test_flat_scene_with_objects);
    RUN_TEST(test_given_and_estimated_height_agree);
    RUN_TEST(test_slope_and_step);
    RUN_TEST(test_up_turns_with_the_scene);
    RUN_TEST(test_thread_count_does_not_matter);
    RUN_TEST(test_empty_and_bad_parameters);
    RUN_TEST(test_no_ground);
    RUN_TEST(test_all_ground);
    return TEST_SUMMARY();
}
