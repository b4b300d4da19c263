// SPDX-License-Identifier: MIT
#include "fpfh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

// SSE2 is part of every x86-64 target. (Not 32-bit x86: its scalar code may use x87 precision, and the
// vector lanes must match the scalar pair feature bit for bit.)
#if defined(__x86_64__) || defined(_M_X64)
#  define KISSM_FPFH_SSE2 1
#  include <emmintrin.h>
#else
#  define KISSM_FPFH_SSE2 0
#endif

KISSM_DETAIL_BEGIN

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

// The neighbours of one point that it pairs with, as structure of arrays, so that the pair features of a
// whole row are computed four at a time. Each lane performs exactly the operations of pair_bins in the same
// order (Eigen sums a 3-vector's terms as x + (y + z); no FMA), and nothing is reduced across lanes, so the
// bins are bitwise those of the scalar code. The arrays are padded to a multiple of 4 lanes.
struct PairBatch {
    std::vector<float> x, y, z, nx, ny, nz;
    std::vector<std::uint32_t> index; // the neighbour's point index
    std::vector<std::uint64_t> slot;  // its position in the neighbour list
    std::vector<std::int32_t> code;   // bins and flags, see below
    std::size_t size = 0;

    void reserve(std::size_t n) {
        n = (n + 3) & ~std::size_t(3);
        if (x.size() >= n) return;
        for (auto *v : {&x, &y, &z, &nx, &ny, &nz}) v->resize(n);
        index.resize(n), slot.resize(n), code.resize(n);
    }
};

// Code of a lane: bins in bits 0-3, 4-7, 8-11; kLaneFrame when the pair has a frame; kLaneTie when the
// other order of the points could give other bins (equal angles of the normals with the line).
constexpr std::int32_t kLaneFrame = kCodeValid, kLaneTie = kCodeValid << 1;

#if KISSM_FPFH_SSE2
// Intrinsics because GCC does not vectorise the plain loop: under its default -ftrapping-math the selects
// become branches around comparisons and products that may trap, which it will not if-convert.
void batch_pair_codes(const Vec3f &p, const Vec3f &n, PairBatch &batch) {
    // Padding lanes (copies of p itself) only produce codes nobody reads; NaNs in them are harmless.
    for (std::size_t m = batch.size; m < ((batch.size + 3) & ~std::size_t(3)); ++m) {
        batch.x[m] = p.x(), batch.y[m] = p.y(), batch.z[m] = p.z();
        batch.nx[m] = n.x(), batch.ny[m] = n.y(), batch.nz[m] = n.z();
    }
    const __m128 px = _mm_set1_ps(p.x()), py = _mm_set1_ps(p.y()), pz = _mm_set1_ps(p.z());
    const __m128 n1x = _mm_set1_ps(n.x()), n1y = _mm_set1_ps(n.y()), n1z = _mm_set1_ps(n.z());
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    const __m128 sign = _mm_set1_ps(-0.0f);
    // Sector boundaries of the angle bins: lanes with y >= 0 use k = 6..10, the others k = 1..5.
    __m128 cl[5], sl[5], cu[5], su[5];
    for (int k = 0; k < 5; ++k) {
        cl[k] = _mm_set1_ps(kAngleBins.c[1 + k]), sl[k] = _mm_set1_ps(kAngleBins.s[1 + k]);
        cu[k] = _mm_set1_ps(kAngleBins.c[6 + k]), su[k] = _mm_set1_ps(kAngleBins.s[6 + k]);
    }
    // bin_of(value, -1, 1): t = (value - lo) / (hi - lo) * 11; t <= 0 or NaN gives 0, t >= 11 gives 10.
    // Clamping t to [0, 10.5] before the truncation gives the same bins.
    const __m128 lo = _mm_set1_ps(-1.0f), range = _mm_set1_ps(2.0f);
    const __m128 bins = _mm_set1_ps(static_cast<float>(kBinsPerFeature));
    const __m128 top = _mm_set1_ps(static_cast<float>(kBinsPerFeature) - 0.5f);
    const __m128i five = _mm_set1_epi32(kBinsPerFeature / 2);
    const __m128i frame_bit = _mm_set1_epi32(kLaneFrame), tie_bit = _mm_set1_epi32(kLaneTie);
    auto select = [](__m128 mask, __m128 a, __m128 b) {
        return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
    };
    auto dot = [](__m128 ax, __m128 ay, __m128 az, __m128 bx, __m128 by, __m128 bz) {
        return _mm_add_ps(_mm_mul_ps(ax, bx), _mm_add_ps(_mm_mul_ps(ay, by), _mm_mul_ps(az, bz)));
    };
    auto bin_of = [&](__m128 value) {
        __m128 t = _mm_mul_ps(_mm_div_ps(_mm_sub_ps(value, lo), range), bins);
        t = _mm_and_ps(_mm_cmpgt_ps(t, zero), t);
        return _mm_cvttps_epi32(_mm_min_ps(t, top));
    };

    for (std::size_t m = 0; m < batch.size; m += 4) {
        __m128 dx = _mm_sub_ps(_mm_loadu_ps(&batch.x[m]), px);
        __m128 dy = _mm_sub_ps(_mm_loadu_ps(&batch.y[m]), py);
        __m128 dz = _mm_sub_ps(_mm_loadu_ps(&batch.z[m]), pz);
        const __m128 len2 = dot(dx, dy, dz, dx, dy, dz);
        const __m128 inv = _mm_div_ps(one, _mm_sqrt_ps(len2));
        dx = _mm_mul_ps(dx, inv), dy = _mm_mul_ps(dy, inv), dz = _mm_mul_ps(dz, inv);
        const __m128 n2x = _mm_loadu_ps(&batch.nx[m]), n2y = _mm_loadu_ps(&batch.ny[m]);
        const __m128 n2z = _mm_loadu_ps(&batch.nz[m]);
        const __m128 c1 = dot(n1x, n1y, n1z, dx, dy, dz), c2 = dot(n2x, n2y, n2z, dx, dy, dz);
        const __m128 a1 = _mm_andnot_ps(sign, c1), a2 = _mm_andnot_ps(sign, c2);
        const __m128 swap = _mm_cmplt_ps(a1, a2);
        const __m128 tie = _mm_andnot_ps(swap, _mm_cmpnlt_ps(a2, a1));
        const __m128 ux = select(swap, n2x, n1x), uy = select(swap, n2y, n1y), uz = select(swap, n2z, n1z);
        const __m128 bx = select(swap, n1x, n2x), by = select(swap, n1y, n2y), bz = select(swap, n1z, n2z);
        const __m128 flip = _mm_and_ps(swap, sign); // d = -d where swapped
        dx = _mm_xor_ps(dx, flip), dy = _mm_xor_ps(dy, flip), dz = _mm_xor_ps(dz, flip);
        const __m128 f3 = select(swap, _mm_xor_ps(c2, sign), c1);
        __m128 vx = _mm_sub_ps(_mm_mul_ps(dy, uz), _mm_mul_ps(dz, uy));
        __m128 vy = _mm_sub_ps(_mm_mul_ps(dz, ux), _mm_mul_ps(dx, uz));
        __m128 vz = _mm_sub_ps(_mm_mul_ps(dx, uy), _mm_mul_ps(dy, ux));
        const __m128 vlen2 = dot(vx, vy, vz, vx, vy, vz);
        const __m128 vinv = _mm_div_ps(one, _mm_sqrt_ps(vlen2));
        vx = _mm_mul_ps(vx, vinv), vy = _mm_mul_ps(vy, vinv), vz = _mm_mul_ps(vz, vinv);
        const __m128 wx = _mm_sub_ps(_mm_mul_ps(uy, vz), _mm_mul_ps(uz, vy));
        const __m128 wy = _mm_sub_ps(_mm_mul_ps(uz, vx), _mm_mul_ps(ux, vz));
        const __m128 wz = _mm_sub_ps(_mm_mul_ps(ux, vy), _mm_mul_ps(uy, vx));
        const __m128 ay = dot(wx, wy, wz, bx, by, bz), ax = dot(ux, uy, uz, bx, by, bz);
        const __m128 f2 = dot(vx, vy, vz, bx, by, bz);

        const __m128 upper = _mm_cmpge_ps(ay, zero);
        __m128i b0 = _mm_and_si128(_mm_castps_si128(upper), five);
        for (int k = 0; k < 5; ++k) {
            const __m128 ck = select(upper, cu[k], cl[k]), sk = select(upper, su[k], sl[k]);
            const __m128 ge = _mm_cmpge_ps(_mm_sub_ps(_mm_mul_ps(ck, ay), _mm_mul_ps(sk, ax)), zero);
            b0 = _mm_sub_epi32(b0, _mm_castps_si128(ge)); // true is -1
        }
        const __m128i at_origin = _mm_castps_si128(_mm_and_ps(_mm_cmpeq_ps(ay, zero), _mm_cmpeq_ps(ax, zero)));
        b0 = _mm_or_si128(_mm_and_si128(at_origin, five), _mm_andnot_si128(at_origin, b0));
        const __m128i b1 = bin_of(f2), b2 = bin_of(f3);
        const __m128 has_len = _mm_cmpgt_ps(len2, zero);
        const __m128i frame = _mm_castps_si128(_mm_and_ps(has_len, _mm_cmpgt_ps(vlen2, zero)));
        const __m128i order_matters = _mm_castps_si128(_mm_and_ps(has_len, tie));
        __m128i c = _mm_or_si128(b0, _mm_or_si128(_mm_slli_epi32(b1, 4), _mm_slli_epi32(b2, 8)));
        c = _mm_or_si128(c, _mm_or_si128(_mm_and_si128(frame, frame_bit), _mm_and_si128(order_matters, tie_bit)));
        _mm_storeu_si128(reinterpret_cast<__m128i *>(&batch.code[m]), c);
    }
}
#else
void batch_pair_codes(const Vec3f &p, const Vec3f &n, PairBatch &batch) {
    int bins[3];
    for (std::size_t m = 0; m < batch.size; ++m) {
        bool order_matters;
        const Vec3f q(batch.x[m], batch.y[m], batch.z[m]), nq(batch.nx[m], batch.ny[m], batch.nz[m]);
        const bool frame = pair_bins(p, n, q, nq, bins, order_matters);
        batch.code[m] = (frame ? pack_bins(bins) : 0) | (order_matters ? kLaneTie : 0);
    }
}
#endif

} // namespace

bool pair_feature_bins(const Vec3f &p1, const Vec3f &n1, const Vec3f &p2, const Vec3f &n2, int bins[3]) {
    bool order_matters;
    return pair_bins(p1, n1, p2, n2, bins, order_matters);
}

UninitVector<float> compute_spfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                                 RunContext &ctx) {
    const std::size_t n = points.size();
    constexpr int D = kDescriptorDim;
    UninitVector<float> spfh;
    spfh.resize(n * D); // zeroed chunk by chunk in the first pass, by the chunk that owns the rows
    if (n == 0) return spfh;

    // Each unordered pair is evaluated once, by the lower index (neighbour lists are symmetric: the same
    // float distance test both ways), and counted for both points. Before the final scaling the histograms
    // hold exact small integers, so the order in which counts arrive does not matter: results are those of
    // the per-direction loop, for any thread count. A chunk owns the histograms of its rows; a pair whose
    // second point lies in a later chunk leaves its code in the edge slot, and a second pass collects it.
    constexpr std::size_t kChunk = 1024;
    UninitVector<std::uint16_t> code;
    code.resize(nb.num_entries()); // likewise

    // Besides its rows' histograms and codes, each chunk returns its rows' lowest neighbour.
    const std::vector<std::uint32_t> first_source = ctx.map_chunks(n, kChunk, [&](std::size_t b, std::size_t e) {
        std::fill(&spfh[b * D], &spfh[0] + e * D, 0.0f);
        std::fill(&code[0] + nb.offsets[b], &code[0] + nb.offsets[e], std::uint16_t(0));
        std::uint32_t lowest = static_cast<std::uint32_t>(b);
        PairBatch batch;
        int rev[3];
        for (std::size_t i = b; i < e; ++i) {
            if (!normals.valid[i]) continue;
            const std::uint64_t begin = nb.offsets[i];
            const std::uint32_t *row = nb.row(i);
            const std::size_t count = nb.count(i);
            batch.reserve(count);
            std::size_t size = 0;
            for (std::size_t t = 0; t < count; ++t) {
                const std::uint64_t k = begin + t;
                const std::uint32_t j = row[t];
                if (!normals.valid[j]) continue;
                if (j <= i) { // evaluated by row j (or the point itself)
                    lowest = std::min(lowest, j);
                    continue;
                }
                const Vec3f &q = points[j], &m = normals.normal[j];
                batch.x[size] = q.x(), batch.y[size] = q.y(), batch.z[size] = q.z();
                batch.nx[size] = m.x(), batch.ny[size] = m.y(), batch.nz[size] = m.z();
                batch.index[size] = j, batch.slot[size] = k;
                ++size;
            }
            batch.size = size;
            batch_pair_codes(points[i], normals.normal[i], batch);
            float *hi = &spfh[i * D];
            for (std::size_t m = 0; m < size; ++m) {
                const std::int32_t c = batch.code[m];
                const std::uint32_t j = batch.index[m];
                if (c & kLaneFrame) add_code(hi, static_cast<std::uint16_t>(c));
                std::uint16_t back = c & kLaneFrame ? static_cast<std::uint16_t>(c & (kLaneFrame | 0xFFF)) : 0;
                if (c & kLaneTie) {
                    back = pair_feature_bins(points[j], normals.normal[j], points[i], normals.normal[i], rev)
                               ? pack_bins(rev)
                               : 0;
                }
                if (back == 0) continue;
                if (j < e)
                    add_code(&spfh[static_cast<std::size_t>(j) * D], back);
                else
                    code[batch.slot[m]] = back;
            }
        }
        return lowest;
    });
    const std::size_t num_chunks = first_source.size();

    // The second pass works in spans of whole chunks, each at least as long as the reach: how far before a
    // chunk its rows' lowest neighbour lies. A span collects the codes of the rows from its lowest neighbour
    // up to its end (rows inside it too: their codes for later chunks of the same span), so it rescans at
    // most about its own length. With one chunk per span a large scene rescanned far more: points are in
    // voxel (x-major) order, so a neighbour can lie a few x-slices of the whole scene back (12K rows per
    // 1K-row chunk at 3M voxels, a second pass 13x the first and growing with the scene's width).
    std::size_t reach = kChunk;
    for (std::size_t c = 0; c < num_chunks; ++c) reach = std::max<std::size_t>(reach, c * kChunk - first_source[c]);
    const std::size_t span = (reach + kChunk - 1) / kChunk * kChunk;
    ctx.parallel_for(n, span, [&](std::size_t b, std::size_t e) {
        std::size_t first = b;
        for (std::size_t c = b / kChunk; c * kChunk < e; ++c) first = std::min<std::size_t>(first, first_source[c]);
        for (std::size_t i = first; i < e; ++i) {
            const std::uint32_t *row = nb.row(i);
            const std::uint16_t *row_code = &code[nb.offsets[i]];
            for (std::size_t t = 0, count = nb.count(i); t < count; ++t) {
                const std::uint32_t j = row[t];
                if (j >= b && j < e && row_code[t] != 0) add_code(&spfh[static_cast<std::size_t>(j) * D], row_code[t]);
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
                         std::vector<std::uint32_t> keypoints, float voxel_size, int weight_power, RunContext &ctx) {
    constexpr int D = kDescriptorDim;

    // SPFH is needed for every point that has a normal and neighbours a keypoint; computing it for all
    // points with a normal keeps the loops simple and costs little (almost all of them qualify).
    const UninitVector<float> spfh = compute_spfh(points, nb, normals, ctx);

    Descriptors out;
    out.keypoint = std::move(keypoints);
    const std::size_t m = out.keypoint.size();
    out.values.resize(m * D); // every row is written below
    const float v2 = voxel_size * voxel_size;
    ctx.parallel_for(m, 512, [&](std::size_t b, std::size_t e) {
        // Single precision: at most a few hundred terms of size <= 100 with weights <= 1, summed in a fixed
        // order; the loop over the 33 bins vectorises.
        float acc[D];
        for (std::size_t q = b; q < e; ++q) {
            const std::uint32_t i = out.keypoint[q];
            std::fill(acc, acc + D, 0.0f);
            int count = 0;
            const std::uint32_t *row = nb.row(i);
            for (std::size_t t = 0, size = nb.count(i); t < size; ++t) {
                const std::uint32_t j = row[t];
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

KISSM_DETAIL_END
