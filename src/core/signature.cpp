// SPDX-License-Identifier: MIT
#include "signature.hpp"

#include <algorithm>
#include <cmath>

KISSM_DETAIL_BEGIN

namespace {

constexpr std::size_t kDim = static_cast<std::size_t>(kDescriptorDim);

// Scales values [0, n) to unit length; a zero block stays zero (a cloud without keypoints).
void to_unit_length(double *values, std::size_t n) {
    double squares = 0.0;
    for (std::size_t i = 0; i < n; ++i) squares += values[i] * values[i];
    if (!(squares > 0.0)) return;
    const double inverse = 1.0 / std::sqrt(squares);
    for (std::size_t i = 0; i < n; ++i) values[i] *= inverse;
}

} // namespace

void cloud_signature(const std::vector<Vec3f> &points, const std::vector<std::uint32_t> &keypoint,
                     const float *descriptors, double voxel_size, double *out) {
    std::fill(out, out + kSignatureSize, 0.0);
    const std::size_t count = keypoint.size();
    if (count == 0) return;
    double *mean = out, *spread = out + kDim, *rings = out + 2 * kDim;
    const double inverse_count = 1.0 / static_cast<double>(count);

    // Two passes rather than sums of squares: no cancellation when a bin barely varies.
    Vec3d centroid = Vec3d::Zero();
    for (std::size_t k = 0; k < count; ++k) {
        const float *row = descriptors + k * kDim;
        for (std::size_t b = 0; b < kDim; ++b) mean[b] += static_cast<double>(row[b]);
        centroid += points[keypoint[k]].cast<double>();
    }
    for (std::size_t b = 0; b < kDim; ++b) mean[b] *= inverse_count;
    centroid *= inverse_count;
    const double ring_width = kSignatureRingVoxels * voxel_size;
    for (std::size_t k = 0; k < count; ++k) {
        const float *row = descriptors + k * kDim;
        for (std::size_t b = 0; b < kDim; ++b) {
            const double d = static_cast<double>(row[b]) - mean[b];
            spread[b] += d * d;
        }
        const double ring = (points[keypoint[k]].cast<double>() - centroid).norm() / ring_width;
        rings[std::min(static_cast<std::size_t>(ring), kSignatureRings - 1)] += 1.0;
    }
    for (std::size_t b = 0; b < kDim; ++b) spread[b] = std::sqrt(spread[b] * inverse_count);
    // Square roots of the shares: Hellinger's distance between the distributions, which weighs the sparse
    // far rings more than the shares themselves would.
    for (std::size_t r = 0; r < kSignatureRings; ++r) rings[r] = std::sqrt(rings[r] * inverse_count);
    to_unit_length(mean, kDim);
    to_unit_length(spread, kDim);
    to_unit_length(rings, kSignatureRings);
}

KISSM_DETAIL_END
