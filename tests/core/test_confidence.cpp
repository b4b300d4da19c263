// SPDX-License-Identifier: MIT
// The confidence function: 0 without a pose, in [0, 1], monotone in each input the way its
// documentation says (up with the evidence for the pose, down with the evidence against it), NaN as the worst.
#include <cmath>
#include <limits>

#include "core/confidence.hpp"
#include "harness.h"

using namespace kissm::detail;

namespace {

ConfidenceInput registered(std::uint64_t inliers, double ambiguity) {
    ConfidenceInput in;
    in.has_pose = in.solver = true;
    in.inliers = inliers;
    in.ambiguity = ambiguity;
    return in;
}

ConfidenceInput refined(std::uint64_t inliers, double ambiguity, double overlap, double rmse_voxels = 0.3) {
    ConfidenceInput in = registered(inliers, ambiguity);
    in.refined = true;
    in.overlap = overlap;
    in.refine_rmse_voxels = rmse_voxels;
    return in;
}

ConfidenceInput from_prior(double overlap, double rmse_voxels) {
    ConfidenceInput in;
    in.has_pose = in.refined = true;
    in.overlap = overlap;
    in.refine_rmse_voxels = rmse_voxels;
    return in;
}

void test_no_pose_is_zero() {
    ConfidenceInput none;
    CHECK(pose_confidence(none) == 0.0);
    CHECK(pose_confidence(refined(200, 0.0, 0.9)) > 0.99);
}

void test_monotone_in_every_input() {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (std::uint64_t n = 0; n < 400; n += 7) {
        for (double a = 0.0; a <= 1.0; a += 0.05) {
            const double c = pose_confidence(registered(n, a));
            CHECK(c >= 0.0 && c <= 1.0);
            CHECK(pose_confidence(registered(n + 1, a)) >= c);
            CHECK(pose_confidence(registered(n, a + 0.01)) <= c);
            CHECK(pose_confidence(registered(n, nan)) <= c); // NaN: as unsure as ambiguity 1
            const double r = pose_confidence(refined(n, a, 0.5));
            CHECK(pose_confidence(refined(n, a, 0.6)) >= r);
            CHECK(pose_confidence(refined(n + 1, a, 0.5)) >= r && pose_confidence(refined(n, a + 0.01, 0.5)) <= r);
            CHECK(pose_confidence(refined(n, a, nan)) <= r);
            CHECK(pose_confidence(refined(n, a, 0.5, 0.4)) <= r && pose_confidence(refined(n, a, 0.5, nan)) <= r);
        }
    }
    for (double o = 0.0; o <= 1.0; o += 0.05)
        for (double e = 0.0; e <= 3.0; e += 0.1) {
            const double c = pose_confidence(from_prior(o, e));
            CHECK(c >= 0.0 && c <= 1.0);
            CHECK(pose_confidence(from_prior(o + 0.01, e)) >= c && pose_confidence(from_prior(o, e + 0.01)) <= c);
            CHECK(pose_confidence(from_prior(o, nan)) <= c);
        }
}

// The documented shapes: many inliers with no competitor near 1, a competitor as good as the pose near 0; a tight
// refinement from a prior near 1, one that leaves the clouds a voxel apart near 0.
void test_ends() {
    CHECK(pose_confidence(registered(200, 0.05)) > 0.999);
    CHECK(pose_confidence(registered(200, 1.0)) < 0.2);                                    // a pick among equals
    CHECK(pose_confidence(registered(200, 0.5)) == pose_confidence(registered(200, 0.0))); // no competitor counts
    CHECK(pose_confidence(registered(0, 0.0)) < 0.05);
    CHECK(pose_confidence(refined(200, 1.0, 0.9)) < 0.3);      // a pick among equals, refined
    CHECK(pose_confidence(refined(20, 0.0, 0.9, 3.0)) < 0.01); // 20 inliers, the clouds three voxels apart
    CHECK(pose_confidence(from_prior(0.9, 0.3)) > 0.99);
    CHECK(pose_confidence(from_prior(0.9, 1.0)) < 0.01);
}

} // namespace

int main() {
    RUN_TEST(test_no_pose_is_zero);
    RUN_TEST(test_monotone_in_every_input);
    RUN_TEST(test_ends);
    return TEST_SUMMARY();
}
