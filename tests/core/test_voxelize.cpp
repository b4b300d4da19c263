// SPDX-License-Identifier: MIT
#include <algorithm>
#include <array>
#include <cstring>
#include <map>

#include "core/failure.hpp"
#include "core/voxelize.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

// A view of pts (which must outlive it), as the input stage gives it for an all-finite cloud.
static InputCloud make_input(const std::vector<Vec3d> &pts) {
    InputCloud in;
    in.view.data = pts.data();
    in.view.count = pts.size();
    in.view.stride_bytes = sizeof(Vec3d);
    in.view.is_double = true;
    in.num_given = pts.size();
    in.min = in.max = pts[0];
    for (const auto &p : pts) in.min = in.min.cwiseMin(p), in.max = in.max.cwiseMax(p);
    return in;
}

static void test_counts_and_centroids() {
    // 4 x 3 x 2 voxels of size 1, each holding 5 points around its centre.
    TestRng rng(1);
    std::vector<Vec3d> pts;
    for (int x = 0; x < 4; ++x)
        for (int y = 0; y < 3; ++y)
            for (int z = 0; z < 2; ++z)
                for (int k = 0; k < 5; ++k)
                    pts.emplace_back(x + 0.1 + 0.8 * rng.uniform(), y + 0.1 + 0.8 * rng.uniform(),
                                     z + 0.1 + 0.8 * rng.uniform());
    RunContext ctx(1, nullptr, Hooks());
    const VoxelCloud v = voxelize(make_input(pts), 1.0, "cloud", ctx);
    CHECK_EQ_INT(v.points.size(), 24);
    // Every centroid lies inside one unit cell and the cells are all different.
    std::vector<int> cells;
    for (const auto &p : v.points) {
        const Vec3d abs = p.cast<double>() + v.origin;
        cells.push_back(static_cast<int>(std::floor(abs.x())) * 100 + static_cast<int>(std::floor(abs.y())) * 10 +
                        static_cast<int>(std::floor(abs.z())));
    }
    std::vector<int> sorted = cells;
    std::sort(sorted.begin(), sorted.end());
    CHECK(std::unique(sorted.begin(), sorted.end()) == sorted.end());
    CHECK(cells == sorted); // x-major key order
}

// voxel_of_points: every point's voxel is the one whose centroid is the mean of exactly the points mapped to it,
// on 200K points (past the chunk size and the merge's key ranges), at 1 and 3 threads.
static void test_voxel_of_points() {
    TestRng rng(5);
    std::vector<Vec3d> pts;
    for (int i = 0; i < 200000; ++i) pts.emplace_back(rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(-3, 3));
    RunContext one(1, nullptr, Hooks()), three(3, nullptr, Hooks());
    std::vector<std::uint64_t> keys;
    const InputCloud in = make_input(pts);
    const VoxelCloud v = voxelize(in, 0.5, "cloud", one, &keys);
    REQUIRE(keys.size() == v.points.size());
    CHECK(std::is_sorted(keys.begin(), keys.end()));
    const std::vector<std::uint32_t> a = voxel_of_points(in, 0.5, "cloud", keys, one);
    const std::vector<std::uint32_t> b = voxel_of_points(in, 0.5, "cloud", keys, three);
    CHECK(a == b);
    std::vector<Vec3d> sum(v.points.size(), Vec3d::Zero());
    std::vector<int> count(v.points.size(), 0);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        REQUIRE(a[i] < v.points.size());
        sum[a[i]] += pts[i] - v.origin;
        ++count[a[i]];
    }
    double worst = 0.0;
    for (std::size_t k = 0; k < v.points.size(); ++k) {
        REQUIRE(count[k] > 0);
        worst = std::max(worst, (sum[k] / count[k] - v.points[k].cast<double>()).norm());
    }
    CHECK_MSG(worst < 1e-4, "centroid of the mapped points %g from the voxel's", worst);
}

static void test_order_independent_of_threads_and_permutation() {
    TestRng rng(2);
    std::vector<Vec3d> pts;
    // Past 16384 points the sums come in per-chunk parts: a shuffle moves points of one voxel between chunks.
    for (int i = 0; i < 150000; ++i) pts.emplace_back(rng.uniform(-20, 20), rng.uniform(-20, 20), rng.uniform(-2, 2));
    RunContext one(1, nullptr, Hooks()), four(4, nullptr, Hooks());
    const VoxelCloud a = voxelize(make_input(pts), 0.5, "cloud", one);
    const VoxelCloud b = voxelize(make_input(pts), 0.5, "cloud", four);
    std::vector<Vec3d> shuffled = pts;
    for (std::size_t i = shuffled.size() - 1; i > 0; --i) std::swap(shuffled[i], shuffled[rng.next() % (i + 1)]);
    const VoxelCloud c = voxelize(make_input(shuffled), 0.5, "cloud", four);
    REQUIRE(a.points.size() == b.points.size());
    REQUIRE(a.points.size() == c.points.size());
    CHECK(std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)) == 0);
    CHECK(std::memcmp(a.points.data(), c.points.data(), a.points.size() * sizeof(Vec3f)) == 0);
    CHECK(a.origin == c.origin);
}

static void test_centroids_are_means() {
    // Against a plain double-precision mean per voxel (the fixed-point sums resolve 2^-30 voxels).
    TestRng rng(4);
    std::vector<Vec3d> pts;
    for (int i = 0; i < 100000; ++i) pts.emplace_back(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(0, 2));
    const double size = 0.7;
    const InputCloud in = make_input(pts);
    RunContext ctx(2, nullptr, Hooks());
    const VoxelCloud v = voxelize(in, size, "cloud", ctx);
    std::map<std::array<long, 3>, std::pair<Vec3d, int>> sums;
    for (const auto &p : pts) {
        const Vec3d rel = (p - in.min) / size;
        const std::array<long, 3> cell = {static_cast<long>(std::floor(rel.x())),
                                          static_cast<long>(std::floor(rel.y())),
                                          static_cast<long>(std::floor(rel.z()))};
        auto it = sums.emplace(cell, std::make_pair(Vec3d(Vec3d::Zero()), 0)).first;
        it->second.first += p - v.origin, ++it->second.second;
    }
    REQUIRE(v.points.size() == sums.size());
    double worst = 0.0;
    std::size_t k = 0;
    for (const auto &kv : sums) { // std::map order is x-major like the voxel keys
        const Vec3d mean = kv.second.first / kv.second.second;
        worst = std::max(worst, (v.points[k++].cast<double>() - mean).norm());
    }
    CHECK_MSG(worst < 2e-6, "worst centroid error %g m", worst);
}

static void test_range_check() {
    std::vector<Vec3d> pts = {Vec3d(0, 0, 0), Vec3d(10, 0, 0), Vec3d(0, 1, 0), Vec3d(0, 0, 1)};
    RunContext ctx(1, nullptr, Hooks());
    bool threw = false;
    try {
        voxelize(make_input(pts), 1e-9, "source", ctx);
    } catch (const Failure &f) {
        threw = f.kind() == ErrorKind::VoxelRange && std::string(f.what()).find("source") != std::string::npos;
    }
    CHECK(threw);
    // Exactly at the limit still works: 2^21 voxels along x.
    const double v = 10.0 / static_cast<double>(kMaxVoxelsPerAxis - 1);
    const VoxelCloud ok = voxelize(make_input(pts), v * 1.000001, "source", ctx);
    CHECK_EQ_INT(ok.points.size(), 4);
}

static void test_large_coordinates_keep_precision() {
    // A 1e7 m offset: local coordinates must come out as if the offset were not there.
    TestRng rng(3);
    std::vector<Vec3d> pts, shifted;
    for (int i = 0; i < 2000; ++i) {
        Vec3d p(rng.uniform(0, 30), rng.uniform(0, 30), rng.uniform(0, 3));
        pts.push_back(p);
        shifted.push_back(p + Vec3d(1e7, -3e6, 250.0));
    }
    RunContext ctx(1, nullptr, Hooks());
    const VoxelCloud a = voxelize(make_input(pts), 0.25, "cloud", ctx);
    const VoxelCloud b = voxelize(make_input(shifted), 0.25, "cloud", ctx);
    REQUIRE(a.points.size() == b.points.size());
    double worst = 0.0;
    for (std::size_t i = 0; i < a.points.size(); ++i)
        worst = std::max(worst, static_cast<double>((a.points[i] - b.points[i]).norm()));
    CHECK_MSG(worst < 1e-5, "worst local difference %g m", worst);
}

int main() {
    RUN_TEST(test_counts_and_centroids);
    RUN_TEST(test_order_independent_of_threads_and_permutation);
    RUN_TEST(test_voxel_of_points);
    RUN_TEST(test_centroids_are_means);
    RUN_TEST(test_range_check);
    RUN_TEST(test_large_coordinates_keep_precision);
    return TEST_SUMMARY();
}
