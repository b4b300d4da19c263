// SPDX-License-Identifier: MIT
#include "validity.hpp"

#include <cmath>
#include <limits>

#include "normals.hpp"

KISSM_DETAIL_BEGIN

InlierEvidence inlier_evidence(const std::vector<Eigen::Vector3d> &inlier_points, double noise_bound) {
    InlierEvidence v;
    v.rotation_uncertainty = std::numeric_limits<double>::infinity();
    if (inlier_points.empty()) {
        v.shape = Reason::Degenerate;
        return v;
    }
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto &p : inlier_points) mean += p;
    mean /= static_cast<double>(inlier_points.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto &p : inlier_points) cov.noalias() += (p - mean) * (p - mean).transpose();
    cov /= static_cast<double>(inlier_points.size());
    Eigen::Vector3d lambda, unused;
    symmetric_eigen3(cov, lambda, unused);
    for (int i = 0; i < 3; ++i) v.extent[i] = std::sqrt(std::max(0.0, lambda[i]));
    const double weakest =
        static_cast<double>(inlier_points.size()) * (v.extent[1] * v.extent[1] + v.extent[2] * v.extent[2]);
    if (weakest > 0.0) v.rotation_uncertainty = noise_bound / std::sqrt(weakest);
    if (v.extent[1] < noise_bound || v.extent[2] < 0.5 * noise_bound) v.shape = Reason::Degenerate;
    return v;
}

Reason describable(std::uint64_t source_voxels, std::uint64_t target_voxels, std::uint64_t source_keypoints,
                   std::uint64_t target_keypoints, std::uint64_t min_voxels) {
    if (source_voxels < min_voxels || target_voxels < min_voxels) return Reason::TooFewVoxels;
    if (source_keypoints < 3 || target_keypoints < 3) return Reason::TooFewFeatures;
    return Reason::None;
}

bool yaw_pose_refuted(const YawEvidence &yaw, double max_tilt) {
    const bool contradicts_core = 4 * yaw.rotation_inliers < yaw.max_core_size;
    return contradicts_core || !(yaw.tilt <= max_tilt);
}

Reason coarse_validity(std::uint64_t num_inliers, const InlierEvidence &inliers, const CoarseRule &rule) {
    if (num_inliers < rule.min_inliers) return Reason::TooFewInliers;
    if (inliers.shape != Reason::None) return inliers.shape;
    if (!(inliers.rotation_uncertainty <= rule.max_rotation_uncertainty)) return Reason::UncertainRotation;
    return Reason::None;
}

Reason prior_validity(const RefinedEvidence &refined, const RefinedRule &rule) {
    if (refined.num_correspondences < 6 || !(refined.overlap >= rule.min_overlap)) return Reason::LowOverlap;
    if (!rule.allow_degenerate && !(refined.condition >= rule.min_condition)) return Reason::Unconstrained;
    if (!refined.converged) return Reason::NotConverged;
    if (!(refined.rmse <= rule.max_rmse)) return Reason::LooseAlignment;
    // Under allow_degenerate too: the wrong poses it refuses are turned, not only slid along the weak direction.
    if (refined.rmse > rule.loose_rmse && !(refined.condition >= kWeakCondition)) return Reason::LooseAndWeak;
    // A degenerate pose the caller accepts is uncertain along its weak directions by definition.
    if (!(rule.allow_degenerate && refined.degenerate) &&
        !(kRefinedRotationSigmas * refined.rotation_sigma <= rule.max_rotation_uncertainty))
        return Reason::UncertainRotation;
    return Reason::None;
}

Reason refined_validity(std::uint64_t num_inliers, const InlierEvidence &inliers, const RefinedEvidence &refined,
                        const RefinedRule &rule) {
    if (num_inliers < rule.min_inliers) return Reason::TooFewInliers;
    if (inliers.shape != Reason::None) return inliers.shape;
    const Reason dense = prior_validity(refined, rule);
    if (dense == Reason::LowOverlap) return dense;
    if (!(refined.inlier_coverage >= rule.min_inlier_coverage)) return Reason::ClusteredInliers;
    return dense;
}

KISSM_DETAIL_END
