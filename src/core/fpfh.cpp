// SPDX-License-Identifier: MIT
#include "fpfh.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "simd_level.hpp"

// SSE2 is part of every x86-64 target (see pair_features.cpp for why not 32-bit x86).
#if (defined(__x86_64__) || defined(_M_X64)) && (defined(__GNUC__) || defined(__clang__))
#  define KISSM_FPFH_SSE2 1
#  include <emmintrin.h>
#  include <immintrin.h>
#else
#  define KISSM_FPFH_SSE2 0
#endif

KISSM_DETAIL_BEGIN

namespace {

// acc[c] += w * h[c] for the 33 bins of one neighbour per call, each bin its own running sum from 0 in neighbour
// order, so the bits are those of the plain loop. The sums stay in registers across a keypoint's neighbours (the
// plain loop over a 33-float array loads and stores them for every neighbour).
static_assert(kDescriptorDim == 33, "32 bins in vectors, the last one alone");
class WeightedSum {
public:
    WeightedSum() {
#if KISSM_FPFH_SSE2
        for (__m128 &a : acc_) a = _mm_setzero_ps();
#else
        std::fill(acc_, acc_ + 32, 0.0f);
#endif
    }
    void add(float w, const float *h) {
#if KISSM_FPFH_SSE2
        const __m128 vw = _mm_set1_ps(w);
        for (int k = 0; k < 8; ++k) acc_[k] = _mm_add_ps(acc_[k], _mm_mul_ps(vw, _mm_loadu_ps(h + 4 * k)));
#else
        for (int c = 0; c < 32; ++c) acc_[c] += w * h[c];
#endif
        last_ += w * h[32];
    }
    void store(float *out) const {
#if KISSM_FPFH_SSE2
        for (int k = 0; k < 8; ++k) _mm_storeu_ps(out + 4 * k, acc_[k]);
#else
        std::copy(acc_, acc_ + 32, out);
#endif
        out[32] = last_;
    }

private:
#if KISSM_FPFH_SSE2
    __m128 acc_[8];
#else
    float acc_[32];
#endif
    float last_ = 0.0f;
};

// WeightedSum's sums over a keypoint's neighbours at eight lanes (simd_level.hpp), from the neighbours' rows in
// spfh and their weights, gathered first (a helper of a target function cannot carry the target's width).
#if KISSM_FPFH_SSE2 && KISSM_HAVE_AVX2_KERNELS
KISSM_TARGET_AVX2 void weighted_sum_avx2(const float *spfh, const std::uint32_t *rows, const float *w,
                                         std::size_t count, float *acc) {
    __m256 sum[4];
    for (__m256 &a : sum) a = _mm256_setzero_ps();
    float last = 0.0f;
    for (std::size_t k = 0; k < count; ++k) {
        const float *h = spfh + static_cast<std::size_t>(rows[k]) * kDescriptorDim;
        const __m256 vw = _mm256_set1_ps(w[k]);
        for (int b = 0; b < 4; ++b) sum[b] = _mm256_add_ps(sum[b], _mm256_mul_ps(vw, _mm256_loadu_ps(h + 8 * b)));
        last += w[k] * h[32];
    }
    for (int b = 0; b < 4; ++b) _mm256_storeu_ps(acc + 8 * b, sum[b]);
    acc[32] = last;
}
#endif

inline void add_code(float *h, std::uint16_t code) {
    h[code & 0xF] += 1.0f;
    h[kBinsPerFeature + ((code >> 4) & 0xF)] += 1.0f;
    h[2 * kBinsPerFeature + ((code >> 8) & 0xF)] += 1.0f;
}

} // namespace

UninitVector<float> compute_spfh(const std::vector<Vec3f> &points, const Neighborhoods &nb, const Normals &normals,
                                 NormalSigns signs, RunContext &ctx) {
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
        const bool mixed = signs == NormalSigns::Mixed && !normals.open_sign.empty();
        auto open = [&](std::size_t k) { return mixed && normals.open_sign[k] != 0; };
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
                if (signs == NormalSigns::Mixed) batch.open[size] = open(j) ? ~std::uint32_t(0) : 0;
                ++size;
            }
            batch.size = size;
            batch_pair_codes(points[i], normals.normal[i], open(i), signs, batch);
            float *hi = &spfh[i * D];
            for (std::size_t m = 0; m < size; ++m) {
                const std::int32_t c = batch.code[m];
                const std::uint32_t j = batch.index[m];
                if (c & kLaneFrame) add_code(hi, static_cast<std::uint16_t>(c));
                std::uint16_t back = c & kLaneFrame ? static_cast<std::uint16_t>(c & (kLaneFrame | 0xFFF)) : 0;
                if (c & kLaneTie) {
                    back = pair_feature_bins(points[j], normals.normal[j], points[i], normals.normal[i], signs, rev,
                                             open(j), open(i))
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
    // most about its own length. With one chunk per span a large scene rescanned far more, and more the
    // wider the scene: points are in voxel (x-major) order, so a neighbour can lie a few x-slices of the
    // whole scene back (docs/design/performance.md, "SPFH second pass").
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
                         NormalSigns signs, std::vector<std::uint32_t> keypoints, float voxel_size, int weight_power,
                         RunContext &ctx) {
    constexpr int D = kDescriptorDim;

    // SPFH is needed for every point that has a normal and neighbours a keypoint; computing it for all
    // points with a normal keeps the loops simple and costs little (almost all of them qualify).
    const UninitVector<float> spfh = compute_spfh(points, nb, normals, signs, ctx);

    Descriptors out;
    out.keypoint = std::move(keypoints);
    const std::size_t m = out.keypoint.size();
    out.values.resize(m * D); // every row is written below
    const float v2 = voxel_size * voxel_size;
    ctx.parallel_for(m, 512, [&](std::size_t b, std::size_t e) {
        // Single precision: at most a few hundred terms of size <= 100 with weights <= 1, summed in a fixed
        // order; the loop over the 33 bins vectorises.
        float acc[D];
        std::vector<std::uint32_t> rows; // the wide path's gathered neighbours and weights
        std::vector<float> weights;
#if KISSM_FPFH_SSE2 && KISSM_HAVE_AVX2_KERNELS
        const bool wide = use_avx2();
#endif
        for (std::size_t q = b; q < e; ++q) {
            const std::uint32_t i = out.keypoint[q];
            const std::uint32_t *row = nb.row(i);
            const std::size_t size = nb.count(i);
            // Each neighbour with a normal, and its weight, in row order.
            const auto for_each_neighbour = [&](auto &&visit) {
                for (std::size_t t = 0; t < size; ++t) {
                    const std::uint32_t j = row[t];
                    if (j == i || !normals.valid[j]) continue;
                    const float w2 = v2 / (points[j] - points[i]).squaredNorm();
                    visit(j, weight_power == 2 ? w2 : std::sqrt(w2));
                }
            };
            std::size_t count = 0;
#if KISSM_FPFH_SSE2 && KISSM_HAVE_AVX2_KERNELS
            if (wide) {
                if (rows.size() < size) rows.resize(size), weights.resize(size);
                for_each_neighbour([&](std::uint32_t j, float w) { rows[count] = j, weights[count++] = w; });
                weighted_sum_avx2(spfh.data(), rows.data(), weights.data(), count, acc);
            } else
#endif
            {
                WeightedSum sum;
                for_each_neighbour([&](std::uint32_t j, float w) {
                    sum.add(w, &spfh[static_cast<std::size_t>(j) * D]);
                    ++count;
                });
                sum.store(acc);
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
