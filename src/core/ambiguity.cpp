// SPDX-License-Identifier: MIT
#include "ambiguity.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <utility>

KISSM_DETAIL_BEGIN

namespace {

// Competitors per rotation: the densest translation cells. Six under the winner's rotation reach a period's
// neighbours on both sides along two directions; four under a second rotation.
constexpr std::size_t kWinnerRotationPeaks = 6;
constexpr std::size_t kSecondRotationPeaks = 4;
constexpr std::size_t kHalfTurnPeaks = 2;
// Below this share of the winner's support within twice the noise bound, a candidate is reported by that share
// and not polished.
constexpr double kWorthPolishing = 0.25;
// The dense support reads at most this many source voxels (evenly strided).
constexpr std::size_t kDenseSamples = 1024;
// The second rotation reads at most this many of the unexplained measurements (evenly strided): the winner's own
// solve reads up to 5,000, and a competitor with nearly the winner's support shows in a fifth of them.
constexpr std::size_t kSecondRotationMeasurements = 1000;
// The target's centroid and principal axes, and how far a candidate moves the matched points, read at most this
// many points (evenly strided).
constexpr std::size_t kShapeSamples = 4096;
constexpr std::size_t kMovedSamples = 512;
// Source voxels whose normal is within about 20 degrees of the dominant normal direction are left out of it.
constexpr double kDominantPlaneCos = 0.94;

struct Candidate {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    bool polish = true;      // polished over the matches; a geometric one is exact and judged where it is
    bool rival_only = false; // from the next core: a rival or nothing (its few matches make a noisy share)
};

// A cell's integer coordinates, clamped to 21 bits around the origin (a local frame spans far fewer cells).
inline std::int64_t cell_of(double x, double inv_cell) {
    return static_cast<std::int64_t>(std::min(std::max(std::floor(x * inv_cell), -1048575.0), 1048574.0));
}

inline std::uint64_t key_of(std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto q = [](std::int64_t c) { return static_cast<std::uint64_t>(c + 1048576) & 0x1FFFFFu; };
    return (q(x) << 42) | (q(y) << 21) | q(z);
}

inline std::uint64_t cell_key(const Eigen::Vector3d &p, double inv_cell) {
    return key_of(cell_of(p.x(), inv_cell), cell_of(p.y(), inv_cell), cell_of(p.z(), inv_cell));
}

// Cell keys in an open-addressing table (linear probing, a power-of-two capacity at least twice the keys): the
// dense support looks up to 27 cells per point, and a node-based set cost more in allocations than in lookups.
class CellTable {
public:
    static constexpr std::uint64_t kEmpty = ~std::uint64_t{0}; // cell_key never makes it (63 bits)
    explicit CellTable(std::size_t keys) {
        std::size_t capacity = 16;
        while (capacity < 2 * keys) capacity *= 2;
        keys_.assign(capacity, kEmpty);
        mask_ = capacity - 1;
    }
    std::size_t capacity() const { return keys_.size(); }
    std::uint64_t key(std::size_t slot) const { return keys_[slot]; }
    // The slot of `key`, taken for it when it was absent.
    std::size_t insert(std::uint64_t key) {
        std::size_t slot = first(key);
        while (keys_[slot] != kEmpty && keys_[slot] != key) slot = (slot + 1) & mask_;
        keys_[slot] = key;
        return slot;
    }
    bool contains(std::uint64_t key) const {
        for (std::size_t slot = first(key);; slot = (slot + 1) & mask_) {
            if (keys_[slot] == key) return true;
            if (keys_[slot] == kEmpty) return false;
        }
    }

private:
    std::size_t first(std::uint64_t key) const {
        return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_;
    }
    std::vector<std::uint64_t> keys_;
    std::size_t mask_ = 0;
};

// The translations b - R a of every match, binned in cells of two noise bounds; the mean translation of the
// `count` fullest cells (ties by cell key, so the answer depends on the data alone).
void translation_peaks(const AmbiguityInput &in, const Eigen::Matrix3d &R, double cell, std::size_t count,
                       std::vector<Candidate> &out) {
    const std::vector<Eigen::Vector3d> &a = *in.source, &b = *in.target;
    const double inv = 1.0 / cell;
    CellTable table(a.size());
    std::vector<std::uint32_t> votes(table.capacity(), 0);
    std::vector<Eigen::Vector3d> sums(table.capacity(), Eigen::Vector3d::Zero());
    for (std::size_t k = 0; k < a.size(); ++k) {
        const Eigen::Vector3d v = b[k] - R * a[k];
        const std::size_t slot = table.insert(cell_key(v, inv));
        ++votes[slot];
        sums[slot] += v;
    }
    struct Run {
        std::uint32_t votes;
        std::uint64_t key;
        std::size_t slot;
    };
    std::vector<Run> runs;
    for (std::size_t slot = 0; slot < table.capacity(); ++slot)
        if (votes[slot] != 0) runs.push_back({votes[slot], table.key(slot), slot});
    const std::size_t n = std::min(count, runs.size());
    std::partial_sort(
        runs.begin(), runs.begin() + static_cast<std::ptrdiff_t>(n), runs.end(),
        [](const Run &x, const Run &y) { return x.votes != y.votes ? x.votes > y.votes : x.key < y.key; });
    for (std::size_t i = 0; i < n; ++i) out.push_back({R, sums[runs[i].slot] / static_cast<double>(runs[i].votes)});
}

// Whether source voxels land beside target voxels: a cell of one voxel around each, 27 cells looked up.
class Occupancy {
public:
    Occupancy(const std::vector<Vec3f> &points, double voxel) : cells_(points.size()), inv_(1.0 / voxel) {
        for (const Vec3f &p : points) cells_.insert(cell_key(p.cast<double>(), inv_));
    }
    // Fraction of the sampled source voxels whose image under (R, t) has an occupied cell beside it.
    double support(const std::vector<Vec3f> &source, const std::vector<std::uint32_t> &sample, const Eigen::Matrix3d &R,
                   const Eigen::Vector3d &t) const {
        std::size_t hit = 0;
        for (std::uint32_t k : sample)
            if (beside(R * source[k].cast<double>() + t)) ++hit;
        return sample.empty() ? 0.0 : static_cast<double>(hit) / static_cast<double>(sample.size());
    }

    // Whether at least `needed` of the sampled source voxels land beside a target voxel under (R, t); stops as soon
    // as the answer is known (a pose that lands the source elsewhere is dismissed after a few hundred misses).
    bool support_reaches(const std::vector<Vec3f> &source, const std::vector<std::uint32_t> &sample,
                         const Eigen::Matrix3d &R, const Eigen::Vector3d &t, std::size_t needed) const {
        std::size_t hit = 0, left = sample.size();
        for (std::uint32_t k : sample) {
            if (hit >= needed) return true;
            if (hit + left < needed) return false;
            --left;
            if (beside(R * source[k].cast<double>() + t)) ++hit;
        }
        return hit >= needed;
    }

private:
    bool beside(const Eigen::Vector3d &p) const {
        const std::int64_t x = cell_of(p.x(), inv_), y = cell_of(p.y(), inv_), z = cell_of(p.z(), inv_);
        // The point's own cell first: where most landed points find their voxel.
        if (cells_.contains(key_of(x, y, z))) return true;
        for (std::int64_t dx = -1; dx <= 1; ++dx)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dz = -1; dz <= 1; ++dz)
                    if ((dx | dy | dz) != 0 && cells_.contains(key_of(x + dx, y + dy, z + dz))) return true;
        return false;
    }
    CellTable cells_;
    double inv_;
};

// The source voxels the dense support reads: evenly strided, without those on the dominant plane's direction (the
// ground of a LiDAR scan, a floor): a pose slid along a road keeps its ground aligned wherever it is, so the ground
// says nothing about which of two poses is right, and would make every slide look nearly as good.
std::vector<std::uint32_t> dense_sample(const std::vector<Vec3f> &voxels, const Normals &normals) {
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < voxels.size(); ++k)
        if (normals.valid[k])
            scatter.noalias() += normals.normal[k].cast<double>() * normals.normal[k].cast<double>().transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> dominant(scatter);
    const Eigen::Vector3d d = dominant.eigenvectors().col(2);
    std::vector<std::uint32_t> kept;
    for (std::size_t k = 0; k < voxels.size(); ++k)
        if (!normals.valid[k] || std::fabs(normals.normal[k].cast<double>().dot(d)) < kDominantPlaneCos)
            kept.push_back(static_cast<std::uint32_t>(k));
    const std::size_t stride = std::max<std::size_t>(1, (kept.size() + kDenseSamples - 1) / kDenseSamples);
    std::vector<std::uint32_t> sample;
    for (std::size_t i = 0; i < kept.size(); i += stride) sample.push_back(kept[i]);
    return sample;
}

} // namespace

Ambiguity measure_ambiguity(const AmbiguityInput &in, const PoseSolver &solver, const Eigen::Matrix3d &R,
                            const Eigen::Vector3d &t, RunContext &ctx) {
    Ambiguity out;
    const std::vector<Eigen::Vector3d> &a = *in.source, &b = *in.target;
    if (a.empty() || in.winner_inliers == 0) return out;
    const double bound = solver.noise_bound();
    std::vector<Candidate> candidates;
    translation_peaks(in, R, 2.0 * bound, kWinnerRotationPeaks, candidates);

    // A second rotation from the measurements the winner's rotation does not explain (a measurement's bound is
    // twice a correspondence's: the translation cancels in the difference, the noise of both ends adds).
    const std::vector<std::uint32_t> &core = *in.core;
    std::vector<IndexPair> unexplained;
    for (const IndexPair &p : *in.measurements) {
        const Eigen::Vector3d da = a[core[p.second]] - a[core[p.first]], db = b[core[p.second]] - b[core[p.first]];
        if ((db - R * da).norm() > 2.0 * bound) unexplained.push_back(p);
    }
    if (unexplained.size() > kSecondRotationMeasurements) {
        const std::size_t step = (unexplained.size() + kSecondRotationMeasurements - 1) / kSecondRotationMeasurements;
        std::size_t kept = 0;
        for (std::size_t i = 0; i < unexplained.size(); i += step) unexplained[kept++] = unexplained[i];
        unexplained.resize(kept);
    }
    if (unexplained.size() >= 3) {
        std::vector<Eigen::Vector3d> ca(core.size()), cb(core.size());
        for (std::size_t k = 0; k < core.size(); ++k) ca[k] = a[core[k]], cb[k] = b[core[k]];
        const PoseSolution second = solver.solve(ca, cb, std::move(unexplained), ctx);
        if (second.solver.solved) {
            candidates.push_back({second.solver.rotation, second.solver.translation});
            translation_peaks(in, second.solver.rotation, 2.0 * bound, kSecondRotationPeaks, candidates);
        }
    }

    // The pose of the next core (pruning.hpp): the structure that agrees with itself once the winner's core is out.
    // Where a symmetric part won (a sphere or a box matched onto itself turned, two alike parts swapped), the
    // right pose's matches are there. Few and weaker, so it is judged as a rival only (below).
    const std::vector<std::uint32_t> &second_core = *in.second_core;
    if (second_core.size() >= 3 && in.second_measurements->size() >= 3) {
        std::vector<Eigen::Vector3d> ca(second_core.size()), cb(second_core.size());
        for (std::size_t k = 0; k < second_core.size(); ++k) ca[k] = a[second_core[k]], cb[k] = b[second_core[k]];
        const PoseSolution next = solver.solve(ca, cb, *in.second_measurements, ctx);
        if (next.solver.solved) {
            const std::size_t first = candidates.size();
            candidates.push_back({next.solver.rotation, next.solver.translation});
            translation_peaks(in, next.solver.rotation, 2.0 * bound, kSecondRotationPeaks, candidates);
            for (std::size_t i = first; i < candidates.size(); ++i) candidates[i].rival_only = true;
        }
    }

    // A symmetric scene's symmetry axes are principal axes of its points: the winner turned half a turn about
    // each principal axis of the target's voxels, through their centroid (a whole symmetric object: exactly its
    // symmetry), and with the densest translations for that rotation (a partial view, a scene).
    const std::vector<Vec3f> &voxels = *in.target_voxels;
    const std::size_t every = std::max<std::size_t>(1, voxels.size() / kShapeSamples);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    std::size_t taken = 0;
    for (std::size_t k = 0; k < voxels.size(); k += every, ++taken) centre += voxels[k].cast<double>();
    centre /= static_cast<double>(std::max<std::size_t>(1, taken));
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    for (std::size_t k = 0; k < voxels.size(); k += every)
        spread.noalias() += (voxels[k].cast<double>() - centre) * (voxels[k].cast<double>() - centre).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes(spread);
    for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3d u = axes.eigenvectors().col(i).normalized();
        const Eigen::Matrix3d half_turn = 2.0 * u * u.transpose() - Eigen::Matrix3d::Identity();
        candidates.push_back({half_turn * R, half_turn * (t - centre) + centre, false});
        translation_peaks(in, half_turn * R, 2.0 * bound, kHalfTurnPeaks, candidates);
    }

    const double winner = static_cast<double>(in.winner_inliers);
    const std::size_t stride = std::max<std::size_t>(1, a.size() / kMovedSamples);
    // RMS of how far (R', t') moves the matched source points from where the winner puts them.
    const auto moved = [&](const Candidate &c) {
        double sum = 0.0;
        std::size_t n = 0;
        for (std::size_t k = 0; k < a.size(); k += stride, ++n) sum += ((c.R - R) * a[k] + (c.t - t)).squaredNorm();
        return std::sqrt(sum / static_cast<double>(n));
    };
    const double distinct = kDistinctNoiseBounds * bound;
    // Few inliers make the ratio noisy either way; the competitor's count raised by two standard deviations of a
    // count (Poisson: 2 sqrt(n) + 1) errs on the side of calling a scene ambiguous.
    const auto share = [&](std::size_t count) {
        const double n2 = static_cast<double>(count);
        return (n2 + 2.0 * std::sqrt(n2) + 1.0) / winner;
    };
    std::vector<std::pair<double, std::size_t>> dense_due; // (sparse share, candidate) for the dense check
    std::vector<std::size_t> rivals;                       // the next core's distinct candidates
    std::vector<std::uint8_t> mask;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        Candidate &c = candidates[i];
        // The winner found again (its own translation peak, a polish that returns to it) is no competitor; half
        // the distance before the polish, which moves a candidate by about a noise bound.
        if (!(moved(c) > 0.5 * distinct)) continue;
        // The next core's poses are judged where they lie, by their dense support only (below).
        if (c.rival_only) {
            if (!(moved(c) > distinct)) continue;
            ++out.candidates;
            rivals.push_back(i);
            continue;
        }
        // A candidate with under a quarter of the winner's support within twice the bound is no competitor, and is
        // not worth its polish.
        const double rough = share(count_inliers(a, b, 2.0 * bound, c.R, c.t, mask));
        if (rough < kWorthPolishing) {
            ++out.candidates;
            out.value = std::max(out.value, std::min(1.0, rough));
            continue;
        }
        const double sparse =
            share(c.polish ? solver.polish(a, b, c.R, c.t, mask) : count_inliers(a, b, bound, c.R, c.t, mask));
        if (!(moved(c) > distinct)) continue;
        ++out.candidates;
        if (sparse < kDenseFrom) {
            out.value = std::max(out.value, std::min(1.0, sparse));
        } else {
            dense_due.emplace_back(sparse, i);
        }
    }
    if (dense_due.empty() && rivals.empty()) return out;
    const Occupancy occupancy(*in.target_voxels, in.voxel_size);
    const std::vector<std::uint32_t> sample = dense_sample(*in.source_voxels, *in.source_normals);
    const double winner_dense = occupancy.support(*in.source_voxels, sample, R, t);
    // A rival: the next core's pose laying clearly more of the source beside the target than the winner, however
    // few matches it has. The winner then explains a part of the scene (a symmetric part matched onto itself) and
    // the rest of the clouds disagrees with it.
    const auto needed =
        static_cast<std::size_t>(std::ceil(kRivalDense * winner_dense * static_cast<double>(sample.size()) - 1e-9));
    for (std::size_t i : rivals) {
        if (out.value >= 1.0) break;
        if (needed <= sample.size() &&
            occupancy.support_reaches(*in.source_voxels, sample, candidates[i].R, candidates[i].t, needed))
            out.value = 1.0;
    }
    // The dense check in order of sparse share: a candidate's value is at most its share, so once the shares left are
    // no more than the value found, none of them can raise it.
    std::stable_sort(dense_due.begin(), dense_due.end(),
                     [](const auto &x, const auto &y) { return x.first > y.first; });
    for (const auto &[sparse, i] : dense_due) {
        if (std::min(1.0, sparse) <= out.value) break;
        const double dense = occupancy.support(*in.source_voxels, sample, candidates[i].R, candidates[i].t);
        out.value = std::max(out.value, std::min({1.0, sparse, winner_dense > 0.0 ? dense / winner_dense : 1.0}));
    }
    return out;
}

KISSM_DETAIL_END
