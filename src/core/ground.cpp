// SPDX-License-Identifier: MIT
#include "ground.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "normals.hpp"

KISSM_DETAIL_BEGIN

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr std::uint32_t kNoBin = std::numeric_limits<std::uint32_t>::max();

// The zone model: four zones between min_range and max_range whose outer edges sit at 1/8, 1/4 and 1/2 of
// the span, with (rings, sectors) per zone. Near the sensor points are dense and the ground is seen at
// steep angles, so small bins follow its shape; far away they are sparse and a bin needs more area to hold
// enough of them. These are Patchwork++'s published KITTI numbers (rings 2, 4, 4, 4; sectors 16, 32, 54, 32):
// matching its partition is what makes the two comparable.
struct Zone {
    double r0, r1;
    int rings, sectors;
    std::uint32_t first_bin;
};
constexpr int kZones = 4;
constexpr std::array<int, kZones> kRings{2, 4, 4, 4};
constexpr std::array<int, kZones> kSectors{16, 32, 54, 32};
// Zones 0 and 1 are "near": there the ground height below the sensor is known well enough to reject raised
// flat surfaces (the elevation test) and to estimate that height in the first place.
constexpr int kNearZones = 2;

// Per bin: at least this many voxels to fit a plane (a thinned cloud has far fewer points per bin than the
// raw scan, so fewer than Patchwork's 10 raw points), the seed height from the mean of the lowest
// kLowestPoints, and kIterations rounds of fit and re-assignment. Chosen against Patchwork++ on the LiDAR
// scans of ../shared/data at 0.3 and 0.5 m voxels.
constexpr std::size_t kMinPoints = 6;
constexpr std::size_t kLowestPoints = 15;
constexpr int kIterations = 3;
// Under-ground returns are sparse: at most one point in kNoiseShare of a bin.
constexpr std::size_t kNoiseShare = 5;
// "Very flat": the variance off the plane of a bin's ground (m^2), about 2 cm of noise.
constexpr double kFlatVariance = 0.0005;

// The frame of the zone model: e1, e2 span the plane perpendicular to up. e1 is the coordinate axis least
// aligned with up (the first on a tie), projected: a function of up alone that turns with a permutation of the
// axes, so a scene and its up permuted together get the same bins, bit for bit (each coordinate then comes
// from one product with 1 and sums of exact zeros).
struct Frame {
    Eigen::Vector3d e1, e2, up, sensor;
    bool ok = false;

    explicit Frame(const GroundParams &p) {
        sensor = p.sensor;
        const double len = p.up.norm();
        if (!(len > 0.0) || !std::isfinite(len) || !sensor.allFinite()) return;
        up = p.up / len;
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (std::fabs(up[a]) < std::fabs(up[axis])) axis = a;
        Eigen::Vector3d a = Eigen::Vector3d::Zero();
        a[axis] = 1.0;
        e1 = (a - a.dot(up) * up).normalized();
        e2 = up.cross(e1);
        ok = true;
    }
    // (x, y, height) relative to the sensor.
    Eigen::Vector3d local(const Vec3f &p) const {
        const Eigen::Vector3d d = p.cast<double>() - sensor;
        return Eigen::Vector3d(d.dot(e1), d.dot(e2), d.dot(up));
    }
};

bool params_usable(const GroundParams &p) {
    return std::isfinite(p.sensor_height) && p.sensor_height >= 0.0 && std::isfinite(p.min_range) &&
           std::isfinite(p.max_range) && p.min_range >= 0.0 && p.max_range > p.min_range &&
           std::isfinite(p.plane_distance) && std::isfinite(p.seed_distance) && std::isfinite(p.min_uprightness) &&
           std::isfinite(p.voxel_size);
}

std::array<Zone, kZones> make_zones(const GroundParams &p) {
    const double lo = p.min_range, hi = p.max_range, span = hi - lo;
    const std::array<double, kZones + 1> edge{lo, lo + span / 8.0, lo + span / 4.0, lo + span / 2.0, hi};
    std::array<Zone, kZones> zones{};
    std::uint32_t bin = 0;
    for (int z = 0; z < kZones; ++z) {
        zones[z] = Zone{edge[z], edge[z + 1], kRings[z], kSectors[z], bin};
        bin += static_cast<std::uint32_t>(kRings[z] * kSectors[z]);
    }
    return zones;
}

// The bin of a point at (x, y) from the sensor, or kNoBin outside [min_range, max_range).
std::uint32_t bin_of(const std::array<Zone, kZones> &zones, double x, double y) {
    const double r = std::sqrt(x * x + y * y);
    if (!std::isfinite(r) || r < zones[0].r0 || r >= zones[kZones - 1].r1) return kNoBin;
    int z = 0;
    while (z + 1 < kZones && r >= zones[z].r1) ++z;
    const Zone &zone = zones[z];
    const int ring = std::min(zone.rings - 1, static_cast<int>((r - zone.r0) / (zone.r1 - zone.r0) * zone.rings));
    double theta = std::atan2(y, x);
    if (theta < 0.0) theta += kTwoPi;
    const int sector = std::min(zone.sectors - 1, static_cast<int>(theta / kTwoPi * zone.sectors));
    return zone.first_bin + static_cast<std::uint32_t>(ring * zone.sectors + sector);
}

// The lowest dense layer of heights among the points near the sensor: a histogram of 10 cm bins, the first
// bin (from below) that reaches half the fullest one, then up to the top of that peak, then the mean height
// of the points around it. The lowest layer rather than the fullest: on a scan the near ground is the
// largest horizontal surface, but a low ceiling or a large flat roof must not win; sparse returns from under
// the ground (reflections) stay below half the peak.
double ground_height_from(const std::vector<double> &heights) {
    constexpr double kWidth = 0.1, kReach = 30.0; // heights beyond +-30 m of the sensor are not its ground
    constexpr int kBins = static_cast<int>(2 * kReach / kWidth);
    constexpr std::size_t kMinNear = 30;
    if (heights.size() < kMinNear) return std::numeric_limits<double>::quiet_NaN();
    std::vector<std::uint32_t> hist(kBins, 0);
    for (double h : heights) {
        const double f = (h + kReach) / kWidth;
        if (f >= 0.0 && f < kBins) ++hist[static_cast<std::size_t>(f)];
    }
    // Three-bin sums: a layer split across a bin edge still counts as one.
    std::vector<std::uint32_t> smooth(kBins, 0);
    for (int b = 0; b < kBins; ++b)
        for (int d = -1; d <= 1; ++d)
            if (b + d >= 0 && b + d < kBins) smooth[b] += hist[b + d];
    const std::uint32_t top = *std::max_element(smooth.begin(), smooth.end());
    if (top < kMinNear / 2) return std::numeric_limits<double>::quiet_NaN();
    int peak = 0;
    while (2 * smooth[peak] < top) ++peak;
    while (peak + 1 < kBins && smooth[peak + 1] > smooth[peak]) ++peak;
    const double centre = -kReach + (peak + 0.5) * kWidth;
    double sum = 0.0;
    std::size_t n = 0;
    for (double h : heights)
        if (std::fabs(h - centre) <= 1.5 * kWidth) sum += h, ++n;
    return n > 0 ? sum / static_cast<double>(n) : centre;
}

struct BinFit {
    bool fitted = false;
    double uprightness = 0.0; // normal . up
    double elevation = 0.0;   // mean height of the fitted points above the sensor
    double flatness = 0.0;    // smallest eigenvalue of their covariance (m^2)
    double spread = 0.0;      // middle eigenvalue (m^2): small when the points lie along a line
};

struct ChunkFits {
    std::vector<BinFit> fits;           // one per bin of the chunk
    std::vector<std::uint8_t> near_fit; // one per point of the chunk's bins, in bin order: within the plane band
};

// Mean and covariance of a subset of q; returns false under 3 points.
bool plane_of(const std::vector<Eigen::Vector3d> &q, const std::vector<std::uint32_t> &subset, Eigen::Vector3d &mean,
              Eigen::Vector3d &normal, double &smallest, double &middle) {
    if (subset.size() < 3) return false;
    mean.setZero();
    for (std::uint32_t i : subset) mean += q[i];
    mean /= static_cast<double>(subset.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::uint32_t i : subset) {
        const Eigen::Vector3d d = q[i] - mean;
        cov.noalias() += d * d.transpose();
    }
    cov /= static_cast<double>(subset.size());
    Eigen::Vector3d lambda;
    symmetric_eigen3(cov, lambda, normal);
    const double len = normal.norm();
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    normal /= len;
    if (normal.z() < 0.0) normal = -normal; // local z is up: the plane's upper side
    smallest = std::max(0.0, lambda[2]);
    middle = std::max(0.0, lambda[1]);
    return true;
}

// One bin: sort by height, seeds from the lowest points, kIterations of plane fit and re-assignment.
// q: the bin's points in the local frame, in the order of the bin; near_fit gets one flag per point.
BinFit fit_bin(std::vector<Eigen::Vector3d> &q, double guard_height, const GroundParams &params,
               std::uint8_t *near_fit) {
    BinFit fit;
    const std::size_t n = q.size();
    std::fill(near_fit, near_fit + n, std::uint8_t(0));
    if (n < kMinPoints) return fit;
    // Ties by position in the bin, which is ascending point index: a total order, so the same on every run.
    const auto lower = [&q](std::uint32_t a, std::uint32_t b) {
        return q[a].z() < q[b].z() || (q[a].z() == q[b].z() && a < b);
    };
    // Returns from under the ground (reflections off wet roads or glass) would drag the seeds down: points
    // more than the guard below the expected ground are left out of them (they still end up ground, under
    // the plane). Only when they are few: many points there are a real surface, a dip or a ramp down that
    // the global ground height does not know.
    std::size_t below_guard = 0;
    for (std::size_t i = 0; i < n; ++i) below_guard += q[i].z() < guard_height;
    const bool guarded = below_guard > 0 && below_guard * kNoiseShare <= n;
    std::vector<std::uint32_t> candidates;
    candidates.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (!guarded || !(q[i].z() < guard_height)) candidates.push_back(static_cast<std::uint32_t>(i));
    // The seeds' height from the lowest candidates, summed from the lowest up; then every candidate below it plus
    // the seed distance, from the lowest up. Only those are sorted: a whole bin's sort by height was a twentieth
    // of kissm_ground_mask (docs/design/performance.md, "Ground").
    const std::size_t lowest = std::min(kLowestPoints, candidates.size());
    std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(lowest), candidates.end(),
                      lower);
    double low = 0.0;
    for (std::size_t k = 0; k < lowest; ++k) low += q[candidates[k]].z();
    low /= static_cast<double>(lowest);
    std::vector<std::uint32_t> ground;
    for (std::uint32_t i : candidates)
        if (q[i].z() < low + params.seed_distance) ground.push_back(i);
    std::sort(ground.begin(), ground.end(), lower);
    Eigen::Vector3d mean, normal;
    double smallest = 0.0, middle = 0.0;
    for (int it = 0; it < kIterations; ++it) {
        if (!plane_of(q, ground, mean, normal, smallest, middle)) return BinFit();
        ground.clear();
        const double offset = normal.dot(mean) + params.plane_distance;
        for (std::size_t i = 0; i < n; ++i)
            if (normal.dot(q[i]) < offset) ground.push_back(static_cast<std::uint32_t>(i));
    }
    for (std::uint32_t i : ground) near_fit[i] = 1;
    fit.fitted = true;
    fit.uprightness = normal.z();
    fit.elevation = mean.z();
    fit.flatness = smallest;
    fit.spread = middle;
    return fit;
}

} // namespace

double estimate_ground_height(const std::vector<Vec3f> &points, const GroundParams &params) {
    const Frame frame(params);
    if (!frame.ok || !params_usable(params)) return std::numeric_limits<double>::quiet_NaN();
    const std::array<Zone, kZones> zones = make_zones(params);
    const double near = zones[kNearZones - 1].r1;
    std::vector<double> heights;
    for (const Vec3f &p : points) {
        const Eigen::Vector3d q = frame.local(p);
        const double r2 = q.x() * q.x() + q.y() * q.y();
        if (r2 >= params.min_range * params.min_range && r2 < near * near && std::isfinite(q.z()))
            heights.push_back(q.z());
    }
    return ground_height_from(heights);
}

std::vector<std::uint8_t> segment_ground(const std::vector<Vec3f> &points, const GroundParams &params,
                                         RunContext &ctx) {
    std::vector<std::uint8_t> flags(points.size(), 0);
    const Frame frame(params);
    if (points.empty() || !frame.ok || !params_usable(params)) return flags;
    const std::array<Zone, kZones> zones = make_zones(params);
    const std::size_t num_bins = zones[kZones - 1].first_bin + kRings[kZones - 1] * kSectors[kZones - 1];

    // Bins of the points, then the points grouped by bin (a counting sort: ascending index within a bin).
    constexpr std::size_t kPointChunk = 8192;
    std::vector<std::uint32_t> bin(points.size());
    ctx.parallel_for(points.size(), kPointChunk, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const Eigen::Vector3d q = frame.local(points[i]);
            bin[i] = std::isfinite(q.z()) ? bin_of(zones, q.x(), q.y()) : kNoBin;
        }
    });
    std::vector<std::size_t> start(num_bins + 1, 0);
    for (std::uint32_t b : bin)
        if (b != kNoBin) ++start[b + 1];
    for (std::size_t b = 0; b < num_bins; ++b) start[b + 1] += start[b];
    std::vector<std::uint32_t> order(start[num_bins]);
    {
        std::vector<std::size_t> next(start.begin(), start.end() - 1);
        for (std::size_t i = 0; i < points.size(); ++i)
            if (bin[i] != kNoBin) order[next[bin[i]]++] = static_cast<std::uint32_t>(i);
    }

    // The expected ground: given, or estimated from the near points.
    double ground_height = -params.sensor_height;
    if (!(params.sensor_height > 0.0)) {
        std::vector<double> heights;
        for (std::size_t k = 0; k < start[zones[kNearZones].first_bin]; ++k)
            heights.push_back(frame.local(points[order[k]]).z());
        ground_height = ground_height_from(heights);
    }
    const bool known = std::isfinite(ground_height);
    const double depth = known ? -ground_height : 0.0;
    const double guard = known ? ground_height - std::max(0.25, 0.2 * depth) : -std::numeric_limits<double>::infinity();

    const double min_spread = std::pow(0.25 * (params.voxel_size > 0.0 ? params.voxel_size : 0.0), 2);
    constexpr std::size_t kBinChunk = 16;
    std::vector<ChunkFits> parts = ctx.map_chunks(num_bins, kBinChunk, [&](std::size_t b, std::size_t e) {
        ChunkFits out;
        out.fits.resize(e - b);
        out.near_fit.resize(start[e] - start[b]);
        std::vector<Eigen::Vector3d> q;
        for (std::size_t k = b; k < e; ++k) {
            q.clear();
            for (std::size_t s = start[k]; s < start[k + 1]; ++s) q.push_back(frame.local(points[order[s]]));
            const bool near = k < zones[1].first_bin; // the guard where under-ground returns occur: close by
            out.fits[k - b] = fit_bin(q, near ? guard : -std::numeric_limits<double>::infinity(), params,
                                      out.near_fit.data() + (start[k] - start[b]));
        }
        return out;
    });

    // Decisions per bin, then the flags of its points.
    for (std::size_t c = 0; c < parts.size(); ++c) {
        const std::size_t b0 = c * kBinChunk;
        for (std::size_t k = 0; k < parts[c].fits.size(); ++k) {
            const BinFit &fit = parts[c].fits[k];
            const std::size_t b = b0 + k;
            if (!fit.fitted || fit.uprightness < params.min_uprightness) continue;
            // Points along a line (the foot of a wall, a kerb seen edge-on) fit any plane through it, an
            // upright one too: a plane needs a spread of at least a quarter voxel across as well as along.
            if (fit.spread < min_spread) continue;
            int z = 0;
            while (z + 1 < kZones && b >= zones[z + 1].first_bin) ++z;
            if (known && z < kNearZones) {
                // Elevation: a surface well above the expected ground near the sensor is a roof or a table,
                // unless it is very flat (a raised road, the ground rising on a slope) and not higher than a
                // slope of 0.3 would take it (a ceiling or a canopy above the sensor is flat too). Both
                // margins grow with range.
                const int ring = static_cast<int>((b - zones[z].first_bin) / zones[z].sectors);
                const double r = zones[z].r0 + (ring + 0.5) * (zones[z].r1 - zones[z].r0) / zones[z].rings;
                const double above = fit.elevation - ground_height;
                if (above > 0.5 + 0.05 * r && (fit.flatness > kFlatVariance || above > 0.5 + 0.3 * r)) continue;
            }
            for (std::size_t s = start[b]; s < start[b + 1]; ++s)
                if (parts[c].near_fit[s - start[b0]]) flags[order[s]] = 1;
        }
    }
    return flags;
}

KISSM_DETAIL_END
