// SPDX-License-Identifier: MIT
#include "voxel_suggest.hpp"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include <Eigen/Eigenvalues>

#include "failure.hpp"
#include "lowest_bit.hpp"
#include "radix_sort.hpp"
#include "voxelize.hpp"

KISSM_DETAIL_BEGIN

namespace {

// 2^(j/8), j = 0..7, written out so that the ladder does not depend on the C library's exp2.
constexpr double kRungs[kSuggestRungsPerOctave] = {1.0,
                                                   1.0905077326652577,
                                                   1.189207115002721,
                                                   1.2968395546510096,
                                                   1.4142135623730951,
                                                   1.5422108254079407,
                                                   1.681792830507429,
                                                   1.8340080864093424};

int floor_div(int a, int b) { return a / b - (a % b != 0 && (a < 0) != (b < 0)); }

double rung(int k) {
    const int octave = floor_div(k, kSuggestRungsPerOctave);
    return std::ldexp(kRungs[k - octave * kSuggestRungsPerOctave], octave);
}

// The smallest voxel the grid may be asked for: twice the per-axis limit's, so that a suggestion never
// comes near the range error of voxelize().
constexpr double kMinCellsPerExtent = static_cast<double>(kMaxVoxelsPerAxis / 2);

// One cloud's finite points, relative to their bounding box's minimum, and that box's sides.
struct Finite {
    std::vector<Vec3d> points;
    Vec3d sides = Vec3d::Zero();
    double extent() const { return sides.maxCoeff(); }
};

Finite finite_points(const PointsView &view, const char *name) {
    InputCloud reader;
    reader.view = view;
    Finite f;
    f.points.reserve(static_cast<std::size_t>(view.count));
    Vec3d lo = Vec3d::Constant(HUGE_VAL), hi = Vec3d::Constant(-HUGE_VAL);
    reader.for_each_point(0, static_cast<std::size_t>(view.count), [&](std::size_t, const Vec3d &p) {
        if (!InputCloud::finite(p)) return;
        f.points.push_back(p);
        lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    });
    if (f.points.empty())
        fail(ErrorKind::EmptyInput, std::string(name) + " has no finite points (" + std::to_string(view.count) +
                                        " given); no voxel size can be suggested");
    if (f.points.size() < 4)
        fail(ErrorKind::TooFewPoints, std::string(name) + " has " + std::to_string(f.points.size()) +
                                          " finite points; at least 4 are needed to suggest a voxel size");
    for (Vec3d &p : f.points) p -= lo;
    f.sides = hi - lo;
    if (!(f.extent() > 0.0))
        fail(ErrorKind::TooFewPoints,
             std::string(name) + "'s finite points all coincide; no voxel size can be suggested from them");
    // Spans beyond double's range, or so small that the grid's finest voxel is not a normal number, have no
    // ladder of voxels to search.
    if (!std::isfinite(f.extent()) || !(f.extent() / kMinCellsPerExtent >= std::numeric_limits<double>::min())) {
        std::ostringstream msg;
        msg.precision(6);
        msg << name << "'s finite points span " << f.extent()
            << ", beyond the range a voxel grid can cover; no voxel size can be suggested";
        fail(ErrorKind::VoxelRange, msg.str());
    }
    return f;
}

// Grids of at most this many cells are counted in a bitmap (one pass, no sort); larger ones by sorting keys.
constexpr std::uint64_t kBitmapCells = std::uint64_t(1) << 26;

// What the occupied voxels of one grid add up to: their count and, when asked, their integer cell coordinates'
// sums and products (each voxel once, so the sums do not depend on the points' order; cells < 2^21 per axis
// and at most a few thousand voxels where they are asked for keep them within 64 bits).
struct Occupancy {
    std::uint64_t count = 0;
    std::uint64_t sum[3] = {}, product[6] = {}; // product: xx, xy, xz, yy, yz, zz

    void add(const std::uint64_t c[3]) {
        ++count;
        for (int a = 0, k = 0; a < 3; ++a) {
            sum[a] += c[a];
            for (int b = a; b < 3; ++b) product[k++] += c[a] * c[b];
        }
    }
};

// Occupied voxels of side v, the grid anchored at the minimum (as voxelize() anchors it); with `moments`, also
// their coordinates' sums.
Occupancy occupancy(const Finite &f, double v, bool moments) {
    const double inv = 1.0 / v;
    std::uint64_t cells[3];
    for (int a = 0; a < 3; ++a) cells[a] = static_cast<std::uint64_t>(f.sides[a] * inv) + 1; // v >= extent / 2^20
    const auto key = [&](const Vec3d &p) {
        // Through a signed conversion (one instruction; an unsigned one tests for 2^63 first): p[a] * inv is at
        // least 0 and below 2^21 here.
        std::uint64_t c[3];
        for (int a = 0; a < 3; ++a)
            c[a] = std::min(static_cast<std::uint64_t>(static_cast<std::int64_t>(p[a] * inv)), cells[a] - 1);
        return (c[0] * cells[1] + c[1]) * cells[2] + c[2];
    };
    Occupancy out;
    const auto add = [&](std::uint64_t k) {
        if (!moments) {
            ++out.count;
            return;
        }
        const std::uint64_t c[3] = {k / (cells[1] * cells[2]), k / cells[2] % cells[1], k % cells[2]};
        out.add(c);
    };
    if (cells[0] * cells[1] <= kBitmapCells / cells[2]) {
        // Set the bits, then read them: no count to carry from point to point, and a point in the voxel of the
        // one before (the common case in scan order) touches no memory (docs/design/voxel_auto.md, "Cost").
        std::vector<std::uint64_t> bits(static_cast<std::size_t>((cells[0] * cells[1] * cells[2] + 63) / 64), 0);
        std::uint64_t last = ~std::uint64_t(0);
        for (const Vec3d &p : f.points) {
            const std::uint64_t k = key(p);
            if (k == last) continue;
            last = k;
            bits[static_cast<std::size_t>(k / 64)] |= std::uint64_t(1) << (k % 64);
        }
        for (std::size_t w = 0; w < bits.size(); ++w) {
            if (!moments) {
                out.count += std::bitset<64>(bits[w]).count();
                continue;
            }
            for (std::uint64_t word = bits[w]; word != 0; word &= word - 1) add(w * 64 + lowest_bit(word));
        }
        return out;
    }
    std::vector<KeyIndex> records(f.points.size());
    for (std::size_t i = 0; i < f.points.size(); ++i) records[i] = KeyIndex{key(f.points[i]), 0};
    radix_sort_by_key(records);
    for (std::size_t i = 0; i < records.size(); ++i)
        if (i == 0 || records[i].key != records[i - 1].key) add(records[i].key);
    return out;
}

std::uint64_t occupied(const Finite &f, double v) { return occupancy(f, v, false).count; }

// Occupied voxels per unit of sigma_1 * sigma_2, the two largest principal spreads of their cells (in cells):
// how densely the cloud covers the area it spans. Double arithmetic on exact integer sums: the same bits for
// any point order. A cloud whose cells lie on a line has no such area (0: not compact).
double coverage(const Finite &f, double v) {
    const Occupancy o = occupancy(f, v, true);
    const double n = static_cast<double>(o.count);
    double mean[3];
    for (int a = 0; a < 3; ++a) mean[a] = static_cast<double>(o.sum[a]) / n;
    Eigen::Matrix3d cov;
    for (int a = 0, k = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b, ++k)
            cov(a, b) = cov(b, a) = static_cast<double>(o.product[k]) / n - mean[a] * mean[b];
    const Eigen::Vector3d l = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov, Eigen::EigenvaluesOnly).eigenvalues();
    const double area = l[2] * l[1];
    return area > 0.0 ? n / std::sqrt(area) : 0.0;
}

// The lowest rung whose voxel is at least extent / kMinCellsPerExtent.
int lowest_rung(double extent) {
    const double floor_voxel = extent / kMinCellsPerExtent;
    int k = static_cast<int>(std::floor(std::log2(floor_voxel) * kSuggestRungsPerOctave)) - 1;
    while (rung(k) < floor_voxel) ++k;
    return k;
}

// The lowest rung at least twice the extent: its grid holds one occupied voxel.
int top_rung(double extent) {
    int k = lowest_rung(extent);
    while (rung(k) < 2.0 * extent) ++k;
    return k;
}

// The smallest rung whose grid holds at most the target count, as found by walking down from a voxel twice the
// extent (one occupied voxel) an octave at a time while the grid holds at most the target, then bisecting the
// octave that crossed it. Along that walk each grid's cells are unions of the next finer one's (the rungs an
// octave apart scale the grid by exactly 2), so the count never falls going down: the octave where it crosses the
// target is found from any starting rung with the same answer. The walk starts at `guess` (rounded to the walk's
// octaves): a pass over the points per grid counted, so starting near the answer saves most of them.
int count_rung(const Finite &f, std::uint64_t target_voxels, int guess) {
    const std::uint64_t target = std::min<std::uint64_t>(target_voxels, f.points.size() / 4);
    const int floor_rung = lowest_rung(f.extent());
    const int top = top_rung(f.extent()); // one occupied voxel: within any target
    const auto within = [&](int j) { return occupied(f, rung(top - j * kSuggestRungsPerOctave)) <= target; };
    // The walk's octaves top - 8 j, j = 1..last, lie above the floor; below them the walk ends at the floor.
    const int last = (top - floor_rung - 1) / kSuggestRungsPerOctave;
    int ok = 0, over = last + 1; // the deepest octave known within the target, the shallowest known over it
    if (last >= 1) {
        const int start =
            std::min(last, std::max(1, (top - guess + kSuggestRungsPerOctave / 2) / kSuggestRungsPerOctave));
        if (within(start)) {
            for (ok = start; ok + 1 <= last; ++ok)
                if (!within(ok + 1)) {
                    over = ok + 1;
                    break;
                }
        } else {
            for (over = start; over - 1 > 0 && !within(over - 1);) --over;
            ok = over - 1;
        }
    }
    int hi = top - ok * kSuggestRungsPerOctave, lo; // occupied(hi) <= target < occupied(lo)
    if (over <= last) {
        lo = top - over * kSuggestRungsPerOctave;
    } else {
        lo = floor_rung;
        if (lo == hi || occupied(f, rung(lo)) <= target) return lo; // the floor itself holds at most the target
    }
    while (hi - lo > 1) {
        const int mid = lo + (hi - lo) / 2;
        (occupied(f, rung(mid)) > target ? lo : hi) = mid;
    }
    return hi;
}

// The cloud's own rung: the count rule's for kSuggestTargetVoxels, or for kSuggestCompactVoxels when the cloud
// is compact at that rung. The first walk starts 6 octaves below the top (where a surface of 3,000 voxels lies), the
// compact one half an octave above the first's answer (a surface's count halves over about 4 rungs).
int cloud_rung(const Finite &f) {
    const int top = top_rung(f.extent());
    const int wide = count_rung(f, kSuggestTargetVoxels, top - 6 * kSuggestRungsPerOctave);
    if (coverage(f, rung(wide)) < kCompactCoverage) return wide;
    return count_rung(f, kSuggestCompactVoxels, wide + kSuggestRungsPerOctave / 2);
}

} // namespace

double suggest_voxel_size(const std::vector<PointsView> &clouds, const std::vector<const char *> &names) {
    std::vector<int> own(clouds.size());
    int floor_rung = 0;
    for (std::size_t c = 0; c < clouds.size(); ++c) {
        const Finite f = finite_points(clouds[c], names[c]);
        own[c] = cloud_rung(f);
        const int lowest = lowest_rung(f.extent());
        floor_rung = c == 0 ? lowest : std::max(floor_rung, lowest);
    }
    // The lower median: (n - 1) / 2 in ascending order; the smaller of a pair.
    const auto median = own.begin() + static_cast<std::ptrdiff_t>((own.size() - 1) / 2);
    std::nth_element(own.begin(), median, own.end());
    return rung(std::max(*median, floor_rung));
}

KISSM_DETAIL_END
