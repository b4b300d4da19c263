// SPDX-License-Identifier: MIT
#include "confidence.hpp"

#include <algorithm>
#include <cmath>

KISSM_DETAIL_BEGIN

namespace {

// Fitted by bench/confidence_fit.py on half of bench/validity_study.py's runs (2026-12-05: every real pair raw,
// turned and with its frame moved, far keyframes, scan to map, the multi-scan sets, unrelated scans, the synthetic
// and repetitive scenes, the objects of symmetric parts, in every refinement mode, and kissm_refine from 700 disturbed
// truths), judged on the other half (docs/design/accuracy.md, "Confidence"). Intercept first. The registered model's
// weight is damped (few unrefined poses have 1 to 10 inliers; see the fit's MODELS).
constexpr double kRegistered[] = {-3.93451, 2.65136};                         // ln(1 + inliers)
constexpr double kRegisteredRefined[] = {-5.656, 1.76257, 8.02222, -4.89573}; // ln(1 + inliers), overlap, rmse
constexpr double kFromPrior[] = {1.30069, 15.6705, -24.144};                  // overlap, refine_rmse in voxels
// From kAmbiguityFrom on a competitor counts (every valid right pose of the real data is below it); from
// kAmbiguityFull on the pose is a pick among equals, right in the share of the fitted runs of its kind there:
// 4 of 46 registered, 30 of 110 registered and refined.
constexpr double kAmbiguityFrom = 0.6, kAmbiguityFull = 0.8;
constexpr double kPickRegistered = 4.0 / 46.0, kPickRefined = 30.0 / 110.0;

double logistic(double z) { return 1.0 / (1.0 + std::exp(-z)); }

// A number, or `worst` when it is not one.
double or_worst(double v, double worst) { return std::isnan(v) ? worst : v; }

} // namespace

double pose_confidence(const ConfidenceInput &in) {
    if (!in.has_pose) return 0.0;
    const double overlap = std::clamp(or_worst(in.overlap, 0.0), 0.0, 1.0);
    const double rmse = std::clamp(or_worst(in.refine_rmse_voxels, 10.0), 0.0, 10.0);
    if (!in.solver) return logistic(kFromPrior[0] + kFromPrior[1] * overlap + kFromPrior[2] * rmse);
    const double inliers = std::log1p(static_cast<double>(in.inliers));
    const double evidence = in.refined ? logistic(kRegisteredRefined[0] + kRegisteredRefined[1] * inliers +
                                                  kRegisteredRefined[2] * overlap + kRegisteredRefined[3] * rmse)
                                       : logistic(kRegistered[0] + kRegistered[1] * inliers);
    // With a competitor as good, no count of inliers makes the pose likely: it is one pick among equals.
    const double ambiguity = std::clamp(or_worst(in.ambiguity, 1.0), 0.0, 1.0);
    const double competed = std::clamp((ambiguity - kAmbiguityFrom) / (kAmbiguityFull - kAmbiguityFrom), 0.0, 1.0);
    const double pick = in.refined ? kPickRefined : kPickRegistered;
    return evidence * (1.0 - (1.0 - pick) * competed);
}

KISSM_DETAIL_END
