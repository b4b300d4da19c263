// SPDX-License-Identifier: MIT
#include "voxel_suggest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "failure.hpp"
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

// Occupied voxels of side v, the grid anchored at the minimum (as voxelize() anchors it).
std::uint64_t occupied(const Finite &f, double v) {
    const double inv = 1.0 / v;
    std::uint64_t cells[3];
    for (int a = 0; a < 3; ++a) cells[a] = static_cast<std::uint64_t>(f.sides[a] * inv) + 1; // v >= extent / 2^20
    const auto key = [&](const Vec3d &p) {
        std::uint64_t c[3];
        for (int a = 0; a < 3; ++a) c[a] = std::min(static_cast<std::uint64_t>(p[a] * inv), cells[a] - 1);
        return (c[0] * cells[1] + c[1]) * cells[2] + c[2];
    };
    std::uint64_t count = 0;
    if (cells[0] * cells[1] <= kBitmapCells / cells[2]) {
        std::vector<std::uint64_t> bits(static_cast<std::size_t>((cells[0] * cells[1] * cells[2] + 63) / 64), 0);
        for (const Vec3d &p : f.points) {
            const std::uint64_t k = key(p), bit = std::uint64_t(1) << (k % 64);
            std::uint64_t &word = bits[static_cast<std::size_t>(k / 64)];
            count += (word & bit) == 0;
            word |= bit;
        }
        return count;
    }
    std::vector<KeyIndex> records(f.points.size());
    for (std::size_t i = 0; i < f.points.size(); ++i) records[i] = KeyIndex{key(f.points[i]), 0};
    radix_sort_by_key(records);
    for (std::size_t i = 0; i < records.size(); ++i) count += i == 0 || records[i].key != records[i - 1].key;
    return count;
}

// The lowest rung whose voxel is at least extent / kMinCellsPerExtent.
int lowest_rung(double extent) {
    const double floor_voxel = extent / kMinCellsPerExtent;
    int k = static_cast<int>(std::floor(std::log2(floor_voxel) * kSuggestRungsPerOctave)) - 1;
    while (rung(k) < floor_voxel) ++k;
    return k;
}

// The cloud's own rung: down from a voxel twice the extent (one occupied voxel) an octave at a time while the
// grid holds at most the target count, then bisection within the octave that crossed it. Coarse grids first:
// they are the cheap ones to count.
int cloud_rung(const Finite &f) {
    const std::uint64_t target = std::min<std::uint64_t>(kSuggestTargetVoxels, f.points.size() / 4);
    const int floor_rung = lowest_rung(f.extent());
    int hi = floor_rung; // occupied(hi) <= target
    while (rung(hi) < 2.0 * f.extent()) ++hi;
    int lo = hi; // occupied(lo) > target, or lo == floor_rung
    do {
        lo = std::max(floor_rung, lo - kSuggestRungsPerOctave);
        if (occupied(f, rung(lo)) > target) break;
        hi = lo;
    } while (lo > floor_rung);
    if (hi == lo) return lo; // the floor itself holds at most the target
    while (hi - lo > 1) {
        const int mid = lo + (hi - lo) / 2;
        (occupied(f, rung(mid)) > target ? lo : hi) = mid;
    }
    return hi;
}

} // namespace

double suggest_voxel_size(const std::vector<PointsView> &clouds, const std::vector<const char *> &names) {
    int finest = 0, floor_rung = 0;
    for (std::size_t c = 0; c < clouds.size(); ++c) {
        const Finite f = finite_points(clouds[c], names[c]);
        const int own = cloud_rung(f), lowest = lowest_rung(f.extent());
        finest = c == 0 ? own : std::min(finest, own);
        floor_rung = c == 0 ? lowest : std::max(floor_rung, lowest);
    }
    return rung(std::max(finest, floor_rung));
}

KISSM_DETAIL_END
