#include "fpfh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

namespace {

int bin_of(float value, float lo, float hi) {
    const float t = (value - lo) / (hi - lo) * static_cast<float>(kBinsPerFeature);
    if (!(t > 0.0f)) return 0; // also NaN: never reached for valid pairs, but never out of range either
    const int b = static_cast<int>(t);
    return b < kBinsPerFeature ? b : kBinsPerFeature - 1;
}

// Bin of the angle atan2(y, x) in [-pi, pi] split into 11 equal sectors, without calling atan2 (which was
// 40% of the pair-feature cost): the sector boundaries -pi + 2 pi k / 11 for k = 1..5 lie in the lower half
// plane and k = 6..10 in the upper, and within a half plane "angle >= boundary" is the sign of a cross
// product with the boundary direction.
struct AngleBins {
    float c[kBinsPerFeature], s[kBinsPerFeature];
    AngleBins() {
        for (int k = 0; k < kBinsPerFeature; ++k) {
            const double a = -3.14159265358979323846 + 2.0 * 3.14159265358979323846 * k / kBinsPerFeature;
            c[k] = static_cast<float>(std::cos(a));
            s[k] = static_cast<float>(std::sin(a));
        }
    }
    int operator()(float y, float x) const {
        if (y == 0.0f && x == 0.0f) return kBinsPerFeature / 2; // atan2(0, 0) = 0
        const int first = y >= 0.0f ? 6 : 1;
        int bin = first - 1;
        for (int k = first; k < first + 5; ++k) bin += c[k] * y - s[k] * x >= 0.0f;
        return bin;
    }
};

const AngleBins kAngleBins;

} // namespace

bool pair_feature_bins(const Vec3f &p1, const Vec3f &n1, const Vec3f &p2, const Vec3f &n2, int bins[3]) {
    Vec3f d = p2 - p1;
    const float len2 = d.squaredNorm();
    if (!(len2 > 0.0f)) return false;
    d *= 1.0f / std::sqrt(len2);
    // u is the normal of the point whose normal is closer to the line; d points from it to the other.
    const float c1 = n1.dot(d), c2 = n2.dot(d);
    const bool swap = std::fabs(c1) < std::fabs(c2);
    const Vec3f &u = swap ? n2 : n1;
    const Vec3f &nb = swap ? n1 : n2;
    if (swap) d = -d;
    const float f3 = swap ? -c2 : c1;
    Vec3f v = d.cross(u);
    const float vlen2 = v.squaredNorm();
    if (!(vlen2 > 0.0f)) return false;
    v *= 1.0f / std::sqrt(vlen2);
    const Vec3f w = u.cross(v);
    bins[0] = kAngleBins(w.dot(nb), u.dot(nb));
    bins[1] = bin_of(v.dot(nb), -1.0f, 1.0f);
    bins[2] = bin_of(f3, -1.0f, 1.0f);
    return true;
}

Descriptors compute_fpfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                         std::vector<std::uint32_t> keypoints, float voxel_size, int weight_power,
                         RunContext &ctx) {
    const std::size_t n = points.size();
    constexpr int D = kDescriptorDim;

    // SPFH is needed for every point that has a normal and neighbours a keypoint; computing it for all
    // points with a normal keeps the loop simple and costs little (almost all of them qualify).
    std::vector<float> spfh(n * D, 0.0f);
    ctx.parallel_for(n, 1024, [&](std::size_t b, std::size_t e) {
        int bins[3];
        for (std::size_t i = b; i < e; ++i) {
            if (!normals.valid[i]) continue;
            float *h = &spfh[i * D];
            int pairs = 0;
            for (std::uint64_t k = nb.offsets[i]; k < nb.offsets[i + 1]; ++k) {
                const std::uint32_t j = nb.index[k];
                if (j == i || !normals.valid[j]) continue;
                if (!pair_feature_bins(points[i], normals.normal[i], points[j], normals.normal[j], bins)) continue;
                h[bins[0]] += 1.0f;
                h[kBinsPerFeature + bins[1]] += 1.0f;
                h[2 * kBinsPerFeature + bins[2]] += 1.0f;
                ++pairs;
            }
            if (pairs > 0) {
                const float scale = 100.0f / static_cast<float>(pairs);
                for (int c = 0; c < D; ++c) h[c] *= scale;
            }
        }
    });

    Descriptors out;
    out.keypoint = std::move(keypoints);
    const std::size_t m = out.keypoint.size();
    out.values.assign(m * D, 0.0f);
    const float v2 = voxel_size * voxel_size;
    ctx.parallel_for(m, 512, [&](std::size_t b, std::size_t e) {
        // Single precision: at most a few hundred terms of size <= 100 with weights <= 1, summed in a fixed
        // order; the loop over the 33 bins vectorises.
        float acc[D];
        for (std::size_t q = b; q < e; ++q) {
            const std::uint32_t i = out.keypoint[q];
            std::fill(acc, acc + D, 0.0f);
            int count = 0;
            for (std::uint64_t k = nb.offsets[i]; k < nb.offsets[i + 1]; ++k) {
                const std::uint32_t j = nb.index[k];
                if (j == i || !normals.valid[j]) continue;
                const float w2 = v2 / (points[j] - points[i]).squaredNorm();
                const float w = weight_power == 2 ? w2 : std::sqrt(w2);
                const float *h = &spfh[static_cast<std::size_t>(j) * D];
                for (int c = 0; c < D; ++c) acc[c] += w * h[c];
                ++count;
            }
            const float *own = &spfh[static_cast<std::size_t>(i) * D];
            const float inv_count = count > 0 ? 1.0f / static_cast<float>(count) : 0.0f;
            float *dst = &out.values[q * D];
            for (int block = 0; block < 3; ++block) {
                float v[kBinsPerFeature], sum = 0.0f;
                for (int c = 0; c < kBinsPerFeature; ++c) {
                    const int idx = block * kBinsPerFeature + c;
                    v[c] = own[idx] + acc[idx] * inv_count;
                    sum += v[c];
                }
                const float scale = sum > 0.0f ? 100.0f / sum : 0.0f;
                for (int c = 0; c < kBinsPerFeature; ++c) dst[block * kBinsPerFeature + c] = v[c] * scale;
            }
        }
    });
    return out;
}

} // namespace detail
} // namespace v0_1
} // namespace kissm
