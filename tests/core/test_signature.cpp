// SPDX-License-Identifier: MIT
// The cloud signature against an independent computation: the mean and spread per bin by sums of squares in long
// double, the rings by comparing each keypoint's distance with the bands' edges; each block of unit length; zeros
// without keypoints; the same bits when asked again; voxels that are not keypoints are not read.
#include <cmath>
#include <cstring>
#include <vector>

#include "core/signature.hpp"
#include "harness.h"
#include "test_rng.hpp"

using namespace kissm::detail;

namespace {

constexpr std::size_t kDim = static_cast<std::size_t>(kDescriptorDim);

struct Cloud {
    std::vector<Vec3f> points;
    std::vector<std::uint32_t> keypoint;
    std::vector<float> descriptors;
};

Cloud random_cloud(std::uint64_t seed, std::size_t n, double extent) {
    TestRng rng(seed);
    Cloud c;
    for (std::size_t i = 0; i < n; ++i) {
        c.points.push_back(Vec3f(static_cast<float>(rng.uniform(-extent, extent)),
                                 static_cast<float>(rng.uniform(-extent, extent)),
                                 static_cast<float>(rng.uniform(-0.1 * extent, 0.1 * extent))));
        if (i % 4 == 3) continue; // not every voxel is a keypoint
        c.keypoint.push_back(static_cast<std::uint32_t>(i));
        for (std::size_t b = 0; b < kDim; ++b) c.descriptors.push_back(static_cast<float>(rng.uniform(0.0, 100.0)));
    }
    return c;
}

void unit(std::vector<long double> &block) {
    long double squares = 0.0L;
    for (long double v : block) squares += v * v;
    if (squares > 0.0L)
        for (long double &v : block) v /= std::sqrt(squares);
}

// The expected signature, computed another way.
std::vector<long double> oracle(const Cloud &c, double voxel) {
    const std::size_t n = c.keypoint.size();
    std::vector<long double> mean(kDim, 0.0L), spread(kDim, 0.0L), rings(kSignatureRings, 0.0L);
    long double centroid[3] = {0.0L, 0.0L, 0.0L};
    for (std::size_t k = 0; k < n; ++k) {
        for (std::size_t b = 0; b < kDim; ++b) {
            const long double v = c.descriptors[k * kDim + b];
            mean[b] += v;
            spread[b] += v * v;
        }
        for (int d = 0; d < 3; ++d) centroid[d] += c.points[c.keypoint[k]][d];
    }
    for (std::size_t b = 0; b < kDim; ++b) {
        mean[b] /= static_cast<long double>(n);
        spread[b] = std::sqrt(spread[b] / static_cast<long double>(n) - mean[b] * mean[b]);
    }
    for (long double &v : centroid) v /= static_cast<long double>(n);
    for (std::size_t k = 0; k < n; ++k) {
        long double squares = 0.0L;
        for (int d = 0; d < 3; ++d) {
            const long double e = c.points[c.keypoint[k]][d] - centroid[d];
            squares += e * e;
        }
        const long double r = std::sqrt(squares);
        std::size_t band = 0;
        while (band + 1 < kSignatureRings && r >= static_cast<long double>(band + 1) * kSignatureRingVoxels * voxel)
            ++band;
        rings[band] += 1.0L;
    }
    for (long double &v : rings) v = std::sqrt(v / static_cast<long double>(n));
    unit(mean);
    unit(spread);
    unit(rings);
    std::vector<long double> out(mean);
    out.insert(out.end(), spread.begin(), spread.end());
    out.insert(out.end(), rings.begin(), rings.end());
    return out;
}

void check_against_oracle(const Cloud &c, double voxel) {
    double got[kSignatureSize];
    cloud_signature(c.points, c.keypoint, c.descriptors.data(), voxel, got);
    const std::vector<long double> expected = oracle(c, voxel);
    REQUIRE(expected.size() == kSignatureSize);
    double worst = 0.0;
    for (std::size_t i = 0; i < kSignatureSize; ++i)
        worst = std::fmax(worst, std::fabs(got[i] - static_cast<double>(expected[i])));
    CHECK_MSG(worst < 1e-9, "largest difference %.3g", worst);
    double again[kSignatureSize];
    cloud_signature(c.points, c.keypoint, c.descriptors.data(), voxel, again);
    CHECK(std::memcmp(got, again, sizeof got) == 0);
}

void test_against_oracle() {
    check_against_oracle(random_cloud(3, 5000, 60.0), 0.5);  // a street: every band in use
    check_against_oracle(random_cloud(4, 800, 0.1), 0.006);  // an object: the first bands only
    check_against_oracle(random_cloud(5, 3000, 400.0), 0.5); // beyond the last edge: the open band
    check_against_oracle(random_cloud(6, 1, 1.0), 0.5);      // one keypoint: no spread at all
}

void test_no_keypoints_and_other_voxels() {
    Cloud c = random_cloud(7, 400, 20.0);
    double out[kSignatureSize];
    cloud_signature(c.points, {}, nullptr, 0.5, out);
    for (double v : out) CHECK(v == 0.0);
    // Moving a voxel that is not a keypoint changes nothing.
    double before[kSignatureSize], after[kSignatureSize];
    cloud_signature(c.points, c.keypoint, c.descriptors.data(), 0.5, before);
    c.points[3] = Vec3f(1e6f, -1e6f, 0.0f); // voxel 3 is not a keypoint (random_cloud skips i % 4 == 3)
    cloud_signature(c.points, c.keypoint, c.descriptors.data(), 0.5, after);
    CHECK(std::memcmp(before, after, sizeof before) == 0);
}

} // namespace

int main() {
    RUN_TEST(test_against_oracle);
    RUN_TEST(test_no_keypoints_and_other_voxels);
    return TEST_SUMMARY();
}
