// SPDX-License-Identifier: MIT
#include "confidence.hpp"

#include <algorithm>
#include <cmath>

KISSM_DETAIL_BEGIN

namespace {

// Fitted by bench/confidence_fit.py on half of bench/validity_study.py's runs (2026-12-05: every real pair raw,
// turned and with its frame moved, far keyframes, scan to map, the multi-scan sets, unrelated scans, the synthetic
// and repetitive scenes, in every refinement mode, and kissm_refine from 700 disturbed truths), judged on the
// other half (docs/design/accuracy.md, "Confidence"). Intercept first.
constexpr double kRegistered[] = {-33.3372, 13.297};                  // ln(1 + inliers)
constexpr double kRegisteredRefined[] = {-25.8635, 7.31525, 12.0396}; // ln(1 + inliers), overlap
constexpr double kFromPrior[] = {1.2961, 15.6752, -24.1407};          // overlap, refine_rmse in voxels
// From kAmbiguityFrom on a competitor counts (every valid right pose of the real data is below it); from
// kAmbiguityFull on the pose is a pick among equals, right in the share kPick of the fitted runs there (18 of 108).
constexpr double kAmbiguityFrom = 0.6, kAmbiguityFull = 0.8, kPick = 18.0 / 108.0;

double logistic(double z) { return 1.0 / (1.0 + std::exp(-z)); }

// A number, or `worst` when it is not one.
double or_worst(double v, double worst) { return std::isnan(v) ? worst : v; }

} // namespace

double pose_confidence(const ConfidenceInput &in) {
    if (!in.has_pose) return 0.0;
    const double overlap = std::clamp(or_worst(in.overlap, 0.0), 0.0, 1.0);
    if (!in.solver) {
        const double rmse = std::min(or_worst(in.refine_rmse_voxels, 10.0), 10.0);
        return logistic(kFromPrior[0] + kFromPrior[1] * overlap + kFromPrior[2] * rmse);
    }
    const double inliers = std::log1p(static_cast<double>(in.inliers));
    const double evidence =
        in.refined ? logistic(kRegisteredRefined[0] + kRegisteredRefined[1] * inliers + kRegisteredRefined[2] * overlap)
                   : logistic(kRegistered[0] + kRegistered[1] * inliers);
    // With a competitor as good, no count of inliers makes the pose likely: it is one pick among equals.
    const double ambiguity = std::clamp(or_worst(in.ambiguity, 1.0), 0.0, 1.0);
    const double competed = std::clamp((ambiguity - kAmbiguityFrom) / (kAmbiguityFull - kAmbiguityFrom), 0.0, 1.0);
    return evidence * (1.0 - (1.0 - kPick) * competed);
}

KISSM_DETAIL_END
