// SPDX-License-Identifier: MIT
// The keypoint grid against brute force: every box selects exactly the keypoints a pass over all of them
// selects, in ascending order, whatever the box (inside, straddling, around or far from the cloud).
#include <cmath>
#include <limits>

#include "core/keypoint_grid.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

static std::vector<std::uint32_t> brute(const std::vector<Vec3f> &points, const std::vector<std::uint32_t> &keypoint,
                                        double scale, const double lo[3], const double hi[3]) {
    std::vector<std::uint32_t> out;
    for (std::size_t k = 0; k < keypoint.size(); ++k) {
        const Vec3f &p = points[keypoint[k]];
        bool in = true;
        for (int d = 0; d < 3; ++d) {
            const double v = static_cast<double>(p[d]) * scale;
            in = in && v >= lo[d] && v < hi[d];
        }
        if (in) out.push_back(static_cast<std::uint32_t>(k));
    }
    return out;
}

static void test_boxes_match_brute_force() {
    TestRng rng(23);
    std::vector<Vec3f> points;
    std::vector<std::uint32_t> keypoint;
    for (int i = 0; i < 20000; ++i) {
        points.push_back(Vec3f(static_cast<float>(rng.uniform(-400, 600)), static_cast<float>(rng.uniform(-300, 300)),
                               static_cast<float>(rng.uniform(-20, 20))));
        if (i % 3 != 1) keypoint.push_back(static_cast<std::uint32_t>(i)); // keypoints: a subset of the points
    }
    // Positions the grid must leave out (and brute force never selects with finite bounds around the cloud).
    points[keypoint[10]].x() = std::numeric_limits<float>::quiet_NaN();
    points[keypoint[11]].z() = std::numeric_limits<float>::infinity();
    points[keypoint[12]].y() = 3.0e38f;
    for (double column : {3.0, 16.0, 250.0}) {
        const KeypointGrid grid(points, keypoint, column);
        CHECK(!grid.empty());
        CHECK(grid.bytes() >= (keypoint.size() - 3) * sizeof(std::uint32_t));
        std::size_t nonempty = 0;
        for (int trial = 0; trial < 300; ++trial) {
            const double scale = std::pow(10.0, rng.uniform(-2.5, 0.5));
            double lo[3], hi[3];
            for (int d = 0; d < 3; ++d) {
                const double at = d < 2 ? rng.uniform(-700, 800) : rng.uniform(-30, 20);
                const double a = std::floor(at * scale), w = std::ceil(rng.uniform(0, d < 2 ? 300 : 30) * scale);
                lo[d] = a;
                hi[d] = a + w;
            }
            if (trial % 10 == 0) lo[2] = -1e30, hi[2] = 1e30;                 // every height
            if (trial % 50 == 0) lo[0] = lo[1] = -1e30, hi[0] = hi[1] = 1e30; // the whole plane
            const auto got = grid.select(points, keypoint, scale, lo, hi);
            const auto want = brute(points, keypoint, scale, lo, hi);
            CHECK_MSG(got == want, "column %g, trial %d: %zu selected, brute force %zu", column, trial, got.size(),
                      want.size());
            nonempty += !want.empty();
        }
        CHECK_MSG(nonempty > 100, "only %zu boxes held keypoints", nonempty);
    }
}

static void test_degenerate_inputs() {
    const std::vector<Vec3f> points = {Vec3f(1, 2, 3), Vec3f(4, 5, 6)};
    const std::vector<std::uint32_t> none, both = {0, 1};
    const double lo[3] = {-10, -10, -10}, hi[3] = {10, 10, 10};
    CHECK(KeypointGrid(points, none, 1.0).empty());
    CHECK(KeypointGrid(points, none, 1.0).select(points, none, 1.0, lo, hi).empty());
    CHECK(KeypointGrid().select(points, both, 1.0, lo, hi).empty());
    const KeypointGrid grid(points, both, 1.0);
    CHECK_EQ_INT(grid.select(points, both, 1.0, lo, hi).size(), 2);
    CHECK(grid.select(points, both, 0.0, lo, hi).empty()); // no scale, no box
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double bad_lo[3] = {nan, -10, -10};
    CHECK(grid.select(points, both, 1.0, bad_lo, hi).empty());
    const double empty_hi[3] = {-10, 10, 10}; // lo == hi: an empty box
    CHECK(grid.select(points, both, 1.0, lo, empty_hi).empty());
}

int main() {
    RUN_TEST(test_boxes_match_brute_force);
    RUN_TEST(test_degenerate_inputs);
    return TEST_SUMMARY();
}
