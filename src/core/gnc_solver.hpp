// SPDX-License-Identifier: MIT
// Stage 5: robust pose from the pruned correspondences: rotation by GNC-TLS on translation-invariant
// measurements, translation by truncated least squares, then final inliers.
// Paper: Sec. III-E (\label{subsec:nonminimal_solver}): Eq. (2) (\label{eqn:final_goal}) with the
// truncated least squares loss as rho, solved by graduated non-convexity (its reference Yang et al., RA-L
// 2020). Deviation in the split, not in the loss: Eq. (2) is solved in two steps as in TEASER++, which the
// paper builds on but does not spell out: the rotation from differences of correspondences, in which t of
// Eq. (1) (\label{eq:p-reg-gen-model}) cancels and the noise bound doubles, then the translation by a
// per-axis scalar TLS, then a least-squares polish over the final inliers.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "detail_namespace.hpp"
#include "run_context.hpp"

KISSM_DETAIL_BEGIN

struct SolverParams {
    double noise_bound; // inlier bound on one correspondence, metres
    int max_iterations = 100;
    double gnc_factor = 1.4;
    std::size_t max_tims = 5000; // translation-invariant measurements used by the rotation solver
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
                      int &iterations, RunContext &ctx);

// The GNC-TLS weights of the residuals r2[begin, end) for the squared bound c2 and the current mu (Yang et al.): 1
// up to mu / (mu + 1) c2, 0 from (mu + 1) / mu c2 on, sqrt(c2 mu (mu + 1) / r2) - mu between (the few measurements
// inside the band: a sqrt each). Returns whether every weight came out 0 or 1. Both rotation passes call it, so
// their weights are the same function of their residuals.
inline bool gnc_tls_weights(const double *r2, double *w, std::size_t begin, std::size_t end, double c2, double mu) {
    const double lo = mu / (mu + 1.0) * c2, hi = (mu + 1.0) / mu * c2, scale = c2 * mu * (mu + 1.0);
    bool binary = true;
    for (std::size_t k = begin; k < end; ++k) {
        const double e = r2[k];
        double wk = e >= hi ? 0.0 : 1.0;
        if (e > lo && e < hi) {
            wk = std::sqrt(scale / e) - mu;
            binary = false;
        }
        w[k] = wk;
    }
    return binary;
}

// The GNC-TLS schedule both rotation solvers share (Yang et al.): from `estimate`, mu starts where the surrogate is
// convex over all residuals and grows by gnc_factor until the weights are binary or the cost settles. Each
// pass.run(estimate, c2, mu, ctx) evaluates the residuals of the previous estimate and the weights for this mu in
// one go and returns a partial with cost, binary and max_r2; update(partial) is the weighted estimate. Ends with
// binary `weights` (size n): 1 within the bound under the final estimate. False when fewer than two agree.
template <class Pass, class Estimate, class Update>
bool gnc_tls_schedule(Pass &pass, std::size_t n, double bound, const SolverParams &params, Estimate &estimate,
                      Update &&update, std::vector<double> &weights, int &iterations, RunContext &ctx) {
    const double c2 = std::max(bound * bound, 1e-12);
    const double max_r2 = pass.run(estimate, c2, 0.0, ctx).max_r2;
    if (max_r2 > c2) {
        double mu = 1.0 / (2.0 * max_r2 / c2 - 1.0);
        double prev_cost = std::numeric_limits<double>::infinity();
        for (int it = 0; it < params.max_iterations; ++it) {
            iterations = it + 1;
            const auto p = pass.run(estimate, c2, mu, ctx);
            estimate = update(p);
            if (std::fabs(p.cost - prev_cost) < 1e-12 * std::max(1.0, p.cost)) break;
            prev_cost = p.cost;
            if (p.binary && it > 0) break;
            mu *= params.gnc_factor;
        }
        pass.run(estimate, c2, 0.0, ctx);
    }
    const std::vector<double> &r2 = pass.residuals();
    weights.assign(n, 0.0);
    std::size_t inliers = 0;
    for (std::size_t k = 0; k < n; ++k) {
        weights[k] = r2[k] <= c2 ? 1.0 : 0.0;
        inliers += weights[k] > 0.0;
    }
    return inliers >= 2;
}

// Globally optimal 1-D truncated least squares: argmin_x sum_k min((x_k - x)^2, bound^2).
double scalar_tls(std::vector<double> values, double bound);

// Correspondences with |R a + t - b| <= bound.
std::size_t count_inliers(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                          const Eigen::Matrix3d &R, const Eigen::Vector3d &t, std::vector<std::uint8_t> &mask);

// The polish both solvers end with: a least-squares fit on the inliers, repeated while the inlier set grows or
// stays and changes; a step that would lose inliers is not taken. fit(inlier, ca, cb) is the rotation of the
// inliers centred on their centroids ca (source) and cb (target); t = cb - R ca. Returns the inlier count;
// `inlier` the mask.
template <class FitRotation>
std::size_t polish_pose_by(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                           FitRotation &&fit, Eigen::Matrix3d &R, Eigen::Vector3d &t,
                           std::vector<std::uint8_t> &inlier) {
    std::size_t count = count_inliers(a, b, bound, R, t, inlier);
    // Two inliers fix a yaw and a translation; a third makes any least squares an average.
    for (int round = 0; round < 5 && count >= 3; ++round) {
        Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
        for (std::size_t k = 0; k < a.size(); ++k)
            if (inlier[k]) ca += a[k], cb += b[k];
        ca /= static_cast<double>(count);
        cb /= static_cast<double>(count);
        const Eigen::Matrix3d R2 = fit(inlier, ca, cb);
        const Eigen::Vector3d t2 = cb - R2 * ca;
        std::vector<std::uint8_t> mask2;
        const std::size_t count2 = count_inliers(a, b, bound, R2, t2, mask2);
        if (count2 < count) break;
        const bool same_set = mask2 == inlier;
        R = R2, t = t2, inlier.swap(mask2), count = count2;
        if (same_set) break;
    }
    return count;
}

// polish_pose_by with the centred Kabsch fit: the full rotation.
std::size_t polish_pose(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b, double bound,
                        Eigen::Matrix3d &R, Eigen::Vector3d &t, std::vector<std::uint8_t> &inlier);

using IndexPair = std::pair<std::uint32_t, std::uint32_t>;

// Pairs (k, (k + s) mod n) for a fixed set of strides; all pairs when that is no more than `max_pairs`.
std::vector<IndexPair> strided_pairs(std::size_t n, std::size_t max_pairs);

// A correspondence is a rotation inlier when at least half of its measurements (w > 0) are; measurements
// pair correspondences, so one bad partner does not condemn a good correspondence. Returns the count.
std::size_t rotation_inliers(const std::vector<IndexPair> &pairs, const std::vector<double> &w, std::size_t n,
                             std::vector<std::uint8_t> &mask);

// Translation for a known rotation: per-axis TLS of b - R a over the masked correspondences (all of them when
// `count` < 3), then an L2 consensus mean over those within `beta`.
Eigen::Vector3d tls_translation(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                                const Eigen::Matrix3d &R, const std::vector<std::uint8_t> &mask, std::size_t count,
                                double beta);

// a, b: the correspondences (source, target). `pairs` are the translation-invariant measurements
// (a_l - a_k, b_l - b_k) the rotation solver uses: compatible pairs from the pruning graph are mostly
// inlier-inlier, so GNC sees far fewer outliers than the correspondences have. Empty = strided_pairs().
// The result depends only on the inputs' content, never on threads.
SolverOutput solve_pose(const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b,
                        std::vector<IndexPair> pairs, const SolverParams &params, RunContext &ctx);

KISSM_DETAIL_END
