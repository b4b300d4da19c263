// SPDX-License-Identifier: MIT
// The refinement's 3-D index (stage 6) against brute force: the same nearest point within the radius, with
// the same float squared distance bits, ties (duplicates, equal distances, points on the splitting planes and on
// the hash's cell borders) broken by the lower index, whatever the hint (none, the answer, any other point, an
// index out of range) and whatever the cell size (no hash, cells smaller or larger than the radius, more cells
// than the keys hold); the radius is inclusive and respected; an empty index finds nothing.
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "core/refine_index.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

namespace {

struct Hit {
    std::uint32_t index = RefineIndex::kNone;
    float dist2 = std::numeric_limits<float>::infinity();
};

// The definition: squared distance summed x, y, z in that order in float, kept when <= max_dist2, the
// lowest index among equal distances (points visited in index order, replaced only by a strictly closer one).
Hit brute_force(const std::vector<Vec3f> &points, const Vec3f &q, float max_dist2) {
    Hit best;
    if (!(max_dist2 >= 0.0f)) return best;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const float dx = points[i].x() - q.x(), dy = points[i].y() - q.y(), dz = points[i].z() - q.z();
        const float d2 = dx * dx + dy * dy + dz * dz;
        if (d2 <= max_dist2 && (best.index == RefineIndex::kNone || d2 < best.dist2))
            best.index = static_cast<std::uint32_t>(i), best.dist2 = d2;
    }
    return best;
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Cell sizes of the hash: none, and cells much smaller than, about as large as and larger than the radii.
const double kCells[] = {0.0, 0.05, 0.3, 2.0};

// Queries whose answer differs from brute force (index or distance bits), for every cell size in `cells` and
// every hint: none, the answer itself, a point next to it in index order, the first and the last point, and
// indices that name no point. Prints the first few.
std::size_t mismatches(const std::vector<Vec3f> &points, const std::vector<Vec3f> &queries, float max_dist2,
                       const std::vector<double> &cells) {
    std::size_t bad = 0;
    std::vector<Hit> want;
    for (const Vec3f &q : queries) want.push_back(brute_force(points, q, max_dist2));
    const auto n = static_cast<std::uint32_t>(points.size());
    for (const double cell : cells) {
        const RefineIndex index(points, cell);
        for (std::size_t k = 0; k < queries.size(); ++k) {
            const Vec3f &q = queries[k];
            const std::uint32_t w = want[k].index;
            const std::uint32_t hints[] = {RefineIndex::kNone,
                                           w,
                                           n > 0 && w != RefineIndex::kNone ? (w + 1) % n : 0,
                                           0,
                                           n > 0 ? n - 1 : 0,
                                           n,
                                           n + 7,
                                           RefineIndex::kNone - 1};
            for (const std::uint32_t hint : hints) {
                float d2 = -1.0f;
                const std::uint32_t got = index.nearest(q, max_dist2, &d2, hint);
                if (got == w && same_bits(d2, want[k].dist2)) continue;
                if (bad++ < 5)
                    std::fprintf(stderr, "  query (%g %g %g) r2 %g cell %g hint %u: got %u (%.9g), want %u (%.9g)\n",
                                 q.x(), q.y(), q.z(), max_dist2, cell, hint, got, d2, w, want[k].dist2);
            }
        }
    }
    return bad;
}

std::size_t mismatches(const std::vector<Vec3f> &points, const std::vector<Vec3f> &queries, float max_dist2) {
    return mismatches(points, queries, max_dist2, std::vector<double>(std::begin(kCells), std::end(kCells)));
}

std::vector<Vec3f> gaussian(TestRng &rng, std::size_t n, double sx, double sy, double sz) {
    std::vector<Vec3f> v;
    for (std::size_t i = 0; i < n; ++i)
        v.emplace_back(static_cast<float>(sx * rng.normal()), static_cast<float>(sy * rng.normal()),
                       static_cast<float>(sz * rng.normal()));
    return v;
}

const float kRadii2[] = {std::numeric_limits<float>::infinity(), 100.0f, 1.0f, 0.04f, 0.0f};

} // namespace

static void test_random_clouds_match_brute_force() {
    TestRng rng(61);
    // Anisotropic, so the splits use every axis at different depths.
    const std::vector<Vec3f> points = gaussian(rng, 5000, 8.0, 3.0, 1.0);
    std::vector<Vec3f> queries = gaussian(rng, 300, 10.0, 4.0, 2.0);
    queries.insert(queries.end(), points.begin(), points.begin() + 100); // on data points: distance 0
    queries.emplace_back(1e4f, -1e4f, 50.0f);                            // far outside
    for (const float r2 : kRadii2) CHECK_MSG(mismatches(points, queries, r2) == 0, "max_dist2 %g", r2);
}

// A regular grid: many points share each coordinate (the median split value is held by many points, on both
// sides), and queries at cell centres, edge midpoints and grid points have many neighbours at exactly the same
// float distance.
static void test_grid_ties_and_split_planes() {
    const auto g = [](int i) { return 0.25f * static_cast<float>(i); };
    std::vector<Vec3f> points;
    for (int x = 0; x < 20; ++x)
        for (int y = 0; y < 12; ++y)
            for (int z = 0; z < 7; ++z) points.emplace_back(g(x), g(y), g(z));
    std::vector<Vec3f> queries;
    for (int x = -1; x < 21; x += 3)
        for (int y = -1; y < 13; y += 2)
            for (int z = -1; z < 8; z += 2) {
                queries.emplace_back(g(x), g(y), g(z));                            // a grid point
                queries.emplace_back(g(x) + 0.125f, g(y) + 0.125f, g(z));          // edge midpoint plane
                queries.emplace_back(g(x) + 0.125f, g(y) + 0.125f, g(z) + 0.125f); // cell centre
            }
    for (const float r2 : kRadii2) CHECK_MSG(mismatches(points, queries, r2) == 0, "grid, max_dist2 %g", r2);
    // Cells as wide as the grid's spacing (and half, and twice it): points and queries on the cells' borders.
    for (const float r2 : {0.0625f, 0.02f, 0.3f})
        CHECK_MSG(mismatches(points, queries, r2, {0.25, 0.125, 0.5}) == 0, "grid cells, max_dist2 %g", r2);
    // The grid in another order: the same point has another index, and the tie must follow it.
    std::vector<Vec3f> reversed(points.rbegin(), points.rend());
    CHECK_EQ_INT(mismatches(reversed, queries, 1.0f), 0);
}

static void test_duplicates() {
    TestRng rng(67);
    std::vector<Vec3f> points = gaussian(rng, 2000, 2.0, 2.0, 2.0);
    // 300 copies of one point scattered through the index order, and copies of a few others.
    const Vec3f dup(0.5f, -0.25f, 1.0f);
    for (int i = 0; i < 300; ++i) points.insert(points.begin() + static_cast<std::ptrdiff_t>(7 * i), dup);
    for (int i = 0; i < 40; ++i) points.push_back(points[static_cast<std::size_t>(i * 13)]);
    std::vector<Vec3f> queries = gaussian(rng, 200, 2.0, 2.0, 2.0);
    queries.push_back(dup);
    queries.push_back(dup + Vec3f(1e-3f, 0.0f, 0.0f));
    for (int i = 0; i < 40; ++i) queries.push_back(points[static_cast<std::size_t>(i * 13)]);
    for (const float r2 : kRadii2) CHECK_MSG(mismatches(points, queries, r2) == 0, "duplicates, max_dist2 %g", r2);
    // The lowest index of the duplicated point wins.
    const RefineIndex index(points, 0.3);
    float d2 = -1.0f;
    CHECK_EQ_INT(index.nearest(dup, 1.0f, &d2), 0);
    CHECK_EQ_INT(index.nearest(dup, 1.0f, &d2, 7 * 299), 0); // a later copy as the hint
    CHECK(d2 == 0.0f);
    // Nothing but duplicates: one leaf's worth and many leaves' worth.
    for (const std::size_t n : {std::size_t{5}, std::size_t{16}, std::size_t{17}, std::size_t{5000}}) {
        const std::vector<Vec3f> same(n, dup);
        const RefineIndex all_same(same, 0.25);
        CHECK_EQ_INT(all_same.size(), n);
        CHECK_EQ_INT(all_same.nearest(Vec3f(3.0f, 3.0f, 3.0f), 100.0f, &d2), 0);
        CHECK_EQ_INT(mismatches(same, queries, 4.0f), 0);
    }
}

// A point exactly at the radius is found (<=); one just outside is not; the returned distance never
// exceeds the bound; NaN and negative bounds find nothing.
static void test_radius_is_inclusive_and_respected() {
    const std::vector<Vec3f> points = {Vec3f(3.0f, 0.0f, 0.0f), Vec3f(0.0f, 5.0f, 0.0f), Vec3f(0.0f, 0.0f, -7.0f)};
    const RefineIndex index(points, 1.0);
    float d2 = -1.0f;
    CHECK_EQ_INT(index.nearest(Vec3f::Zero(), 9.0f, &d2), 0);
    CHECK(d2 == 9.0f);
    CHECK_EQ_INT(index.nearest(Vec3f::Zero(), std::nextafter(9.0f, 0.0f), &d2), RefineIndex::kNone);
    CHECK(std::isinf(d2) && d2 > 0.0f);
    CHECK_EQ_INT(index.nearest(Vec3f::Zero(), -1.0f, &d2), RefineIndex::kNone);
    CHECK(std::isinf(d2));
    CHECK_EQ_INT(index.nearest(Vec3f::Zero(), std::numeric_limits<float>::quiet_NaN(), &d2), RefineIndex::kNone);
    CHECK_EQ_INT(index.nearest(Vec3f(0.0f, 5.0f, 0.0f), 0.0f, &d2), 1); // radius 0: the point itself only
    CHECK(d2 == 0.0f);
    CHECK_EQ_INT(index.nearest(Vec3f(0.0f, 5.0f, 1e-3f), 0.0f, nullptr), RefineIndex::kNone);
    CHECK_EQ_INT(index.nearest(Vec3f(0.0f, 0.0f, -6.0f), 1.0f, nullptr), 2); // dist2 may be NULL
    // A hint beyond the radius finds nothing more than the radius allows.
    CHECK_EQ_INT(index.nearest(Vec3f(0.0f, 0.0f, -6.0f), 0.5f, &d2, 2), RefineIndex::kNone);
    CHECK_EQ_INT(index.nearest(Vec3f(0.0f, 0.0f, -6.0f), 0.5f, &d2, 0), RefineIndex::kNone);
    // A query that is not a number finds nothing, with or without a hint.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    CHECK_EQ_INT(index.nearest(Vec3f(nan, 0.0f, 0.0f), 100.0f, &d2), RefineIndex::kNone);
    CHECK_EQ_INT(index.nearest(Vec3f(0.0f, nan, 0.0f), 100.0f, &d2, 1), RefineIndex::kNone);

    // Many random bounds over a random cloud: every hit within its bound.
    TestRng rng(71);
    const std::vector<Vec3f> cloud = gaussian(rng, 3000, 5.0, 5.0, 5.0);
    const RefineIndex big(cloud, 0.5);
    std::size_t outside = 0, hits = 0, misses = 0;
    for (int k = 0; k < 2000; ++k) {
        const Vec3f q(static_cast<float>(rng.uniform(-8, 8)), static_cast<float>(rng.uniform(-8, 8)),
                      static_cast<float>(rng.uniform(-8, 8)));
        const float r2 = static_cast<float>(rng.uniform(0.0, 2.0));
        const std::uint32_t j = big.nearest(q, r2, &d2, static_cast<std::uint32_t>(k) % 3000);
        if (j == RefineIndex::kNone) {
            ++misses;
            continue;
        }
        ++hits;
        const Vec3f e = cloud[j] - q;
        outside += !(d2 <= r2) || e.squaredNorm() > r2 * (1.0f + 1e-6f);
    }
    CHECK_EQ_INT(outside, 0);
    CHECK(hits > 100 && misses > 100); // both outcomes exercised
}

static void test_empty_and_tiny() {
    float d2 = -1.0f;
    const RefineIndex none;
    CHECK(none.empty());
    CHECK_EQ_INT(none.size(), 0);
    CHECK_EQ_INT(none.nearest(Vec3f::Zero(), std::numeric_limits<float>::infinity(), &d2), RefineIndex::kNone);
    CHECK(std::isinf(d2));
    for (const double cell : kCells) {
        const RefineIndex from_empty(std::vector<Vec3f>(), cell);
        CHECK(from_empty.empty());
        CHECK_EQ_INT(from_empty.nearest(Vec3f(1.0f, 2.0f, 3.0f), 1e30f, &d2), RefineIndex::kNone);
        CHECK_EQ_INT(from_empty.nearest(Vec3f(1.0f, 2.0f, 3.0f), 1e30f, &d2, 0), RefineIndex::kNone);
    }
    // 1 point, exactly a leaf (16), one more than a leaf (17).
    TestRng rng(73);
    for (const std::size_t n : {std::size_t{1}, std::size_t{2}, std::size_t{16}, std::size_t{17}, std::size_t{33}}) {
        const std::vector<Vec3f> pts = gaussian(rng, n, 1.0, 1.0, 1.0);
        const RefineIndex index(pts, 0.3);
        CHECK(!index.empty());
        CHECK_EQ_INT(index.size(), n);
        CHECK(index.bytes() >= n * (3 * sizeof(float) + sizeof(std::uint32_t)));
        CHECK_EQ_INT(mismatches(pts, gaussian(rng, 50, 1.5, 1.5, 1.5), std::numeric_limits<float>::infinity()), 0);
        CHECK_EQ_INT(mismatches(pts, gaussian(rng, 50, 1.5, 1.5, 1.5), 0.3f), 0);
    }
}

// Flat and line-like clouds (zero extent along some axes), as walls and poles give; and a large cloud deep
// enough for the traversal stack to hold many pending subtrees.
static void test_flat_and_large() {
    TestRng rng(79);
    std::vector<Vec3f> flat, line;
    for (int i = 0; i < 4000; ++i) {
        flat.emplace_back(static_cast<float>(rng.uniform(-10, 10)), 2.0f, static_cast<float>(rng.uniform(-3, 3)));
        line.emplace_back(-1.0f, static_cast<float>(rng.uniform(-20, 20)), 4.0f);
    }
    const std::vector<Vec3f> queries = gaussian(rng, 200, 8.0, 4.0, 4.0);
    CHECK_EQ_INT(mismatches(flat, queries, 4.0f), 0);
    CHECK_EQ_INT(mismatches(line, queries, 25.0f), 0);
    CHECK_EQ_INT(mismatches(line, queries, std::numeric_limits<float>::infinity()), 0);
    const std::vector<Vec3f> big = gaussian(rng, 200000, 30.0, 30.0, 5.0);
    CHECK_EQ_INT(mismatches(big, gaussian(rng, 60, 30.0, 30.0, 5.0), 1.0f), 0);
    CHECK_EQ_INT(mismatches(big, gaussian(rng, 20, 30.0, 30.0, 5.0), std::numeric_limits<float>::infinity()), 0);
}

// The way refinement uses the hint: each query a little away from the last one, the last answer as the hint,
// on a dense cloud with cells of the voxel size, so that most searches take the cells. Also far from the
// origin, where a float's spacing is large against the cell margin, and with cells so small that the keys'
// 21 bits per axis do not cover the cloud (the tree alone must then serve).
static void test_moving_queries_with_hints() {
    TestRng rng(83);
    for (const double offset : {0.0, 3000.0}) {
        std::vector<Vec3f> surface;
        for (int i = 0; i < 20000; ++i) {
            const double u = rng.uniform(-10, 10), v = rng.uniform(-10, 10);
            surface.emplace_back(static_cast<float>(offset + u), static_cast<float>(offset + v),
                                 static_cast<float>(offset + 0.3 * std::sin(u) + 0.01 * rng.normal()));
        }
        for (const double cell : {0.1, 0.25, 1e-7}) {
            const RefineIndex index(surface, cell);
            std::size_t bad = 0;
            for (int walk = 0; walk < 20; ++walk) {
                Vec3f q = surface[static_cast<std::size_t>(walk) * 997];
                std::uint32_t hint = RefineIndex::kNone;
                for (int step = 0; step < 30; ++step) {
                    q += Vec3f(static_cast<float>(0.02 * rng.normal()), static_cast<float>(0.02 * rng.normal()),
                               static_cast<float>(0.02 * rng.normal()));
                    for (const float r2 : {0.09f, 1.0f}) {
                        float d2 = -1.0f;
                        const std::uint32_t got = index.nearest(q, r2, &d2, hint);
                        const Hit want = brute_force(surface, q, r2);
                        bad += got != want.index || !same_bits(d2, want.dist2);
                        if (r2 == 0.09f) hint = got;
                    }
                }
            }
            CHECK_MSG(bad == 0, "offset %g, cell %g: %zu answers differ", offset, cell, bad);
        }
    }
}

int main() {
    RUN_TEST(test_random_clouds_match_brute_force);
    RUN_TEST(test_grid_ties_and_split_planes);
    RUN_TEST(test_duplicates);
    RUN_TEST(test_radius_is_inclusive_and_respected);
    RUN_TEST(test_empty_and_tiny);
    RUN_TEST(test_flat_and_large);
    RUN_TEST(test_moving_queries_with_hints);
    return TEST_SUMMARY();
}
