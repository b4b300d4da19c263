// SPDX-License-Identifier: MIT
#include <Eigen/Geometry>
#include <cmath>
#include <cstring>

#include "core/fpfh.hpp"
#include "core/normals.hpp"
#include "core/radius_search.hpp"
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

static Descriptors describe(const std::vector<Vec3f> &pts, const Vec3f &viewpoint,
                            NormalSigns signs = NormalSigns::Oriented, std::uint64_t flip_seed = 0) {
    RunContext ctx(2, nullptr, Hooks());
    const float v = 0.1f;
    const Neighborhoods nb = radius_neighbors(pts, 5 * v, ctx);
    NormalParams np{3.5f * v, 3, 0.99, viewpoint};
    if (signs == NormalSigns::Ignored) np.orientation = NormalOrientation::Unoriented;
    Normals normals = estimate_normals(pts, nb, np, ctx);
    if (flip_seed != 0) { // every normal's sign at random
        TestRng rng(flip_seed);
        for (auto &n : normals.normal)
            if (rng.uniform() < 0.5) n = -n;
    }
    return compute_fpfh(pts, nb, normals, signs, select_keypoints(nb, normals, 3), v, 1, ctx);
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
    for (const NormalSigns signs : {NormalSigns::Oriented, NormalSigns::Ignored}) {
        TestRng rng(9);
        int same = 0, defined = 0;
        for (int i = 0; i < 1000; ++i) {
            Vec3f p1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
            Vec3f p2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
            Vec3f n1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
            Vec3f n2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
            int a[3], b[3];
            const bool da = pair_feature_bins(p1, n1, p2, n2, signs, a),
                       db = pair_feature_bins(p2, n2, p1, n1, signs, b);
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
        CHECK(!pair_feature_bins(Vec3f(1, 1, 1), Vec3f(0, 0, 1), Vec3f(1, 1, 1), Vec3f(0, 0, 1), signs, bins));
    }
}

// The sign-free features against their definition, computed here in double with atan2: the representative of
// the four sign choices has u . d >= 0 and u . n_b >= 0; f1 = atan2(w . n_b, u . n_b) in [-pi/2, pi/2], f2 = v . n_b
// in [-1, 1], f3 = u . d in [0, 1], each in 11 equal bins. Flipping either normal must not change a bin.
static void test_sign_free_pair_features() {
    TestRng rng(21);
    const double pi = 3.14159265358979323846;
    int checked = 0, off = 0, flip_changed = 0;
    int seen[3][11] = {};
    for (int i = 0; i < 20000; ++i) {
        const Vec3f p1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
        const Vec3f p2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
        const Vec3f n1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
        const Vec3f n2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
        int bins[3];
        if (!pair_feature_bins(p1, n1, p2, n2, NormalSigns::Ignored, bins)) continue;
        ++checked;
        for (int f = 0; f < 3; ++f) ++seen[f][bins[f]];
        for (int flips = 1; flips < 4; ++flips) {
            int other[3];
            const Vec3f m1 = (flips & 1) ? Vec3f(-n1) : n1, m2 = (flips & 2) ? Vec3f(-n2) : n2;
            REQUIRE(pair_feature_bins(p1, m1, p2, m2, NormalSigns::Ignored, other));
            flip_changed += other[0] != bins[0] || other[1] != bins[1] || other[2] != bins[2];
        }
        // The definition in double.
        Vec3d d = (p2 - p1).cast<double>().normalized(), a = n1.cast<double>(), b = n2.cast<double>();
        if (std::fabs(a.dot(d)) < std::fabs(b.dot(d))) std::swap(a, b), d = -d;
        if (a.dot(d) < 0) a = -a;
        const Vec3d v = d.cross(a).normalized(), w = a.cross(v);
        if (a.dot(b) < 0) b = -b;
        const double f1 = std::atan2(w.dot(b), a.dot(b)), f2 = v.dot(b), f3 = a.dot(d);
        auto bin = [](double x, double lo, double hi) {
            return std::min(10, static_cast<int>((x - lo) / (hi - lo) * 11));
        };
        const int want[3] = {bin(f1, -pi / 2, pi / 2), bin(f2, -1, 1), bin(f3, 0, 1)};
        off += want[0] != bins[0] || want[1] != bins[1] || want[2] != bins[2];
    }
    CHECK(checked > 19900);
    CHECK_MSG(flip_changed == 0, "%d flips changed a bin", flip_changed);
    CHECK_MSG(off <= 3, "%d of %d pairs binned unlike the definition (rounding at a bin edge only)", off, checked);
    for (int f = 0; f < 3; ++f)
        for (int k = 0; k < 11; ++k) CHECK_MSG(seen[f][k] > 0, "feature %d never in bin %d", f + 1, k);
}

// Mixed signs: a pair feature ignores the sign of an open normal and reads that of a decided one. Flipping an
// open normal changes no bin; with both open the bins are the sign-free representative's, on the whole ranges;
// with neither open they are the oriented bins.
static void test_mixed_pair_features() {
    TestRng rng(22);
    int checked = 0, open_flip_changed = 0, decided_flip_changed = 0, both_unlike_sign_free = 0, neither_unlike = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3f p1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
        const Vec3f p2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).cast<float>();
        const Vec3f n1 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
        const Vec3f n2 = Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
        const bool open1 = (i & 1) != 0, open2 = (i & 2) != 0;
        int bins[3], other[3];
        if (!pair_feature_bins(p1, n1, p2, n2, NormalSigns::Mixed, bins, open1, open2)) continue;
        ++checked;
        for (int flips = 1; flips < 4; ++flips) {
            const Vec3f m1 = (flips & 1) ? Vec3f(-n1) : n1, m2 = (flips & 2) ? Vec3f(-n2) : n2;
            REQUIRE(pair_feature_bins(p1, m1, p2, m2, NormalSigns::Mixed, other, open1, open2));
            const bool changed = other[0] != bins[0] || other[1] != bins[1] || other[2] != bins[2];
            const bool only_open = (!(flips & 1) || open1) && (!(flips & 2) || open2);
            (only_open ? open_flip_changed : decided_flip_changed) += changed;
        }
        if (!open1 && !open2) {
            REQUIRE(pair_feature_bins(p1, n1, p2, n2, NormalSigns::Oriented, other));
            neither_unlike += other[0] != bins[0] || other[1] != bins[1] || other[2] != bins[2];
        }
        if (open1 && open2) { // the sign-free representative: f1 in [-pi/2, pi/2], f3 in [0, 1]
            both_unlike_sign_free += bins[0] < 2 || bins[0] > 8 || bins[2] < 5; // sectors of 360/11 degrees
        }
    }
    CHECK(checked > 19900);
    CHECK_MSG(open_flip_changed == 0, "%d flips of open normals changed a bin", open_flip_changed);
    CHECK_MSG(decided_flip_changed > 10000, "flips of decided normals changed only %d bins", decided_flip_changed);
    CHECK_EQ_INT(neither_unlike, 0);
    CHECK_EQ_INT(both_unlike_sign_free, 0);
}

// Sign-free descriptors do not depend on the normals' signs (bitwise), so on no viewpoint; oriented ones do.
static void test_sign_free_descriptors_ignore_normal_signs() {
    const std::vector<Vec3f> pts = scene(11);
    const Descriptors a = describe(pts, Vec3f(3, 3, 10), NormalSigns::Ignored);
    const Descriptors b = describe(pts, Vec3f(-40, 7, -3), NormalSigns::Ignored, 5);
    REQUIRE(!a.keypoint.empty());
    REQUIRE(a.keypoint == b.keypoint);
    CHECK(std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)) == 0);
    const Descriptors c = describe(pts, Vec3f(3, 3, 10), NormalSigns::Oriented);
    const Descriptors e = describe(pts, Vec3f(3, 3, 10), NormalSigns::Oriented, 5);
    CHECK(std::memcmp(c.values.data(), e.values.data(), c.values.size() * sizeof(float)) != 0);
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
    RUN_TEST(test_sign_free_pair_features);
    RUN_TEST(test_sign_free_descriptors_ignore_normal_signs);
    RUN_TEST(test_mixed_pair_features);
    RUN_TEST(test_invalid_neighbours_do_not_leak_in);
    return TEST_SUMMARY();
}
