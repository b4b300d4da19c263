// SPDX-License-Identifier: MIT
// Stage 5c: whether the scene holds a second pose nearly as well supported as the solver's. Repetitive and
// symmetric scenes (a street of identical facades, pillars at a regular spacing, a symmetric object) match
// just as well one period along, or turned onto their own symmetry, and every other rule is satisfied by such
// a pose because the scene really does look the same there (docs/design/accuracy.md, "Ambiguity").
// Not in the paper: an addition of this library (issue 33, part 3).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "gnc_solver.hpp"
#include "pose_solver.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

struct AmbiguityInput {
    const std::vector<Eigen::Vector3d> *source; // every match's points (local frames)
    const std::vector<Eigen::Vector3d> *target;
    const std::vector<std::uint32_t> *core;        // the pruned core, indices into the matches
    const std::vector<IndexPair> *measurements;    // the core's measurements, positions in `core`
    const std::vector<std::uint32_t> *second_core; // the next core (pruning.hpp), and its measurements
    const std::vector<IndexPair> *second_measurements;
    std::size_t winner_inliers;              // the solver's pose's polished inliers over every match
    const std::vector<Vec3f> *source_voxels; // the clouds' voxels (local frames), for the dense support
    const std::vector<Vec3f> *target_voxels;
    const Normals *source_normals; // per source voxel
    double voxel_size;
};

struct Ambiguity {
    // The best distinct competitor's support over the winner's, in [0, 1] (1 also when it has more): its
    // polished inliers over every match, raised by 2 sqrt(n) + 1, against the winner's, and from kDenseFrom on the
    // smaller of that and its dense support (source voxels landing beside target voxels) against the winner's. A
    // candidate under a quarter of the winner's support within twice the bound is reported by that share,
    // unpolished. 1 when a distinct candidate is a rival (kRivalDense).
    double value = 0.0;
    int candidates = 0; // poses examined
};

// A competitor is distinct when it moves the matched source points by more than this many solver noise bounds
// (RMS) from the winner: farther than two right poses can be apart (a right pose is within a noise bound of
// the truth), nearer ones are the winner again.
constexpr double kDistinctNoiseBounds = 8.0;
// From this sparse ratio on, the dense support decides with it (below, the sparse ratio alone is reported).
constexpr double kDenseFrom = 0.5;
// A rival: a distinct pose whose dense support is at least this many times the winner's makes the result ambiguous
// (value 1), however few matches it has: the winner explains a part of the clouds and the rest disagrees with it.
// Measured (docs/design/accuracy.md, "Ambiguity"): 1.2 refuses every gross pose of the symmetric parts'
// objects and no right pose of any family; 1.5 lets one 180 degree flip through.
constexpr double kRivalDense = 1.2;

// The competitors: the densest translations under the winner's rotation (a period along a repetitive scene),
// the rotation the core's measurements give without those the winner explains, with its densest translations,
// and the winner turned half a turn about each principal axis of the target's voxels (a symmetry), through their
// centroid and with the densest translations; each polished over every match like the winner. And the pose of
// the next core with its densest translations, judged as rivals only (kRivalDense).
Ambiguity measure_ambiguity(const AmbiguityInput &in, const PoseSolver &solver, const Eigen::Matrix3d &R,
                            const Eigen::Vector3d &t, RunContext &ctx);

KISSM_DETAIL_END
