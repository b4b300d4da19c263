// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/fpfh.hpp"
#include "core/radius_search.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

// compute_spfh evaluates each unordered pair once and counts it for both points; it must give exactly what
// evaluating every ordered pair gives, including the pairs where the order matters (equal angles of the
// two normals with the line) and the pairs without a frame.
static bool open(const Normals &normals, std::size_t i) {
    return !normals.open_sign.empty() && normals.open_sign[i] != 0;
}

static std::vector<float> reference_spfh(const std::vector<Vec3f> &points, const Neighborhoods &nb,
                                         const Normals &normals, NormalSigns signs) {
    const std::size_t n = points.size();
    std::vector<float> spfh(n * kDescriptorDim, 0.0f);
    int bins[3];
    for (std::size_t i = 0; i < n; ++i) {
        if (!normals.valid[i]) continue;
        float *h = &spfh[i * kDescriptorDim];
        int pairs = 0;
        for (std::size_t t = 0; t < nb.count(i); ++t) {
            const std::uint32_t j = nb.row(i)[t];
            if (j == i || !normals.valid[j]) continue;
            if (!pair_feature_bins(points[i], normals.normal[i], points[j], normals.normal[j], signs, bins,
                                   open(normals, i), open(normals, j)))
                continue;
            h[bins[0]] += 1.0f;
            h[kBinsPerFeature + bins[1]] += 1.0f;
            h[2 * kBinsPerFeature + bins[2]] += 1.0f;
            ++pairs;
        }
        if (pairs > 0) {
            const float scale = 100.0f / static_cast<float>(pairs);
            for (int c = 0; c < kDescriptorDim; ++c) h[c] *= scale;
        }
    }
    return spfh;
}

static Vec3f random_unit(TestRng &rng) {
    return Vec3d(rng.normal(), rng.normal(), rng.normal()).normalized().cast<float>();
}

// Points on a coarse lattice (many exactly axis-aligned or diagonal connecting lines), a few duplicates
// (pairs without a frame), normals drawn from a small set (equal or opposite normals: exact ties) or random,
// some missing. `spatial_order` sorts the points like voxel centroids (most pairs inside a chunk or the
// next); otherwise neighbours are scattered over all chunks.
struct Scene {
    std::vector<Vec3f> points;
    Normals normals;
};

static Scene make_scene(std::uint64_t seed, std::size_t n, bool spatial_order) {
    TestRng rng(seed);
    Scene s;
    for (std::size_t i = 0; i < n; ++i) {
        if (i > 0 && rng.uniform() < 0.02) {
            s.points.push_back(s.points[static_cast<std::size_t>(rng.uniform() * static_cast<double>(i))]);
            continue;
        }
        const bool lattice = rng.uniform() < 0.5;
        Vec3f p;
        for (int a = 0; a < 3; ++a) {
            const double x = rng.uniform(0, 12);
            p[a] = static_cast<float>(lattice ? std::floor(x * 4) / 4 : x);
        }
        s.points.push_back(p);
    }
    if (spatial_order)
        std::sort(s.points.begin(), s.points.end(), [](const Vec3f &a, const Vec3f &b) {
            return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
        });
    const Vec3f palette[4] = {Vec3f(0, 0, 1), Vec3f(0, 0, -1), Vec3f(1, 0, 0), Vec3f(0.6f, 0.8f, 0.0f)};
    for (std::size_t i = 0; i < n; ++i) {
        const double r = rng.uniform();
        s.normals.valid.push_back(r < 0.1 ? 0 : 1);
        s.normals.normal.push_back(r < 0.1 ? Vec3f::Zero() : r < 0.6 ? palette[i % 4] : random_unit(rng));
        s.normals.open_sign.push_back(rng.uniform() < 0.4 ? 1 : 0); // read under NormalSigns::Mixed only
    }
    return s;
}

static void check_scene(std::uint64_t seed, std::size_t n, bool spatial_order, NormalSigns signs) {
    const Scene s = make_scene(seed, n, spatial_order);
    RunContext ctx1(1, nullptr, Hooks());
    const Neighborhoods nb = radius_neighbors(s.points, 1.0f, ctx1);
    const std::vector<float> ref = reference_spfh(s.points, nb, s.normals, signs);

    // The reference must contain what this test is about: ties where the order changes the bins.
    std::size_t ties = 0, frameless = 0;
    int a[3], b[3];
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t t = 0; t < nb.count(i); ++t) {
            const std::uint32_t j = nb.row(i)[t];
            if (j <= i || !s.normals.valid[i] || !s.normals.valid[j]) continue;
            const bool oi = open(s.normals, i), oj = open(s.normals, j);
            const bool da =
                pair_feature_bins(s.points[i], s.normals.normal[i], s.points[j], s.normals.normal[j], signs, a, oi, oj);
            const bool db =
                pair_feature_bins(s.points[j], s.normals.normal[j], s.points[i], s.normals.normal[i], signs, b, oj, oi);
            ties += da != db || (da && (a[0] != b[0] || a[1] != b[1] || a[2] != b[2]));
            frameless += !da;
        }
    // Sign-free bins of this scene's tied pairs (equal or opposite palette normals) come out the same in both
    // orders, but the tie path still runs: its pairs are evaluated in the other order all the same.
    if (signs != NormalSigns::Ignored) CHECK_MSG(ties > 10, "only %zu order-dependent pairs", ties);
    CHECK_MSG(frameless > 10, "only %zu pairs without a frame", frameless);

    for (int threads = 1; threads <= 3; ++threads) {
        RunContext ctx(threads, nullptr, Hooks());
        const auto spfh = compute_spfh(s.points, nb, s.normals, signs, ctx);
        const std::vector<float> got(spfh.begin(), spfh.end());
        REQUIRE(got.size() == ref.size());
        CHECK_MSG(std::memcmp(got.data(), ref.data(), ref.size() * sizeof(float)) == 0,
                  "seed %llu, %zu points, %s order, %s, %d threads: SPFH differs",
                  static_cast<unsigned long long>(seed), n, spatial_order ? "spatial" : "random",
                  signs == NormalSigns::Ignored ? "sign-free"
                  : signs == NormalSigns::Mixed ? "mixed"
                                                : "oriented",
                  threads);
    }
}

static void test_spfh_matches_per_direction_pairs() {
    for (const NormalSigns signs : {NormalSigns::Oriented, NormalSigns::Ignored, NormalSigns::Mixed}) {
        check_scene(1, 3000, true, signs);
        check_scene(2, 3000, false, signs);
        check_scene(3, 700, true, signs); // a single chunk
        check_scene(4, 5000, true, signs);
    }
}

static void test_spfh_empty_and_tiny() {
    RunContext ctx(2, nullptr, Hooks());
    const std::vector<Vec3f> none;
    Normals no_normals;
    Neighborhoods nb = radius_neighbors(none, 1.0f, ctx);
    CHECK(compute_spfh(none, nb, no_normals, NormalSigns::Oriented, ctx).empty());
    const std::vector<Vec3f> two = {Vec3f(0, 0, 0), Vec3f(0.5f, 0, 0)};
    Normals normals;
    normals.normal = {Vec3f(0, 0, 1), Vec3f(0, 0, 1)};
    normals.valid = {1, 1};
    nb = radius_neighbors(two, 1.0f, ctx);
    for (const NormalSigns signs : {NormalSigns::Oriented, NormalSigns::Ignored, NormalSigns::Mixed}) {
        const auto two_spfh = compute_spfh(two, nb, normals, signs, ctx);
        CHECK(std::vector<float>(two_spfh.begin(), two_spfh.end()) == reference_spfh(two, nb, normals, signs));
    }
}

int main() {
    RUN_TEST(test_spfh_matches_per_direction_pairs);
    RUN_TEST(test_spfh_empty_and_tiny);
    return TEST_SUMMARY();
}
