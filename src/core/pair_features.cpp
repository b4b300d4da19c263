// SPDX-License-Identifier: MIT
#include "pair_features.hpp"

#include <Eigen/Geometry>

#include <cmath>

#include "simd_level.hpp"

// SSE2 is part of every x86-64 target. (Not 32-bit x86: its scalar code may use x87 precision, and the
// vector lanes must match the scalar pair feature bit for bit.)
#if defined(__x86_64__) || defined(_M_X64)
#  define KISSM_PAIR_FEATURES_SSE2 1
#  include <emmintrin.h>
#  if KISSM_HAVE_AVX2_KERNELS
#    include <immintrin.h>
#  endif
#else
#  define KISSM_PAIR_FEATURES_SSE2 0
#endif

KISSM_DETAIL_BEGIN

namespace {

int bin_of(float value, float lo, float hi) {
    const float t = (value - lo) / (hi - lo) * static_cast<float>(kBinsPerFeature);
    if (!(t > 0.0f)) return 0; // also NaN: never reached for valid pairs, but never out of range either
    const int b = static_cast<int>(t);
    return b < kBinsPerFeature ? b : kBinsPerFeature - 1;
}

// Bin of the angle atan2(y, x) in [start, start + span] split into 11 equal sectors, without calling atan2 (a
// large part of the pair feature's cost; docs/design/performance.md, "Pair features"). Two tables: the whole circle
// [-pi, pi] for oriented normals, the right half plane [-pi/2, pi/2] (x >= 0) for sign-free pairs. In both,
// boundaries k = 1..5 lie below the x axis and k = 6..10 above it, and within one of those halves (less than
// pi wide) "angle >= boundary" is the sign of a cross product with the boundary direction.
struct AngleBins {
    float c[kBinsPerFeature], s[kBinsPerFeature];
    AngleBins(double start, double span) {
        for (int k = 0; k < kBinsPerFeature; ++k) {
            const double a = start + span * k / kBinsPerFeature;
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

constexpr double kPi = 3.14159265358979323846;
const AngleBins kAngleBins(-kPi, 2.0 * kPi), kHalfAngleBins(-0.5 * kPi, kPi);

// The pair feature, and whether the other order of the two points could give different bins: only when the
// two normals make exactly the same angle with the line (or a comparison is NaN), because otherwise both
// orders pick the same source point, and the reversed direction is an exact negation in float, so every
// intermediate value is the same.
inline bool pair_bins(const Vec3f &p1, const Vec3f &n1, bool open1, const Vec3f &p2, const Vec3f &n2, bool open2,
                      NormalSigns signs, int bins[3], bool &order_matters) {
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
    float f3 = swap ? -c2 : c1;
    Vec3f v = d.cross(u);
    const float vlen2 = v.squaredNorm();
    if (!(vlen2 > 0.0f)) return false;
    v *= 1.0f / std::sqrt(vlen2);
    const Vec3f w = u.cross(v);
    float a = w.dot(nb), b = u.dot(nb), f2 = v.dot(nb);
    if (signs == NormalSigns::Oriented) {
        bins[0] = kAngleBins(a, b);
        bins[1] = bin_of(f2, -1.0f, 1.0f);
        bins[2] = bin_of(f3, -1.0f, 1.0f);
        return true;
    }
    // The representative of the sign choices left: u (when its sign is free) turned toward the other point, then
    // nb (when free) toward u. Turning u negates v and keeps w; turning nb negates every dot product with it.
    const bool ignored = signs == NormalSigns::Ignored;
    const bool free_u = ignored || (swap ? open2 : open1), free_b = ignored || (swap ? open1 : open2);
    if (free_u && f3 < 0.0f) f3 = -f3, b = -b, f2 = -f2;
    if (free_b && b < 0.0f) b = -b, a = -a, f2 = -f2;
    // Where f3 or b is zero (exactly planar synthetic scenes have many such pairs) the turn it decides is
    // still open; the remaining choices are settled on a, then f2 (or on b, then f2, when only u is free).
    const bool f3_zero = free_u && f3 == 0.0f, b_zero = free_b && b == 0.0f;
    if (f3_zero && free_b) a = std::fabs(a); // u and n_b both turned: only a changes sign
    if (f3_zero && b_zero)
        f2 = std::fabs(f2);
    else if (b_zero && (a < 0.0f || (a == 0.0f && f2 < 0.0f)))
        a = -a, f2 = -f2; // n_b turned
    else if (f3_zero && !free_b && (b < 0.0f || (b == 0.0f && f2 < 0.0f)))
        b = -b, f2 = -f2; // u turned
    if (ignored) {
        bins[0] = kHalfAngleBins(a, b);
        bins[1] = bin_of(f2, -1.0f, 1.0f);
        bins[2] = bin_of(f3, 0.0f, 1.0f);
    } else {
        bins[0] = kAngleBins(a, b);
        bins[1] = bin_of(f2, -1.0f, 1.0f);
        bins[2] = bin_of(f3, -1.0f, 1.0f);
    }
    return true;
}

} // namespace

#if KISSM_PAIR_FEATURES_SSE2 && KISSM_HAVE_AVX2_KERNELS
namespace {

// The SSE2 kernel below at eight lanes (simd_level.hpp): each operation is its 256-bit twin, so each lane's bits are
// the SSE2 lane's. Helpers rather than lambdas, which would not inherit the target.
KISSM_TARGET_AVX2 inline __m256 sel8(__m256 mask, __m256 a, __m256 b) {
    return _mm256_or_ps(_mm256_and_ps(mask, a), _mm256_andnot_ps(mask, b));
}
KISSM_TARGET_AVX2 inline __m256 dot8(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz) {
    return _mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_add_ps(_mm256_mul_ps(ay, by), _mm256_mul_ps(az, bz)));
}
KISSM_TARGET_AVX2 inline __m256i bin8(__m256 value, __m256 from, __m256 width, __m256 bins, __m256 top) {
    __m256 t = _mm256_mul_ps(_mm256_div_ps(_mm256_sub_ps(value, from), width), bins);
    t = _mm256_and_ps(_mm256_cmp_ps(t, _mm256_setzero_ps(), _CMP_GT_OS), t);
    return _mm256_cvttps_epi32(_mm256_min_ps(t, top));
}

KISSM_TARGET_AVX2 void batch_pair_codes_avx2(const Vec3f &p, const Vec3f &n, bool open, NormalSigns signs,
                                             PairBatch &batch) {
    for (std::size_t m = batch.size; m < ((batch.size + 7) & ~std::size_t(7)); ++m) {
        batch.x[m] = p.x(), batch.y[m] = p.y(), batch.z[m] = p.z();
        batch.nx[m] = n.x(), batch.ny[m] = n.y(), batch.nz[m] = n.z();
        batch.open[m] = 0;
    }
    const __m256 px = _mm256_set1_ps(p.x()), py = _mm256_set1_ps(p.y()), pz = _mm256_set1_ps(p.z());
    const __m256 n1x = _mm256_set1_ps(n.x()), n1y = _mm256_set1_ps(n.y()), n1z = _mm256_set1_ps(n.z());
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 sign = _mm256_set1_ps(-0.0f);
    __m256 cl[5], sl[5], cu[5], su[5];
    const bool sign_free = signs == NormalSigns::Ignored, mixed = signs == NormalSigns::Mixed;
    const __m256 all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    const __m256 open1 = sign_free || open ? all : zero;
    const AngleBins &angle_bins = sign_free ? kHalfAngleBins : kAngleBins;
    for (int k = 0; k < 5; ++k) {
        cl[k] = _mm256_set1_ps(angle_bins.c[1 + k]), sl[k] = _mm256_set1_ps(angle_bins.s[1 + k]);
        cu[k] = _mm256_set1_ps(angle_bins.c[6 + k]), su[k] = _mm256_set1_ps(angle_bins.s[6 + k]);
    }
    const __m256 lo = _mm256_set1_ps(-1.0f), range = _mm256_set1_ps(2.0f);
    const __m256 bins = _mm256_set1_ps(static_cast<float>(kBinsPerFeature));
    const __m256 top = _mm256_set1_ps(static_cast<float>(kBinsPerFeature) - 0.5f);
    const __m256i five = _mm256_set1_epi32(kBinsPerFeature / 2);
    const __m256i frame_bit = _mm256_set1_epi32(kLaneFrame), tie_bit = _mm256_set1_epi32(kLaneTie);
    const __m256 lo3 = sign_free ? zero : lo, range3 = sign_free ? one : range;

    for (std::size_t m = 0; m < batch.size; m += 8) {
        __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(&batch.x[m]), px);
        __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(&batch.y[m]), py);
        __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(&batch.z[m]), pz);
        const __m256 len2 = dot8(dx, dy, dz, dx, dy, dz);
        const __m256 inv = _mm256_div_ps(one, _mm256_sqrt_ps(len2));
        dx = _mm256_mul_ps(dx, inv), dy = _mm256_mul_ps(dy, inv), dz = _mm256_mul_ps(dz, inv);
        const __m256 n2x = _mm256_loadu_ps(&batch.nx[m]), n2y = _mm256_loadu_ps(&batch.ny[m]);
        const __m256 n2z = _mm256_loadu_ps(&batch.nz[m]);
        const __m256 c1 = dot8(n1x, n1y, n1z, dx, dy, dz), c2 = dot8(n2x, n2y, n2z, dx, dy, dz);
        const __m256 a1 = _mm256_andnot_ps(sign, c1), a2 = _mm256_andnot_ps(sign, c2);
        const __m256 swap = _mm256_cmp_ps(a1, a2, _CMP_LT_OS);
        const __m256 tie = _mm256_andnot_ps(swap, _mm256_cmp_ps(a2, a1, _CMP_NLT_US));
        const __m256 ux = sel8(swap, n2x, n1x), uy = sel8(swap, n2y, n1y), uz = sel8(swap, n2z, n1z);
        const __m256 bx = sel8(swap, n1x, n2x), by = sel8(swap, n1y, n2y), bz = sel8(swap, n1z, n2z);
        const __m256 flip = _mm256_and_ps(swap, sign);
        dx = _mm256_xor_ps(dx, flip), dy = _mm256_xor_ps(dy, flip), dz = _mm256_xor_ps(dz, flip);
        __m256 f3 = sel8(swap, _mm256_xor_ps(c2, sign), c1);
        __m256 vx = _mm256_sub_ps(_mm256_mul_ps(dy, uz), _mm256_mul_ps(dz, uy));
        __m256 vy = _mm256_sub_ps(_mm256_mul_ps(dz, ux), _mm256_mul_ps(dx, uz));
        __m256 vz = _mm256_sub_ps(_mm256_mul_ps(dx, uy), _mm256_mul_ps(dy, ux));
        const __m256 vlen2 = dot8(vx, vy, vz, vx, vy, vz);
        const __m256 vinv = _mm256_div_ps(one, _mm256_sqrt_ps(vlen2));
        vx = _mm256_mul_ps(vx, vinv), vy = _mm256_mul_ps(vy, vinv), vz = _mm256_mul_ps(vz, vinv);
        const __m256 wx = _mm256_sub_ps(_mm256_mul_ps(uy, vz), _mm256_mul_ps(uz, vy));
        const __m256 wy = _mm256_sub_ps(_mm256_mul_ps(uz, vx), _mm256_mul_ps(ux, vz));
        const __m256 wz = _mm256_sub_ps(_mm256_mul_ps(ux, vy), _mm256_mul_ps(uy, vx));
        __m256 ay = dot8(wx, wy, wz, bx, by, bz), ax = dot8(ux, uy, uz, bx, by, bz);
        __m256 f2 = dot8(vx, vy, vz, bx, by, bz);
        if (sign_free || mixed) {
            const __m256 open2 =
                sign_free ? all
                          : _mm256_castsi256_ps(_mm256_loadu_si256(reinterpret_cast<const __m256i *>(&batch.open[m])));
            const __m256 free_u = sel8(swap, open2, open1), free_b = sel8(swap, open1, open2);
            const __m256 turn_u = _mm256_and_ps(_mm256_and_ps(free_u, _mm256_cmp_ps(f3, zero, _CMP_LT_OS)), sign);
            f3 = _mm256_xor_ps(f3, turn_u), ax = _mm256_xor_ps(ax, turn_u), f2 = _mm256_xor_ps(f2, turn_u);
            const __m256 turn_b = _mm256_and_ps(_mm256_and_ps(free_b, _mm256_cmp_ps(ax, zero, _CMP_LT_OS)), sign);
            ax = _mm256_xor_ps(ax, turn_b), ay = _mm256_xor_ps(ay, turn_b), f2 = _mm256_xor_ps(f2, turn_b);
            const __m256 f3_zero = _mm256_and_ps(free_u, _mm256_cmp_ps(f3, zero, _CMP_EQ_OQ));
            const __m256 b_zero = _mm256_and_ps(free_b, _mm256_cmp_ps(ax, zero, _CMP_EQ_OQ));
            ay = sel8(_mm256_and_ps(f3_zero, free_b), _mm256_andnot_ps(sign, ay), ay);
            const __m256 both = _mm256_and_ps(f3_zero, b_zero);
            f2 = sel8(both, _mm256_andnot_ps(sign, f2), f2);
            const __m256 negative_a =
                _mm256_or_ps(_mm256_cmp_ps(ay, zero, _CMP_LT_OS),
                             _mm256_and_ps(_mm256_cmp_ps(ay, zero, _CMP_EQ_OQ), _mm256_cmp_ps(f2, zero, _CMP_LT_OS)));
            const __m256 turn_b0 = _mm256_and_ps(_mm256_andnot_ps(both, _mm256_and_ps(b_zero, negative_a)), sign);
            ay = _mm256_xor_ps(ay, turn_b0), f2 = _mm256_xor_ps(f2, turn_b0);
            const __m256 negative_b =
                _mm256_or_ps(_mm256_cmp_ps(ax, zero, _CMP_LT_OS),
                             _mm256_and_ps(_mm256_cmp_ps(ax, zero, _CMP_EQ_OQ), _mm256_cmp_ps(f2, zero, _CMP_LT_OS)));
            const __m256 turn_u0 = _mm256_and_ps(_mm256_andnot_ps(free_b, _mm256_and_ps(f3_zero, negative_b)), sign);
            ax = _mm256_xor_ps(ax, turn_u0), f2 = _mm256_xor_ps(f2, turn_u0);
        }

        const __m256 upper = _mm256_cmp_ps(ay, zero, _CMP_GE_OS);
        __m256i b0 = _mm256_and_si256(_mm256_castps_si256(upper), five);
        for (int k = 0; k < 5; ++k) {
            const __m256 ck = sel8(upper, cu[k], cl[k]), sk = sel8(upper, su[k], sl[k]);
            const __m256 ge =
                _mm256_cmp_ps(_mm256_sub_ps(_mm256_mul_ps(ck, ay), _mm256_mul_ps(sk, ax)), zero, _CMP_GE_OS);
            b0 = _mm256_sub_epi32(b0, _mm256_castps_si256(ge)); // true is -1
        }
        const __m256i at_origin = _mm256_castps_si256(
            _mm256_and_ps(_mm256_cmp_ps(ay, zero, _CMP_EQ_OQ), _mm256_cmp_ps(ax, zero, _CMP_EQ_OQ)));
        b0 = _mm256_or_si256(_mm256_and_si256(at_origin, five), _mm256_andnot_si256(at_origin, b0));
        const __m256i b1 = bin8(f2, lo, range, bins, top), b2 = bin8(f3, lo3, range3, bins, top);
        const __m256 has_len = _mm256_cmp_ps(len2, zero, _CMP_GT_OS);
        const __m256i frame = _mm256_castps_si256(_mm256_and_ps(has_len, _mm256_cmp_ps(vlen2, zero, _CMP_GT_OS)));
        const __m256i order_matters = _mm256_castps_si256(_mm256_and_ps(has_len, tie));
        __m256i c = _mm256_or_si256(b0, _mm256_or_si256(_mm256_slli_epi32(b1, 4), _mm256_slli_epi32(b2, 8)));
        c = _mm256_or_si256(
            c, _mm256_or_si256(_mm256_and_si256(frame, frame_bit), _mm256_and_si256(order_matters, tie_bit)));
        _mm256_storeu_si256(reinterpret_cast<__m256i *>(&batch.code[m]), c);
    }
}

} // namespace
#endif

#if KISSM_PAIR_FEATURES_SSE2
// Intrinsics because GCC does not vectorise the plain loop: under its default -ftrapping-math the selects
// become branches around comparisons and products that may trap, which it will not if-convert.
void batch_pair_codes(const Vec3f &p, const Vec3f &n, bool open, NormalSigns signs, PairBatch &batch) {
#  if KISSM_HAVE_AVX2_KERNELS
    if (use_avx2()) {
        batch_pair_codes_avx2(p, n, open, signs, batch);
        return;
    }
#  endif
    // Padding lanes (copies of p itself) only produce codes nobody reads; NaNs in them are harmless.
    for (std::size_t m = batch.size; m < ((batch.size + 3) & ~std::size_t(3)); ++m) {
        batch.x[m] = p.x(), batch.y[m] = p.y(), batch.z[m] = p.z();
        batch.nx[m] = n.x(), batch.ny[m] = n.y(), batch.nz[m] = n.z();
        batch.open[m] = 0;
    }
    const __m128 px = _mm_set1_ps(p.x()), py = _mm_set1_ps(p.y()), pz = _mm_set1_ps(p.z());
    const __m128 n1x = _mm_set1_ps(n.x()), n1y = _mm_set1_ps(n.y()), n1z = _mm_set1_ps(n.z());
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    const __m128 sign = _mm_set1_ps(-0.0f);
    // Sector boundaries of the angle bins: lanes with y >= 0 use k = 6..10, the others k = 1..5.
    __m128 cl[5], sl[5], cu[5], su[5];
    const bool sign_free = signs == NormalSigns::Ignored, mixed = signs == NormalSigns::Mixed;
    const __m128 all = _mm_castsi128_ps(_mm_set1_epi32(-1));
    const __m128 open1 = sign_free || open ? all : zero;
    const AngleBins &angle_bins = sign_free ? kHalfAngleBins : kAngleBins;
    for (int k = 0; k < 5; ++k) {
        cl[k] = _mm_set1_ps(angle_bins.c[1 + k]), sl[k] = _mm_set1_ps(angle_bins.s[1 + k]);
        cu[k] = _mm_set1_ps(angle_bins.c[6 + k]), su[k] = _mm_set1_ps(angle_bins.s[6 + k]);
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
    // bin_of(f3, 0, 1) for sign-free pairs: the same operations with lo = 0 and hi - lo = 1.
    const __m128 lo3 = sign_free ? zero : lo, range3 = sign_free ? one : range;
    auto bin_of = [&](__m128 value, __m128 from, __m128 width) {
        __m128 t = _mm_mul_ps(_mm_div_ps(_mm_sub_ps(value, from), width), bins);
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
        __m128 f3 = select(swap, _mm_xor_ps(c2, sign), c1);
        __m128 vx = _mm_sub_ps(_mm_mul_ps(dy, uz), _mm_mul_ps(dz, uy));
        __m128 vy = _mm_sub_ps(_mm_mul_ps(dz, ux), _mm_mul_ps(dx, uz));
        __m128 vz = _mm_sub_ps(_mm_mul_ps(dx, uy), _mm_mul_ps(dy, ux));
        const __m128 vlen2 = dot(vx, vy, vz, vx, vy, vz);
        const __m128 vinv = _mm_div_ps(one, _mm_sqrt_ps(vlen2));
        vx = _mm_mul_ps(vx, vinv), vy = _mm_mul_ps(vy, vinv), vz = _mm_mul_ps(vz, vinv);
        const __m128 wx = _mm_sub_ps(_mm_mul_ps(uy, vz), _mm_mul_ps(uz, vy));
        const __m128 wy = _mm_sub_ps(_mm_mul_ps(uz, vx), _mm_mul_ps(ux, vz));
        const __m128 wz = _mm_sub_ps(_mm_mul_ps(ux, vy), _mm_mul_ps(uy, vx));
        __m128 ay = dot(wx, wy, wz, bx, by, bz), ax = dot(ux, uy, uz, bx, by, bz);
        __m128 f2 = dot(vx, vy, vz, bx, by, bz);
        if (sign_free || mixed) { // the scalar code's turns, as sign flips where the comparisons hold
            const __m128 open2 =
                sign_free ? all : _mm_castsi128_ps(_mm_loadu_si128(reinterpret_cast<const __m128i *>(&batch.open[m])));
            const __m128 free_u = select(swap, open2, open1), free_b = select(swap, open1, open2);
            const __m128 turn_u = _mm_and_ps(_mm_and_ps(free_u, _mm_cmplt_ps(f3, zero)), sign);
            f3 = _mm_xor_ps(f3, turn_u), ax = _mm_xor_ps(ax, turn_u), f2 = _mm_xor_ps(f2, turn_u);
            const __m128 turn_b = _mm_and_ps(_mm_and_ps(free_b, _mm_cmplt_ps(ax, zero)), sign);
            ax = _mm_xor_ps(ax, turn_b), ay = _mm_xor_ps(ay, turn_b), f2 = _mm_xor_ps(f2, turn_b);
            const __m128 f3_zero = _mm_and_ps(free_u, _mm_cmpeq_ps(f3, zero));
            const __m128 b_zero = _mm_and_ps(free_b, _mm_cmpeq_ps(ax, zero));
            ay = select(_mm_and_ps(f3_zero, free_b), _mm_andnot_ps(sign, ay), ay);
            const __m128 both = _mm_and_ps(f3_zero, b_zero);
            f2 = select(both, _mm_andnot_ps(sign, f2), f2);
            const __m128 negative_a =
                _mm_or_ps(_mm_cmplt_ps(ay, zero), _mm_and_ps(_mm_cmpeq_ps(ay, zero), _mm_cmplt_ps(f2, zero)));
            const __m128 turn_b0 = _mm_and_ps(_mm_andnot_ps(both, _mm_and_ps(b_zero, negative_a)), sign);
            ay = _mm_xor_ps(ay, turn_b0), f2 = _mm_xor_ps(f2, turn_b0);
            // Only u free and f3 zero: settled on b, then f2 (exclusive with the turn above, which needs n_b free).
            const __m128 negative_b =
                _mm_or_ps(_mm_cmplt_ps(ax, zero), _mm_and_ps(_mm_cmpeq_ps(ax, zero), _mm_cmplt_ps(f2, zero)));
            const __m128 turn_u0 = _mm_and_ps(_mm_andnot_ps(free_b, _mm_and_ps(f3_zero, negative_b)), sign);
            ax = _mm_xor_ps(ax, turn_u0), f2 = _mm_xor_ps(f2, turn_u0);
        }

        const __m128 upper = _mm_cmpge_ps(ay, zero);
        __m128i b0 = _mm_and_si128(_mm_castps_si128(upper), five);
        for (int k = 0; k < 5; ++k) {
            const __m128 ck = select(upper, cu[k], cl[k]), sk = select(upper, su[k], sl[k]);
            const __m128 ge = _mm_cmpge_ps(_mm_sub_ps(_mm_mul_ps(ck, ay), _mm_mul_ps(sk, ax)), zero);
            b0 = _mm_sub_epi32(b0, _mm_castps_si128(ge)); // true is -1
        }
        const __m128i at_origin = _mm_castps_si128(_mm_and_ps(_mm_cmpeq_ps(ay, zero), _mm_cmpeq_ps(ax, zero)));
        b0 = _mm_or_si128(_mm_and_si128(at_origin, five), _mm_andnot_si128(at_origin, b0));
        const __m128i b1 = bin_of(f2, lo, range), b2 = bin_of(f3, lo3, range3);
        const __m128 has_len = _mm_cmpgt_ps(len2, zero);
        const __m128i frame = _mm_castps_si128(_mm_and_ps(has_len, _mm_cmpgt_ps(vlen2, zero)));
        const __m128i order_matters = _mm_castps_si128(_mm_and_ps(has_len, tie));
        __m128i c = _mm_or_si128(b0, _mm_or_si128(_mm_slli_epi32(b1, 4), _mm_slli_epi32(b2, 8)));
        c = _mm_or_si128(c, _mm_or_si128(_mm_and_si128(frame, frame_bit), _mm_and_si128(order_matters, tie_bit)));
        _mm_storeu_si128(reinterpret_cast<__m128i *>(&batch.code[m]), c);
    }
}
#else
void batch_pair_codes(const Vec3f &p, const Vec3f &n, bool open, NormalSigns signs, PairBatch &batch) {
    int bins[3];
    for (std::size_t m = 0; m < batch.size; ++m) {
        bool order_matters;
        const Vec3f q(batch.x[m], batch.y[m], batch.z[m]), nq(batch.nx[m], batch.ny[m], batch.nz[m]);
        const bool frame = pair_bins(p, n, open, q, nq, batch.open[m] != 0, signs, bins, order_matters);
        batch.code[m] = (frame ? pack_bins(bins) : 0) | (order_matters ? kLaneTie : 0);
    }
}
#endif

bool pair_feature_bins(const Vec3f &p1, const Vec3f &n1, const Vec3f &p2, const Vec3f &n2, NormalSigns signs,
                       int bins[3], bool open1, bool open2) {
    bool order_matters;
    return pair_bins(p1, n1, open1, p2, n2, open2, signs, bins, order_matters);
}

KISSM_DETAIL_END
