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

namespace {

// The pair feature, and whether the other order of the two points could give different bins: only when the
// two normals make exactly the same angle with the line (or a comparison is NaN), because otherwise both
// orders pick the same source point, and the reversed direction is an exact negation in float, so every
// intermediate value is the same.
inline bool pair_bins(const Vec3f &p1, const Vec3f &n1, const Vec3f &p2, const Vec3f &n2, int bins[3],
                      bool &order_matters) {
    order_matters = false;
    Vec3f d = p2 - p1;
    const float len2 = d.squaredNorm();
    if (!(len2 > 0.0f)) return false; // the same in both orders
    d *= 1.0f / std::sqrt(len2);
    // u is the normal of the point whose normal is closer to the line; d points from it to the other.
    const float c1 = n1.dot(d), c2 = n2.dot(d);
    const float a1 = std::fabs(c1), a2 = std::fabs(c2);
    const bool swap = a1 < a2;
    order_matters = !swap && !(a2 < a1);
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

inline void add_bins(float *h, const int bins[3]) {
    h[bins[0]] += 1.0f;
    h[kBinsPerFeature + bins[1]] += 1.0f;
    h[2 * kBinsPerFeature + bins[2]] += 1.0f;
}

// A pair's bins for the second point of the pair, parked in the edge's slot until that point's owner
// collects them: 4 bits per feature, bit 12 set when the pair has a frame (0 = nothing to add).
constexpr std::uint16_t kCodeValid = 0x1000;

inline std::uint16_t pack_bins(const int bins[3]) {
    return static_cast<std::uint16_t>(kCodeValid | bins[0] | (bins[1] << 4) | (bins[2] << 8));
}

inline void add_code(float *h, std::uint16_t code) {
    h[code & 0xF] += 1.0f;
    h[kBinsPerFeature + ((code >> 4) & 0xF)] += 1.0f;
    h[2 * kBinsPerFeature + ((code >> 8) & 0xF)] += 1.0f;
}

} // namespace

bool pair_feature_bins(const Vec3f &p1, const Vec3f &n1, const Vec3f &p2, const Vec3f &n2, int bins[3]) {
    bool order_matters;
    return pair_bins(p1, n1, p2, n2, bins, order_matters);
}

std::vector<float> compute_spfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                                RunContext &ctx) {
    const std::size_t n = points.size();
    constexpr int D = kDescriptorDim;
    std::vector<float> spfh(n * D, 0.0f);
    if (n == 0) return spfh;

    // Each unordered pair is evaluated once, by the lower index (neighbour lists are symmetric: the same
    // float distance test both ways), and counted for both points. Before the final scaling the histograms
    // hold exact small integers, so the order in which counts arrive does not matter: results are those of
    // the per-direction loop, for any thread count. A chunk owns the histograms of its rows; a pair whose
    // second point lies in a later chunk leaves its code in the edge slot, and the later chunk collects it in
    // a second pass. Neighbours are spatially local and points are in voxel order, so the rows a chunk has to
    // scan for its codes are few.
    constexpr std::size_t kChunk = 1024;
    const std::size_t num_chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::uint16_t> code(nb.index.size(), 0);
    std::vector<std::uint32_t> first_source(num_chunks);

    ctx.parallel_for(n, kChunk, [&](std::size_t b, std::size_t e) {
        std::uint32_t lowest = static_cast<std::uint32_t>(b);
        int fwd[3], rev[3];
        for (std::size_t i = b; i < e; ++i) {
            if (!normals.valid[i]) continue;
            float *hi = &spfh[i * D];
            const Vec3f &pi = points[i], &ni = normals.normal[i];
            for (std::uint64_t k = nb.offsets[i]; k < nb.offsets[i + 1]; ++k) {
                const std::uint32_t j = nb.index[k];
                if (!normals.valid[j]) continue;
                if (j <= i) { // evaluated by row j (or the point itself)
                    lowest = std::min(lowest, j);
                    continue;
                }
                bool order_matters;
                const bool ok = pair_bins(pi, ni, points[j], normals.normal[j], fwd, order_matters);
                bool rev_ok = ok;
                const int *back = fwd;
                if (order_matters) {
                    rev_ok = pair_feature_bins(points[j], normals.normal[j], pi, ni, rev);
                    back = rev;
                }
                if (ok) add_bins(hi, fwd);
                if (j < e) {
                    if (rev_ok) add_bins(&spfh[static_cast<std::size_t>(j) * D], back);
                } else if (rev_ok) {
                    code[k] = pack_bins(back);
                }
            }
        }
        first_source[b / kChunk] = lowest;
    });

    ctx.parallel_for(n, kChunk, [&](std::size_t b, std::size_t e) {
        // Rows before this chunk that have a neighbour in it: codes of pairs whose second point is here.
        for (std::size_t i = first_source[b / kChunk]; i < b; ++i) {
            for (std::uint64_t k = nb.offsets[i]; k < nb.offsets[i + 1]; ++k) {
                const std::uint32_t j = nb.index[k];
                if (j >= b && j < e && code[k] != 0) add_code(&spfh[static_cast<std::size_t>(j) * D], code[k]);
            }
        }
        for (std::size_t i = b; i < e; ++i) {
            float *h = &spfh[i * D];
            // Every pair with a frame adds exactly one count to the first block.
            int pairs = 0;
            for (int c = 0; c < kBinsPerFeature; ++c) pairs += static_cast<int>(h[c]);
            if (pairs > 0) {
                const float scale = 100.0f / static_cast<float>(pairs);
                for (int c = 0; c < D; ++c) h[c] *= scale;
            }
        }
    });
    return spfh;
}

Descriptors compute_fpfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                         std::vector<std::uint32_t> keypoints, float voxel_size, int weight_power,
                         RunContext &ctx) {
    constexpr int D = kDescriptorDim;

    // SPFH is needed for every point that has a normal and neighbours a keypoint; computing it for all
    // points with a normal keeps the loops simple and costs little (almost all of them qualify).
    const std::vector<float> spfh = compute_spfh(points, nb, normals, ctx);

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
