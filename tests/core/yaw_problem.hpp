// SPDX-License-Identifier: MIT
// Synthetic correspondences for the yaw (4-DoF) solver tests: a LiDAR-like scene (wide horizontally, a few
// metres tall) in a frame whose vertical axis is `up`, the target turned about `up` by `yaw`, optionally tilted
// by `pitch` about a horizontal axis (a pair that breaks the zero roll/pitch model), noise within the bound.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/compat_graph.hpp"
#include "core/gnc_solver.hpp"
#include "core/kcore.hpp"
#include "test_rng.hpp"

struct YawProblem {
    Eigen::Vector3d up;
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    std::vector<Eigen::Vector3d> a, b;
    std::vector<bool> inl;
    double noise_bound;

    // Rotation `angle` about the unit `axis` (Eigen's, independent of the solver's rotation_about).
    static Eigen::Matrix3d about(const Eigen::Vector3d &axis, double angle) {
        return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    }

    YawProblem(std::uint64_t seed, std::size_t n, double outlier_fraction, double yaw, const Eigen::Vector3d &up_in,
               double pitch = 0.0, double bound = 0.2)
        : up(up_in.normalized()), noise_bound(bound) {
        TestRng rng(seed);
        // A horizontal frame (e1, e2) for `up`, independent of the solver's choice.
        const Eigen::Vector3d e1 = up.unitOrthogonal(), e2 = up.cross(e1);
        R = about(e1, pitch) * about(up, yaw);
        t = e1 * rng.uniform(-20, 20) + e2 * rng.uniform(-20, 20) + up * rng.uniform(-2, 2);
        const auto scene_point = [&]() {
            return Eigen::Vector3d(e1 * rng.uniform(-30, 30) + e2 * rng.uniform(-30, 30) + up * rng.uniform(-3, 3));
        };
        for (std::size_t i = 0; i < n; ++i) {
            const Eigen::Vector3d p = scene_point();
            a.push_back(p);
            const bool inlier = rng.uniform() >= outlier_fraction;
            inl.push_back(inlier);
            if (inlier) {
                // Noise of norm at most half the bound, in a uniformly random direction.
                const Eigen::Vector3d dir = Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal()).normalized();
                b.push_back(R * p + t + rng.uniform(0.0, 0.5 * noise_bound) * dir);
            } else {
                b.push_back(R * scene_point() + t); // in the target's scene, but at the wrong place
            }
        }
    }

    std::size_t num_inliers() const {
        std::size_t c = 0;
        for (bool x : inl) c += x;
        return c;
    }

    // The pipeline's pruning: compatibility graph, max k-core; the problem keeps only the core and returns the
    // TIM pairs drawn from its edges.
    std::vector<kissm::detail::IndexPair> prune(kissm::detail::RunContext &ctx, std::size_t max_tims) {
        using namespace kissm::detail;
        std::vector<Vec3f> af, bf;
        for (std::size_t i = 0; i < a.size(); ++i) af.push_back(a[i].cast<float>()), bf.push_back(b[i].cast<float>());
        const CsrGraph g = build_compat_graph(af, bf, static_cast<float>(noise_bound), ctx);
        std::uint32_t k = 0;
        const std::vector<std::uint32_t> core = max_kcore(g, k);
        std::vector<Eigen::Vector3d> ca, cb;
        std::vector<bool> cinl;
        for (auto v : core) ca.push_back(a[v]), cb.push_back(b[v]), cinl.push_back(inl[v]);
        a.swap(ca), b.swap(cb), inl.swap(cinl);
        return sample_induced_edges(g, core, max_tims);
    }
};

inline double rotation_error_deg(const Eigen::Matrix3d &x, const Eigen::Matrix3d &y) {
    const double c = ((x.transpose() * y).trace() - 1.0) / 2.0;
    return std::acos(std::max(-1.0, std::min(1.0, c))) * 180.0 / 3.14159265358979323846;
}
