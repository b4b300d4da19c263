// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cmath>

#include "core/radius_search.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

// radius_neighbors against brute force: the same float distance test ((dx^2 + dy^2) + dz^2 < r^2), runs of
// every length (the vector path takes four points at a time, the tail one), points on cell boundaries,
// duplicates; identical lists for any thread count; symmetric lists (the SPFH relies on it).
static std::vector<Vec3f> cloud(std::uint64_t seed, std::size_t n) {
    TestRng rng(seed);
    std::vector<Vec3f> pts;
    for (std::size_t i = 0; i < n; ++i) {
        if (i > 0 && rng.uniform() < 0.03) {
            pts.push_back(pts[static_cast<std::size_t>(rng.uniform() * static_cast<double>(i))]);
            continue;
        }
        Vec3f p;
        for (int a = 0; a < 3; ++a) {
            const double x = rng.uniform(-3, 9);
            p[a] = static_cast<float>(rng.uniform() < 0.3 ? std::floor(x * 2) / 2 : x); // on cell edges
        }
        pts.push_back(p);
    }
    return pts;
}

static void check(std::uint64_t seed, std::size_t n, float radius) {
    const std::vector<Vec3f> pts = cloud(seed, n);
    RunContext ctx1(1, nullptr, Hooks());
    const Neighborhoods nb = radius_neighbors(pts, radius, ctx1);
    REQUIRE(nb.offsets.size() == n + 1);
    const float r2 = radius * radius;
    std::size_t wrong = 0, asymmetric = 0;
    for (std::size_t i = 0; i < n; ++i) {
        std::vector<std::uint32_t> got(nb.row(i), nb.row(i) + nb.count(i));
        std::sort(got.begin(), got.end());
        std::vector<std::uint32_t> want;
        for (std::size_t j = 0; j < n; ++j) {
            const float dx = pts[j].x() - pts[i].x(), dy = pts[j].y() - pts[i].y(), dz = pts[j].z() - pts[i].z();
            if (dx * dx + dy * dy + dz * dz < r2) want.push_back(static_cast<std::uint32_t>(j));
        }
        wrong += got != want;
        for (const std::uint32_t j : got) {
            const std::uint32_t *first = nb.row(j), *last = nb.row(j) + nb.count(j);
            asymmetric += std::find(first, last, static_cast<std::uint32_t>(i)) == last;
        }
    }
    CHECK_MSG(wrong == 0, "seed %llu: %zu rows differ from brute force", static_cast<unsigned long long>(seed), wrong);
    CHECK_EQ_INT(asymmetric, 0);
    for (int threads = 2; threads <= 3; ++threads) {
        RunContext ctx(threads, nullptr, Hooks());
        const Neighborhoods other = radius_neighbors(pts, radius, ctx);
        CHECK(other.offsets == nb.offsets);
        CHECK(other.blocks == nb.blocks);
    }
}

static void test_matches_brute_force() {
    check(1, 3000, 1.0f);
    check(2, 2500, 0.5f);
    check(3, 40, 3.0f);
}

static void test_single_point() {
    RunContext ctx(1, nullptr, Hooks());
    const Neighborhoods nb = radius_neighbors({Vec3f(1, 2, 3)}, 1.0f, ctx);
    CHECK(nb.offsets.size() == 2 && nb.num_entries() == 1 && nb.count(0) == 1 && nb.row(0)[0] == 0);
}

int main() {
    RUN_TEST(test_matches_brute_force);
    RUN_TEST(test_single_point);
    return TEST_SUMMARY();
}
