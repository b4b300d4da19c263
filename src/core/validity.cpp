// SPDX-License-Identifier: MIT
#include "validity.hpp"

#include <cmath>

#include "normals.hpp"

KISSM_DETAIL_BEGIN

Validity check_validity(const std::vector<Eigen::Vector3d> &inlier_points, std::size_t min_inliers, double noise_bound,
                        const Eigen::Matrix3d &rotation, const Eigen::Vector3d &translation) {
    Validity v;
    if (!rotation.allFinite() || !translation.allFinite()) {
        v.reason = Reason::SolverFailed;
        return v;
    }
    if (!inlier_points.empty()) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const auto &p : inlier_points) mean += p;
        mean /= static_cast<double>(inlier_points.size());
        Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
        for (const auto &p : inlier_points) cov.noalias() += (p - mean) * (p - mean).transpose();
        cov /= static_cast<double>(inlier_points.size());
        Eigen::Vector3d lambda, unused;
        symmetric_eigen3(cov, lambda, unused);
        for (int i = 0; i < 3; ++i) v.extent[i] = std::sqrt(std::max(0.0, lambda[i]));
    }
    if (inlier_points.size() < min_inliers)
        v.reason = Reason::TooFewInliers;
    else if (v.extent[1] < noise_bound || v.extent[2] < 0.5 * noise_bound)
        v.reason = Reason::Degenerate;
    return v;
}

Reason check_refined_validity(Reason coarse, const RefinedEvidence &e, const RefinedRule &rule) {
    if (coarse != Reason::None) return coarse;
    if (e.num_correspondences < 6 || e.overlap < rule.min_overlap) return Reason::LowOverlap;
    if (e.condition < rule.min_condition) return Reason::Unconstrained;
    return Reason::None;
}

KISSM_DETAIL_END
