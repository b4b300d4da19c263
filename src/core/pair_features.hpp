// SPDX-License-Identifier: MIT
// Stage 2c, the pair-feature kernel: the three Darboux-frame angle features of one pair of oriented points
// (paper Eq. (A2), \label{eqn:angular_features}) and their histogram bins (Eq. (A3), \label{eqn:histogram}),
// one pair at a time or a row of neighbours four at a time (SSE2), bitwise alike. What fpfh.cpp shares with
// it: the bins' packed code and the batch of a row's pairs. fpfh.cpp sums the bins into SPFH and FPFH.
//
// Eq. (A2) as the paper has it: p_a is the point whose normal makes the smaller angle with the line, d the
// unit vector from p_a to p_b, u = n_a, v = d x u, w = u x v; f1 = atan2(w . n_b, u . n_b), f2 = v . n_b,
// f3 = u . d. Eq. (A3) bins f in [f_min, f_max] into H = 11 bins as floor(H (f - f_min) / (f_max + eps -
// f_min)) + 1; here bins are 0-based and the top value is clamped into the last bin instead of the eps, and
// f1 is binned by its sector in [-pi, pi] without computing atan2 (the sector tests are float cross products,
// so a value within rounding of a sector boundary may fall on the other side of it). A pair without a frame
// (coincident points, or u parallel to d) gives no bins; the paper does not discuss that case.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

constexpr int kBinsPerFeature = 11;

// Whether the features may depend on the signs of the normals. Oriented: Eq. (A2) as it stands, for normals
// turned toward a viewpoint. Ignored: each pair is first brought to one representative of its four sign
// choices (the frame's normal u turned so that f3 = u . d >= 0, then n_b so that u . n_b >= 0), so flipping
// either normal changes nothing and unoriented normals will do: f1 then lies in [-pi/2, pi/2] and f3 in
// [0, 1], each still binned into 11 bins over its range. What is lost is only what the signs carried (a convex
// edge and a concave one look alike); what is gained is features that do not depend on any viewpoint, so
// on no cloud's frame (docs/design/frames.md). Mixed: as Oriented, but a normal whose sign is open (Normals::open_sign)
// is turned to the representative of its two choices: u so that f3 >= 0, n_b so that u . n_b >= 0 (the bins
// stay those of the whole ranges, so that pairs of decided normals keep what their signs carry).
enum class NormalSigns { Oriented, Ignored, Mixed };

// Bins (0..10) of the three Darboux-frame angle features of a pair of oriented points; false when the pair
// has no defined frame (coincident points, or a normal parallel to the connecting line). The source point
// of the frame is the one whose normal makes the smaller angle with the connecting line, so the result
// does not depend on the order of the two points. open1 and open2: whether a normal's sign is open (Mixed only).
bool pair_feature_bins(const Vec3f &p1, const Vec3f &n1, const Vec3f &p2, const Vec3f &n2, NormalSigns signs,
                       int bins[3], bool open1 = false, bool open2 = false);

// A pair's bins for the second point of the pair, parked in the edge's slot until that point's owner
// collects them: 4 bits per feature, bit 12 set when the pair has a frame (0 = nothing to add).
constexpr std::uint16_t kCodeValid = 0x1000;

inline std::uint16_t pack_bins(const int bins[3]) {
    return static_cast<std::uint16_t>(kCodeValid | bins[0] | (bins[1] << 4) | (bins[2] << 8));
}

// The neighbours of one point that it pairs with, as structure of arrays, so that the pair features of a
// whole row are computed four (SSE2) or eight (AVX2) at a time. Each lane performs exactly the operations of
// pair_bins in the same order (Eigen sums a 3-vector's terms as x + (y + z); no FMA), and nothing is reduced across
// lanes, so the bins are bitwise those of the scalar code. The arrays are padded to a multiple of 8 lanes.
struct PairBatch {
    std::vector<float> x, y, z, nx, ny, nz;
    std::vector<std::uint32_t> index; // the neighbour's point index
    std::vector<std::uint64_t> slot;  // its position in the neighbour list
    std::vector<std::int32_t> code;   // bins and flags, see below
    std::vector<std::uint32_t> open;  // NormalSigns::Mixed: all ones where the neighbour's sign is open, else 0
    std::size_t size = 0;

    void reserve(std::size_t n) {
        n = (n + 7) & ~std::size_t(7);
        if (x.size() >= n) return;
        for (auto *v : {&x, &y, &z, &nx, &ny, &nz}) v->resize(n);
        index.resize(n), slot.resize(n), code.resize(n), open.resize(n);
    }
};

// Code of a lane: bins in bits 0-3, 4-7, 8-11; kLaneFrame when the pair has a frame; kLaneTie when the
// other order of the points could give other bins (equal angles of the normals with the line).
constexpr std::int32_t kLaneFrame = kCodeValid, kLaneTie = kCodeValid << 1;

// Fills batch.code[0, batch.size) with the codes of the pairs (p, n) - (batch point m, its normal): exactly
// the bins pair_feature_bins gives for that order, kLaneFrame when the pair has a frame, kLaneTie when the
// other order must be evaluated separately. Uses (and may overwrite) the padding lanes up to a multiple of 8.
// Under NormalSigns::Mixed, open says whether n's sign is open and batch.open the neighbours'.
void batch_pair_codes(const Vec3f &p, const Vec3f &n, bool open, NormalSigns signs, PairBatch &batch);

KISSM_DETAIL_END
