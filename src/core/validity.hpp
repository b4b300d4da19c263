// SPDX-License-Identifier: MIT
// Stage 5b and 6b: whether a pose can be trusted.
// Paper: Sec. III-E (\label{subsec:nonminimal_solver}): valid when the final inlier set I_final is large
// enough (no numbered equation). Everything else here is an addition of this library, each rule measured on
// every real pair raw, rotated and with its frame moved, and on the synthetic pair at 24 yaws
// (docs/design/accuracy.md, "The validity rules").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

enum class Reason {
    None = 0,
    TooFewVoxels,
    TooFewFeatures,
    TooFewCorrespondences,
    SolverFailed,
    TooFewInliers,
    Degenerate,
    LowOverlap,
    Unconstrained,
    UncertainRotation,
    ClusteredInliers,
    NotConverged,
    Tilted,
    LooseAlignment,
    Ambiguous,
    LooseAndWeak,
};

// Before matching: both clouds need more voxels than a normal needs neighbours (min_voxels) and at least three
// keypoints; otherwise TooFewVoxels or TooFewFeatures.
Reason describable(std::uint64_t source_voxels, std::uint64_t target_voxels, std::uint64_t source_keypoints,
                   std::uint64_t target_keypoints, std::uint64_t min_voxels);

// What the solver's inliers say about its pose.
struct InlierEvidence {
    Reason shape = Reason::None;                      // Degenerate when collinear or planar, else None
    Eigen::Vector3d extent = Eigen::Vector3d::Zero(); // sqrt of the inliers' covariance eigenvalues, descending
    // The rotation's 1-sigma uncertainty (radians) about its worst axis if every inlier were off by the noise
    // bound b: the point-to-point information about the inliers' centroid is N / b^2 (tr(C) I - C), whose
    // smallest eigenvalue is N (l2 + l3) / b^2, so sigma = b / sqrt(N (l2 + l3)). Infinite for no inliers.
    double rotation_uncertainty = 0.0;
};

// The inliers' extents and rotation uncertainty; collinear or planar (second or third extent below the noise
// bound) is Degenerate: such a set pins the pose down only up to a rotation or reflection the data cannot see.
InlierEvidence inlier_evidence(const std::vector<Eigen::Vector3d> &inlier_points, double noise_bound);

// The rule without refinement: at least min_inliers inliers, not degenerate, and the rotation known to within
// max_rotation_uncertainty (2 degrees by default, so that the 5 degree error of a wrong pose is 2.5 sigma
// away). The uncertainty rejects what the inlier count cannot see: inliers on one compact object (a sphere
// matches itself under any rotation) and few inliers along one line.
// A pose valid by the coarse rule whose rotation uncertainty exceeds max_rotation_uncertainty at this many sigmas
// is confirmed by refinement (pipeline.cpp): reported refined when the refined rule accepts it, else unchanged.
// Objects of spheres and boxes kept coarse poses 8-9 degrees off at an uncertainty of 1.4 degrees (inliers on a
// few parts, which the formula counts as independent); refined, they are right (docs/design/accuracy.md,
// "Ambiguity"). Refusing such poses instead lost right 3DMatch poses whose refinement the refined rule declines.
constexpr double kCoarseConfirmSigmas = 2.0;

struct CoarseRule {
    std::uint64_t min_inliers;
    double max_rotation_uncertainty;
};
Reason coarse_validity(std::uint64_t num_inliers, const InlierEvidence &inliers, const CoarseRule &rule);

// rotation_dof = 1: a yaw-only pose is refused (Tilted, with or without refinement) when the data contradict zero
// roll and pitch: the best free rotation on its inliers tilts `up` by more than max_tilt (the rotation
// uncertainty's bound; NaN, nothing measurable, counts as tilted), or the yaw rotation explains under a quarter of
// the max core (the largest set of mutually consistent matches whatever the rotation). docs/design/accuracy.md, "The
// validity rules", has the evidence.
struct YawEvidence {
    std::uint64_t rotation_inliers;
    std::uint64_t max_core_size;
    double tilt; // radians
};
bool yaw_pose_refuted(const YawEvidence &yaw, double max_tilt);

// What refinement (stage 6) found, as the refined rule reads it.
struct RefinedEvidence {
    std::uint64_t num_correspondences = 0; // at the final pose
    double overlap = 0.0;                  // share of source voxels with a target voxel within the distance
    double condition = 0.0;                // see RefineOutput::condition
    double inlier_coverage = 0.0;          // solver inliers' spread over the aligned overlap's (NaN: no solver)
    bool converged = false;                // stopped on its convergence test, not its iteration cap
    double rmse = 0.0;                     // the aligned clouds' residual (RefineOutput::rmse), metres
    // The refined rotation's 1-sigma uncertainty about its worst axis as the information states it (radians):
    // the square root of the largest eigenvalue of inv(information)'s rotation block; infinite when the
    // information is singular.
    double rotation_sigma = 0.0;
    bool degenerate = false; // RefineOutput's weak directions exist (and allow_degenerate may accept them)
};

// The refined rotation is held to the coarse rule's bound (max_rotation_uncertainty) at this many of the sigmas
// its calibrated information states (a 95% bound). Measured on every family of the validity study: the same
// decisions as 4 sigmas of the former, uncalibrated information (which stated about half the sigma), and two
// more right poses valid (docs/design/accuracy.md, "A calibrated information matrix").
constexpr double kRefinedRotationSigmas = 2.0;

// A refined pose whose residual is above kLooseRmseGain voxels while its weakest direction holds less than
// kWeakCondition of the strongest's (refine_condition) is refused (LooseAndWeak). A wrong pose between repeated
// structure lines up the ground and one facade: the rest stays apart (a high residual) and the pose slides along
// the street (a weak direction). On three simulated drives of 1,000 scans, the 28 wrong poses reported valid read
// 0.38 to 0.45 voxel and a condition of 0.014 to 0.070; right poses with so high a residual are well conditioned
// (3DMatch, far keyframes, ground suppressed: at least 0.10), and right poses so weakly conditioned (object rings)
// have lower residuals (at most 0.353 voxel, a Happy Buddha pair 48 degrees apart). docs/design/accuracy.md, "The
// simulated city's wrong poses", has the tables; either number alone loses right poses.
constexpr double kLooseRmseGain = 0.37;
constexpr double kWeakCondition = 0.09;

struct RefinedRule {
    std::uint64_t min_inliers;       // refine_min_inliers
    double max_rotation_uncertainty; // radians: kRefinedRotationSigmas * rotation_sigma at most this
    double min_overlap;
    double min_condition;
    double min_inlier_coverage;
    double max_rmse;       // metres: max_refine_rmse_gain * voxel_size
    double loose_rmse;     // metres: kLooseRmseGain * voxel_size (LooseAndWeak with a condition under kWeakCondition)
    bool allow_degenerate; // skip min_condition: the caller takes the weak directions from elsewhere
};

// The rule with refinement, for a registration: the dense alignment decides the accuracy, so the inliers
// only need to show that the refinement started in the right basin: at least refine_min_inliers, not
// degenerate, and spread over at least min_inlier_coverage of the aligned overlap (inliers on one compact
// object cover a small part of it, whatever the pose). Then the refined pose must overlap (min_overlap), be
// constrained in every direction (min_condition, unless allow_degenerate) and have converged: a refinement still moving
// at its iteration cap is crossing from one basin to another (most wrong local optima measured did), and leave the
// clouds within max_rmse of each other, and its rotation known to within max_rotation_uncertainty at
// kRefinedRotationSigmas of the information's sigma (prior_validity).
Reason refined_validity(std::uint64_t num_inliers, const InlierEvidence &inliers, const RefinedEvidence &refined,
                        const RefinedRule &rule);

// The rule for a refinement from the caller's pose (kissm_refine): overlap, conditioning, convergence, and the
// aligned clouds within max_rmse of each other. Right alignments of two voxelised clouds leave a residual of a
// fraction of a voxel (every real pair measured: at most 0.39 voxels); the wrong local optima that refinements
// from a prior outside the convergence basin reach, and that pass the other tests, leave more (at least 0.48),
// since a road shifted along itself or a scene turned onto its own symmetry matches only part of its structure
// (docs/design/accuracy.md, "Refinement from a prior"). The residual test comes last, so a result another test
// refuses keeps that test's reason.
Reason prior_validity(const RefinedEvidence &refined, const RefinedRule &rule);

KISSM_DETAIL_END
