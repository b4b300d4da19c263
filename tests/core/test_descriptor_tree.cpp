// SPDX-License-Identifier: MIT
// The projected-descriptor kd-tree against brute force: the same k nearest, in the same order, with the
// same float distances, ties (duplicate points, equal distances) broken by the lower index.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <nanoflann.hpp>

#include "core/descriptor_tree.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

namespace {

constexpr int kDim = ProjectedKdTree::kDim;

struct Hit {
    float dist;
    std::uint32_t index;
};

// The definition the tree must meet: squared distance summed in dimension order, finite distances only
// (strictly below FLT_MAX), ordered by (distance, index).
std::vector<Hit> brute_force(const std::vector<float> &points, const float *q, int k) {
    std::vector<Hit> all;
    for (std::size_t i = 0; i < points.size() / kDim; ++i) {
        float dist = 0.0f;
        for (int d = 0; d < kDim; ++d) {
            const float t = q[d] - points[i * kDim + d];
            dist += t * t;
        }
        if (dist < std::numeric_limits<float>::max()) all.push_back(Hit{dist, static_cast<std::uint32_t>(i)});
    }
    std::sort(all.begin(), all.end(),
              [](const Hit &a, const Hit &b) { return a.dist != b.dist ? a.dist < b.dist : a.index < b.index; });
    if (all.size() > static_cast<std::size_t>(k)) all.resize(static_cast<std::size_t>(k));
    return all;
}

// Number of queries whose answer differs from brute force in count, index or distance bits.
std::size_t mismatches(const std::vector<float> &points, const std::vector<float> &queries, int k) {
    const ProjectedKdTree tree(points.data(), points.size() / kDim);
    std::size_t bad = 0;
    for (std::size_t q = 0; q < queries.size() / kDim; ++q) {
        std::uint32_t index[ProjectedKdTree::kMaxK], slot[ProjectedKdTree::kMaxK];
        float dist[ProjectedKdTree::kMaxK];
        const int found = tree.nearest(&queries[q * kDim], k, index, dist, slot);
        const std::vector<Hit> want = brute_force(points, &queries[q * kDim], k);
        bool same = found == static_cast<int>(want.size());
        for (int i = 0; same && i < found; ++i)
            same = index[i] == want[static_cast<std::size_t>(i)].index &&
                   std::memcmp(&dist[i], &want[static_cast<std::size_t>(i)].dist, sizeof(float)) == 0 &&
                   slot[i] < tree.num_slots() && tree.slot_index(slot[i]) == index[i];
        bad += !same;
    }
    return bad;
}

std::vector<float> gaussian(TestRng &rng, std::size_t n, double scale) {
    std::vector<float> v(n * kDim);
    for (float &x : v) x = static_cast<float>(scale * rng.normal());
    return v;
}

} // namespace

static void test_random_points_match_brute_force() {
    TestRng rng(31);
    // Anisotropic like projected descriptors: the leading axes spread most.
    std::vector<float> points = gaussian(rng, 3000, 1.0);
    for (std::size_t i = 0; i < 3000; ++i)
        for (int d = 0; d < kDim; ++d) points[i * kDim + d] *= static_cast<float>(8 - d);
    std::vector<float> queries = gaussian(rng, 200, 6.0);
    queries.insert(queries.end(), points.begin(), points.begin() + 100 * kDim); // queries on data points
    for (int d = 0; d < kDim; ++d) queries.push_back(1000.0f);                  // far outside the box
    for (const int k : {1, 2, 7, 16}) CHECK_EQ_INT(mismatches(points, queries, k), 0);
}

// nanoflann (vendored in third_party/, the index matching used before) as an independent oracle: its exact
// k-nearest search, with ties broken by index, must give the same neighbours and distance bits.
namespace {
struct FlatSet {
    const std::vector<float> *v;
    std::size_t kdtree_get_point_count() const { return v->size() / kDim; }
    float kdtree_get_pt(std::size_t i, std::size_t d) const { return (*v)[i * kDim + d]; }
    template <class Box>
    bool kdtree_get_bbox(Box &) const {
        return false;
    }
};
using FlannTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, FlatSet, float, std::uint32_t>, FlatSet,
                                        kDim, std::uint32_t>;
} // namespace

static void test_agrees_with_nanoflann() {
    TestRng rng(37);
    std::vector<float> points = gaussian(rng, 4000, 3.0);
    const std::vector<float> queries = gaussian(rng, 300, 4.0);
    const FlatSet set{&points};
    FlannTree flann(kDim, set, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    const ProjectedKdTree tree(points.data(), 4000);
    std::size_t bad = 0;
    for (std::size_t q = 0; q < 300; ++q) {
        constexpr int k = 16;
        // nanoflann's own order among equal distances is not by index: ask for more and sort (distance, index).
        std::vector<std::uint32_t> fi(k + 8);
        std::vector<float> fd(k + 8);
        const std::size_t got = flann.knnSearch(&queries[q * kDim], k + 8, fi.data(), fd.data());
        std::vector<Hit> want;
        for (std::size_t i = 0; i < got; ++i) want.push_back(Hit{fd[i], fi[i]});
        std::sort(want.begin(), want.end(),
                  [](const Hit &a, const Hit &b) { return a.dist != b.dist ? a.dist < b.dist : a.index < b.index; });
        std::uint32_t index[k];
        float dist[k];
        const int found = tree.nearest(&queries[q * kDim], k, index, dist);
        bool same = found == k;
        for (int i = 0; same && i < k; ++i)
            same = index[i] == want[static_cast<std::size_t>(i)].index &&
                   std::memcmp(&dist[i], &want[static_cast<std::size_t>(i)].dist, sizeof(float)) == 0;
        bad += !same;
    }
    CHECK_EQ_INT(bad, 0);
}

static void test_duplicates_and_equal_distances() {
    TestRng rng(32);
    // Coordinates on a 3-value grid: most points have duplicates and most distances tie.
    std::vector<float> points(2000 * kDim);
    for (float &x : points) x = static_cast<float>(static_cast<int>(rng.uniform(0.0, 3.0)));
    std::vector<float> queries(300 * kDim);
    for (float &x : queries) x = static_cast<float>(static_cast<int>(rng.uniform(0.0, 7.0))) * 0.5f - 0.5f;
    for (const int k : {1, 2, 16}) CHECK_EQ_INT(mismatches(points, queries, k), 0);

    // All points identical: the lowest indices win.
    const std::vector<float> same(100 * kDim, 0.25f);
    CHECK_EQ_INT(mismatches(same, queries, 16), 0);
    const ProjectedKdTree tree(same.data(), 100);
    std::uint32_t index[16];
    float dist[16];
    REQUIRE(tree.nearest(&queries[0], 16, index, dist) == 16);
    for (int i = 0; i < 16; ++i) CHECK_EQ_INT(index[i], i);
}

static void test_small_and_degenerate_sets() {
    TestRng rng(33);
    const std::vector<float> queries = gaussian(rng, 50, 2.0);
    for (const std::size_t n : {0, 1, 3, 15, 16, 17, 33, 65})
        for (const int k : {1, 16}) CHECK_EQ_INT(mismatches(gaussian(rng, n, 1.0), queries, k), 0);

    // Non-finite points are never returned; distances that overflow never count as found.
    std::vector<float> points = gaussian(rng, 500, 1.0);
    for (std::size_t i = 0; i < 500; i += 7) points[i * kDim + i % kDim] = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t i = 3; i < 500; i += 11) points[i * kDim] = std::numeric_limits<float>::infinity();
    for (std::size_t i = 5; i < 500; i += 13) points[i * kDim + 1] = 3e19f;
    CHECK_EQ_INT(mismatches(points, queries, 16), 0);

    const ProjectedKdTree tree(points.data(), 500);
    std::uint32_t index[16];
    float dist[16];
    float nan_query[kDim];
    for (float &x : nan_query) x = std::numeric_limits<float>::quiet_NaN();
    CHECK_EQ_INT(tree.nearest(nan_query, 16, index, dist), 0);
}

static void test_slots_hold_every_finite_point_once() {
    TestRng rng(38);
    for (const std::size_t n : {1, 4, 47, 48, 49, 97, 1000, 4099}) {
        std::vector<float> points = gaussian(rng, n, 2.0);
        std::size_t finite = n;
        if (n > 10) {
            points[3 * kDim + 2] = std::numeric_limits<float>::quiet_NaN();
            points[7 * kDim] = -std::numeric_limits<float>::infinity();
            finite -= 2;
        }
        const ProjectedKdTree tree(points.data(), n);
        // Leaves are full but the last, so padding fills less than one block of 4.
        CHECK_MSG(tree.num_slots() >= finite && tree.num_slots() < finite + 4, "n %zu: %zu slots for %zu points", n,
                  tree.num_slots(), finite);
        std::vector<int> seen(n, 0);
        std::size_t wrong_coords = 0;
        for (std::size_t s = 0; s < tree.num_slots(); ++s) {
            const std::uint32_t i = tree.slot_index(s);
            if (i == ProjectedKdTree::kNoPoint) continue;
            REQUIRE(i < n);
            ++seen[i];
            float p[kDim];
            tree.slot_point(s, p);
            wrong_coords += std::memcmp(p, &points[i * kDim], sizeof p) != 0;
        }
        CHECK_EQ_INT(wrong_coords, 0);
        std::size_t once = 0;
        for (std::size_t i = 0; i < n; ++i) once += seen[i] == 1;
        CHECK_EQ_INT(once, finite);
    }
}

int main() {
    RUN_TEST(test_random_points_match_brute_force);
    RUN_TEST(test_agrees_with_nanoflann);
    RUN_TEST(test_duplicates_and_equal_distances);
    RUN_TEST(test_small_and_degenerate_sets);
    RUN_TEST(test_slots_hold_every_finite_point_once);
    return TEST_SUMMARY();
}
