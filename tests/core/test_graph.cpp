// SPDX-License-Identifier: MIT
#include <algorithm>

#include "core/compat_graph.hpp"
#include "core/kcore.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

static CsrGraph from_edges(std::size_t n, const std::vector<std::pair<int, int>> &edges) {
    std::vector<std::vector<std::uint32_t>> rows(n);
    for (auto e : edges) {
        rows[static_cast<std::size_t>(e.first)].push_back(static_cast<std::uint32_t>(e.second));
        rows[static_cast<std::size_t>(e.second)].push_back(static_cast<std::uint32_t>(e.first));
    }
    CsrGraph g;
    g.offsets.push_back(0);
    for (auto &r : rows) {
        std::sort(r.begin(), r.end());
        g.adj.insert(g.adj.end(), r.begin(), r.end());
        g.offsets.push_back(g.adj.size());
    }
    return g;
}

static void test_core_numbers_hand_made() {
    // K5 on {0..4}, a triangle {5,6,7} hanging off vertex 4, a path 7-8-9, and an isolated vertex 10.
    std::vector<std::pair<int, int>> e;
    for (int i = 0; i < 5; ++i)
        for (int j = i + 1; j < 5; ++j) e.emplace_back(i, j);
    e.insert(e.end(), {{4, 5}, {5, 6}, {6, 7}, {5, 7}, {7, 8}, {8, 9}});
    const CsrGraph g = from_edges(11, e);
    const std::vector<std::uint32_t> core = core_numbers(g);
    const std::vector<std::uint32_t> expect = {4, 4, 4, 4, 4, 2, 2, 2, 1, 1, 0};
    CHECK(core == expect);
    std::uint32_t k = 0;
    const auto maxcore = max_kcore(g, k);
    CHECK_EQ_INT(k, 4);
    CHECK((maxcore == std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
}

// Two disjoint 4-cliques {0..3}, {4..7} joined by the edge 3-4, and a 6-clique {8..13}.
static std::vector<std::pair<int, int>> two_cliques_and_a_six_clique() {
    std::vector<std::pair<int, int>> e;
    auto clique = [&](int first, int size) {
        for (int i = first; i < first + size; ++i)
            for (int j = i + 1; j < first + size; ++j) e.emplace_back(i, j);
    };
    clique(0, 4);
    clique(4, 4);
    e.emplace_back(3, 4);
    clique(8, 6);
    return e;
}

static void test_core_of_two_cliques() {
    // Two disjoint 4-cliques joined by one edge; plus a 6-clique elsewhere: max core is the 6-clique (k = 5).
    const std::vector<std::pair<int, int>> e = two_cliques_and_a_six_clique();
    std::uint32_t k = 0;
    const auto maxcore = max_kcore(from_edges(14, e), k);
    CHECK_EQ_INT(k, 5);
    CHECK((maxcore == std::vector<std::uint32_t>{8, 9, 10, 11, 12, 13}));
    CHECK(max_kcore(from_edges(3, {}), k).empty());
    CHECK_EQ_INT(k, 0);
}

// Excluded vertices leave the graph: the core numbers equal those of the graph built without them (random graphs
// against that brute force), and the two cliques' example gives the next core once the 6-clique is out.
static void test_core_numbers_without_excluded_vertices() {
    TestRng rng(23);
    for (int trial = 0; trial < 20; ++trial) {
        const std::size_t n = 60;
        std::vector<std::pair<int, int>> e, kept;
        std::vector<std::uint8_t> excluded(n, 0);
        for (std::size_t v = 0; v < n; ++v) excluded[v] = rng.uniform(0, 1) < 0.3;
        const double p = rng.uniform(0.05, 0.4);
        for (int i = 0; i < static_cast<int>(n); ++i)
            for (int j = i + 1; j < static_cast<int>(n); ++j)
                if (rng.uniform(0, 1) < p) {
                    e.emplace_back(i, j);
                    if (!excluded[static_cast<std::size_t>(i)] && !excluded[static_cast<std::size_t>(j)])
                        kept.emplace_back(i, j);
                }
        const std::vector<std::uint32_t> got = core_numbers(from_edges(n, e), &excluded);
        std::vector<std::uint32_t> expect = core_numbers(from_edges(n, kept));
        for (std::size_t v = 0; v < n; ++v)
            if (excluded[v]) expect[v] = 0;
        CHECK_MSG(got == expect, "trial %d: core numbers differ from the graph without the excluded vertices", trial);
    }
    const std::vector<std::pair<int, int>> e = two_cliques_and_a_six_clique();
    std::vector<std::uint8_t> excluded(14, 0);
    for (int v = 8; v < 14; ++v) excluded[static_cast<std::size_t>(v)] = 1;
    std::uint32_t k = 0;
    const auto next = max_kcore(from_edges(14, e), k, &excluded);
    CHECK_EQ_INT(k, 3);
    CHECK((next == std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5, 6, 7}));
}

static void test_compat_graph_matches_definition() {
    TestRng rng(11);
    const std::size_t n = 300;
    std::vector<Vec3f> a(n), b(n);
    for (std::size_t i = 0; i < n; ++i) {
        a[i] = Vec3d(rng.uniform(-10, 10), rng.uniform(-10, 10), rng.uniform(-2, 2)).cast<float>();
        // Half inliers (a pure translation), half random.
        b[i] = i % 2 ? Vec3d(rng.uniform(-10, 10), rng.uniform(-10, 10), rng.uniform(-2, 2)).cast<float>()
                     : Vec3f(a[i] + Vec3f(1, 2, 3));
    }
    RunContext ctx(3, nullptr, Hooks());
    const float eps = 0.2f;
    const CsrGraph g = build_compat_graph(a, b, eps, ctx);
    bool same = true;
    std::uint64_t edges = 0;
    for (std::size_t i = 0; i < n; ++i) {
        std::vector<std::uint32_t> expect;
        for (std::size_t j = 0; j < n; ++j) {
            if (j == i) continue;
            const float d = std::fabs((a[i] - a[j]).norm() - (b[i] - b[j]).norm());
            if (d <= eps) expect.push_back(static_cast<std::uint32_t>(j));
        }
        edges += expect.size();
        std::vector<std::uint32_t> got(g.adj.begin() + static_cast<std::ptrdiff_t>(g.offsets[i]),
                                       g.adj.begin() + static_cast<std::ptrdiff_t>(g.offsets[i + 1]));
        same = same && got == expect;
    }
    CHECK(same);
    CHECK_EQ_INT(g.num_edges(), edges / 2);
    // The inliers (even indices) form the maximum core.
    std::uint32_t k = 0;
    const auto core = max_kcore(g, k);
    bool all_even = !core.empty();
    for (auto v : core) all_even = all_even && v % 2 == 0;
    CHECK(all_even);
    CHECK(core.size() >= n / 2 - 2);
}

int main() {
    RUN_TEST(test_core_numbers_hand_made);
    RUN_TEST(test_core_of_two_cliques);
    RUN_TEST(test_core_numbers_without_excluded_vertices);
    RUN_TEST(test_compat_graph_matches_definition);
    return TEST_SUMMARY();
}
