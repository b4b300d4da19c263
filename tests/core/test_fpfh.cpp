// SPDX-License-Identifier: MIT
#include <Eigen/Geometry>
#include <cmath>

#include "core/fpfh.hpp"
#include "core/neighbors.hpp"
#include "core/normals.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

// A small scene with structure at several scales: three planes of a corner, a sphere and a cylinder.
static std::vector<Vec3f> scene(std::uint64_t seed) {
    TestRng rng(seed);
    std::vector<Vec3f> pts;
    for (int i = 0; i < 4000; ++i) {
        const double u = rng.uniform(0, 6), w = rng.uniform(0, 6);
        switch (i % 3) {
        case 0: pts.emplace_back(static_cast<float>(u), static_cast<float>(w), 0.0f); break;
        case 1: pts.emplace_back(static_cast<float>(u), 0.0f, static_cast<float>(w * 0.5)); break;
        default: pts.emplace_back(0.0f, static_cast<float>(u), static_cast<float>(w * 0.5)); break;
        }
    }
    for (int i = 0; i < 1500; ++i) {
        Vec3d d(rng.normal(), rng.normal(), rng.normal());
        pts.push_back((Vec3d(3, 3, 1) + 0.8 * d.normalized()).cast<float>());
    }
    for (int i = 0; i < 1000; ++i) {
        const double a = rng.uniform(0, 6.283185307179586);
        pts.emplace_back(static_cast<float>(4.5 + 0.3 * std::cos(a)), static_cast<float>(1.5 + 0.3 * std::sin(a)),
                         static_cast<float>(rng.uniform(0, 2.5)));
    }
    return pts;
}

static Descriptors describe(const std::vector<Vec3f> &pts, const Vec3f &viewpoint) {
    RunContext ctx(2, nullptr, Hooks());
    const float v = 0.1f;
    const Neighborhoods nb = radius_neighbors(pts, 5 * v, ctx);
    const Normals normals = estimate_normals(pts, nb, NormalParams{3.5f * v, 3, 0.99, viewpoint}, ctx);
    return compute_fpfh(pts, nb, normals, select_keypoints(nb, normals, 3), v, 1, ctx);
}

static void test_blocks_sum_to_100() {
    const Descriptors d = describe(scene(7), Vec3f(3, 3, 10));
    REQUIRE(!d.keypoint.empty());
    double worst = 0.0;
    for (std::size_t k = 0; k < d.keypoint.size(); ++k)
        for (int b = 0; b < 3; ++b) {
            double s = 0.0;
            for (int c = 0; c < kBinsPerFeature; ++c) s += d.values[k * kDescriptorDim + b * kBinsPerFeature + c];
            worst = std::max(worst, std::fabs(s - 100.0));
        }
    CHECK_MSG(worst < 1e-3, "worst block sum error %g", worst);
}

static void test_rotation_invariance() {
    const std::vector<Vec3f> pts = scene(8);
    const Eigen::Matrix3f R = Eigen::AngleAxisf(2.3f, Vec3f(0.3f, -0.5f, 0.8f).normalized()).toRotationMatrix();
    const Vec3f t(10.0f, -4.0f, 2.0f);
    std::vector<Vec3f> moved;
    for (const auto &p : pts) moved.push_back(R * p + t);
    const Vec3f vp(3, 3, 10);
    const Descriptors a = describe(pts, vp);
    const Descriptors b = describe(moved, R * vp + t);
    REQUIRE(a.keypoint == b.keypoint);
    // Rounding can move a feature across a bin edge now and then; the descriptors must agree closely.
    double sum_abs = 0.0, norm = 0.0;
    for (std::size_t i = 0; i < a.values.size(); ++i) {
        sum_abs += std::fabs(a.values[i] - b.values[i]);
        norm += a.values[i];
    }
    CHECK_MSG(sum_abs / norm < 0.01, "relative L1 difference %g", sum_abs / norm);
}

static void test_pair_feature_symmetric() {
    TestRng rng(9);
    int same = 0, defined = 0;
    for (int i = 0; i < 1000; ++i) {
        Vec3f p1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
        Vec3f p2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
        Vec3f n1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
        Vec3f n2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
        int a[3], b[3];
        const bool da = pair_feature_bins(p1, n1, p2, n2, a), db = pair_feature_bins(p2, n2, p1, n1, b);
        CHECK(da == db);
        if (da && db) {
            ++defined;
            same += a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
            CHECK(a[0] >= 0 && a[0] < 11 && a[1] >= 0 && a[1] < 11 && a[2] >= 0 && a[2] < 11);
        }
    }
    CHECK(defined > 990);
    CHECK_MSG(same >= defined - 2, "%d of %d symmetric", same, defined);
    int bins[3];
    CHECK(!pair_feature_bins(Vec3f(1, 1, 1), Vec3f(0, 0, 1), Vec3f(1, 1, 1), Vec3f(0, 0, 1), bins)); // coincident
}

static void test_invalid_neighbours_do_not_leak_in() {
    // Adding a far-away line of points (which gets no normals) must not change any descriptor.
    std::vector<Vec3f> pts = scene(10);
    const Descriptors a = describe(pts, Vec3f(3, 3, 10));
    std::vector<Vec3f> more = pts;
    // A line 0.4 above the floor: inside the floor points' FPFH radius (0.5), outside their normal radius (0.35).
    for (int i = 0; i < 30; ++i) more.emplace_back(0.5f + 0.1f * static_cast<float>(i), 5.5f, 0.4f);
    const Descriptors b = describe(more, Vec3f(3, 3, 10));
    // The line points have no normal, so they are skipped everywhere: keypoints of the original points and
    // their descriptors are unchanged.
    REQUIRE(b.keypoint.size() >= a.keypoint.size());
    std::size_t k = 0, equal = 0;
    for (std::size_t i = 0; i < b.keypoint.size() && k < a.keypoint.size(); ++i) {
        if (b.keypoint[i] != a.keypoint[k]) continue;
        equal += std::equal(a.values.begin() + static_cast<std::ptrdiff_t>(k * kDescriptorDim),
                            a.values.begin() + static_cast<std::ptrdiff_t>((k + 1) * kDescriptorDim),
                            b.values.begin() + static_cast<std::ptrdiff_t>(i * kDescriptorDim));
        ++k;
    }
    CHECK_EQ_INT(k, a.keypoint.size());
    CHECK_EQ_INT(equal, a.keypoint.size());
}

int main() {
    RUN_TEST(test_blocks_sum_to_100);
    RUN_TEST(test_rotation_invariance);
    RUN_TEST(test_pair_feature_symmetric);
    RUN_TEST(test_invalid_neighbours_do_not_leak_in);
    return TEST_SUMMARY();
}
