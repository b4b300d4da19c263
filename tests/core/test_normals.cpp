// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "core/normals.hpp"
#include "core/radius_search.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

static void test_plane_normals_face_viewpoint() {
    // A noisy-free tilted plane through the origin; viewpoint above it.
    TestRng rng(4);
    const Vec3f n_true = Vec3f(0.2f, -0.3f, 1.0f).normalized();
    const Vec3f e1 = n_true.unitOrthogonal(), e2 = n_true.cross(e1);
    std::vector<Vec3f> pts;
    for (int i = 0; i < 3000; ++i)
        pts.push_back(static_cast<float>(rng.uniform(-5, 5)) * e1 + static_cast<float>(rng.uniform(-5, 5)) * e2);
    RunContext ctx(2, nullptr, Hooks());
    const Neighborhoods nb = radius_neighbors(pts, 1.0f, ctx);
    NormalParams np{0.7f, 3, 0.99, 10.0f * n_true};
    const Normals normals = estimate_normals(pts, nb, np, ctx);
    std::size_t valid = 0;
    double worst = 0.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        if (!normals.valid[i]) continue;
        ++valid;
        worst = std::max(worst, 1.0 - static_cast<double>(normals.normal[i].dot(n_true)));
    }
    CHECK(valid > 2900);
    CHECK_MSG(worst < 1e-5, "worst 1 - cos = %g", worst);
}

static void test_sphere_normals_radial() {
    TestRng rng(5);
    std::vector<Vec3f> pts;
    for (int i = 0; i < 20000; ++i) {
        Vec3d d(rng.normal(), rng.normal(), rng.normal());
        pts.push_back((3.0 * d.normalized()).cast<float>());
    }
    RunContext ctx(2, nullptr, Hooks());
    const Neighborhoods nb = radius_neighbors(pts, 0.5f, ctx);
    // The viewpoint at the centre: normals must point inward, along -p.
    NormalParams np{0.3f, 3, 0.99, Vec3f::Zero()};
    const Normals normals = estimate_normals(pts, nb, np, ctx);
    double worst = 0.0;
    std::size_t valid = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        if (!normals.valid[i]) continue;
        ++valid;
        worst = std::max(worst, 1.0 - static_cast<double>(normals.normal[i].dot(-pts[i].normalized())));
    }
    CHECK(valid > 19000);
    CHECK_MSG(worst < 0.01, "worst 1 - cos = %g", worst);
}

// AwayFromNeighbours: outward on a sphere wherever the sphere is seen from outside or inside, and the same
// normals (turned with the cloud) when the cloud is turned and moved: the rule reads only the local shape.
static void test_normals_away_from_neighbours() {
    TestRng rng(12);
    std::vector<Vec3f> pts;
    for (int i = 0; i < 20000; ++i) {
        Vec3d d(rng.normal(), rng.normal(), rng.normal());
        pts.push_back((Vec3d(1, -2, 0.5) + 3.0 * d.normalized()).cast<float>());
    }
    const Eigen::Matrix3f R = Eigen::AngleAxisf(2.1f, Vec3f(0.4f, 0.1f, -0.9f).normalized()).toRotationMatrix();
    const Vec3f t(-7.0f, 3.0f, 11.0f);
    std::vector<Vec3f> moved;
    for (const Vec3f &p : pts) moved.push_back(R * p + t);
    RunContext ctx(2, nullptr, Hooks());
    NormalParams np{0.3f, 3, 0.99, Vec3f(100, 100, 100)}; // the viewpoint is not read
    np.orientation = NormalOrientation::AwayFromNeighbours;
    const Neighborhoods nb = radius_neighbors(pts, 0.5f, ctx), nb_moved = radius_neighbors(moved, 0.5f, ctx);
    const Normals a = estimate_normals(pts, nb, np, ctx), b = estimate_normals(moved, nb_moved, np, ctx);
    std::size_t valid = 0, outward = 0, same = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        if (!a.valid[i] || !b.valid[i]) continue;
        ++valid;
        outward += a.normal[i].dot(pts[i] - Vec3f(1, -2, 0.5f)) > 0.0f;
        same += (R * a.normal[i]).dot(b.normal[i]) > 0.99f;
    }
    CHECK(valid > 19000);
    CHECK_MSG(outward == valid, "%zu of %zu outward", outward, valid);
    CHECK_MSG(same == valid, "%zu of %zu the same after the move", same, valid);
}

static void test_lines_and_sparse_points_get_no_normal() {
    std::vector<Vec3f> pts;
    for (int i = 0; i < 100; ++i) pts.emplace_back(0.1f * static_cast<float>(i), 0.0f, 0.0f); // a line
    pts.emplace_back(50.0f, 50.0f, 50.0f);                                                    // isolated
    pts.emplace_back(50.2f, 50.0f, 50.0f);                                                    // and its one neighbour
    RunContext ctx(1, nullptr, Hooks());
    const Neighborhoods nb = radius_neighbors(pts, 0.5f, ctx);
    const Normals normals = estimate_normals(pts, nb, NormalParams{0.35f, 3, 0.99, Vec3f::Zero()}, ctx);
    std::size_t valid = 0;
    for (auto v : normals.valid) valid += v;
    CHECK_EQ_INT(valid, 0);
    CHECK(select_keypoints(nb, normals, 3).empty());
}

static void test_radius_search_match_brute_force() {
    TestRng rng(6);
    std::vector<Vec3f> pts;
    for (int i = 0; i < 2000; ++i)
        pts.emplace_back(static_cast<float>(rng.uniform(-3, 3)), static_cast<float>(rng.uniform(-3, 3)),
                         static_cast<float>(rng.uniform(-1, 1)));
    RunContext ctx(3, nullptr, Hooks());
    const float r = 0.4f;
    const Neighborhoods nb = radius_neighbors(pts, r, ctx);
    bool same = true;
    for (std::size_t i = 0; i < pts.size() && same; ++i) {
        std::vector<std::uint32_t> brute, grid(nb.row(i), nb.row(i) + nb.count(i));
        for (std::size_t j = 0; j < pts.size(); ++j)
            if ((pts[j] - pts[i]).squaredNorm() < r * r) brute.push_back(static_cast<std::uint32_t>(j));
        std::sort(grid.begin(), grid.end());
        same = brute == grid;
    }
    CHECK(same);
}

static void test_eigen3_closed_form() {
    Eigen::Matrix3d Q = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    const Eigen::Matrix3d A = Q * Eigen::Vector3d(5.0, 2.0, 0.01).asDiagonal() * Q.transpose();
    Eigen::Vector3d lambda, v;
    symmetric_eigen3(A, lambda, v);
    CHECK_NEAR(lambda[0], 5.0, 1e-9);
    CHECK_NEAR(lambda[1], 2.0, 1e-9);
    CHECK_NEAR(lambda[2], 0.01, 1e-9);
    CHECK_NEAR(std::fabs(v.dot(Q.col(2))), 1.0, 1e-9);
}

int main() {
    RUN_TEST(test_plane_normals_face_viewpoint);
    RUN_TEST(test_sphere_normals_radial);
    RUN_TEST(test_normals_away_from_neighbours);
    RUN_TEST(test_lines_and_sparse_points_get_no_normal);
    RUN_TEST(test_radius_search_match_brute_force);
    RUN_TEST(test_eigen3_closed_form);
    return TEST_SUMMARY();
}
