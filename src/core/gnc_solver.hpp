// Stage 5: robust pose from the pruned correspondences: rotation by GNC-TLS on translation-invariant
// measurements, translation by truncated least squares, then final inliers.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace kissm {
namespace detail {

struct SolverParams {
    double noise_bound;     // inlier bound on one correspondence, metres
    int max_iterations = 100;
    double gnc_factor = 1.4;
    std::size_t max_tims = 20000; // translation-invariant measurements used by the rotation solver
};

struct SolverOutput {
    bool solved = false; // a rotation and translation were estimated
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    std::vector<std::uint8_t> rotation_inlier; // per correspondence
    std::vector<std::uint8_t> inlier;          // per correspondence: |R a + t - b| <= noise_bound
    std::size_t num_rotation_inliers = 0;
    std::size_t num_inliers = 0;
    int iterations = 0;
};

// Weighted Kabsch without centring: the rotation R minimising sum w_k |b_k - R a_k|^2 (det R = +1).
Eigen::Matrix3d weighted_rotation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                                  const std::vector<double> &w);

// GNC-TLS rotation (Yang et al., graduated non-convexity with a truncated least squares loss).
// Returns false when fewer than two measurements end up as inliers.
bool gnc_tls_rotation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                      const SolverParams &params, Eigen::Matrix3d &rotation, std::vector<double> &weights,
                      int &iterations);

// Globally optimal 1-D truncated least squares: argmin_x sum_k min((x_k - x)^2, bound^2).
double scalar_tls(std::vector<double> values, double bound);

// a, b: the correspondences (source, target) in any fixed order; the result depends only on that order's
// content, never on threads. Translation-invariant measurements pair each correspondence with partners at
// fixed strides in the given order (all pairs when few).
SolverOutput solve_pose(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                        const SolverParams &params);

} // namespace detail
} // namespace kissm
