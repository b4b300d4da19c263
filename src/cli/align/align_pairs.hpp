// SPDX-License-Identifier: MIT
// Which pairs of scans `kissm align` registers (--pairs): every pair, a sequence's candidates, or a file's.
// Each policy returns the list in a fixed order; that order numbers the pairs (the results' "pair") and is
// the order their edges enter the pose graph, so the poses never depend on which pair finished first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "align/align_scans.hpp"
#include "batch/batch_pairs.hpp"

namespace kissm_cli {

// Positions in the scans file; the source is the scan whose points the pair's transform moves.
struct ScanPair {
    size_t source = 0, target = 0;
};

// "all": every pair once, the later scan the source: (j, i) for i < j, i outer, j inner (the order of Python's
// kissm.multiway.align, so that both build the same graph).
std::vector<ScanPair> all_pairs(size_t scans);

// "sequence": the scans in order along a trajectory. Round 1: each scan registered to the `window` scans after
// it (source the later one), scan by scan: (i+1, i), ..., (i+window, i), then i+1. Round 2: the loop candidates
// that round 1's consecutive registrations give (sequence_loops), numbered after round 1's pairs.
struct SequenceOptions {
    int32_t window = 1;
    int32_t loop_gap = 10;      // a loop candidate's scans are at least this many apart (>= 1)
    int32_t loops_per_scan = 5; // at most this many candidates per later scan (0: none)
    double loop_radius = 0.0;   // > 0 (the command makes it 30 x the voxel when not given)
};
std::vector<ScanPair> sequence_candidates(size_t scans, const SequenceOptions &opt);

// The radius of a loop candidate grows by this share of the dead-reckoned path between its scans: Python's
// kissm._candidates.DRIFT.
constexpr double kLoopDrift = 0.02;

// Python's kissm._candidates.dead_reckoned: the consecutive registrations chained. steps[k] is the transform
// (16, row-major) of scan k+1 into scan k, or nullptr when that registration is missing or not valid, which
// starts a new piece in a frame of its own (pose the identity). The poses are multiplied as numpy's matmul
// does here (OpenBLAS: a fused multiply-add chain over the inner index, from 0), each step's length is
// sqrt((x*x + y*y) + z*z), as np.linalg.norm of a 3-vector.
struct DeadReckoning {
    std::vector<double> positions; // 3 per scan
    std::vector<double> path;      // per scan: the path length from the start of the sequence
    std::vector<int64_t> piece;    // per scan
};
DeadReckoning dead_reckoned(const std::vector<const double *> &steps, size_t scans);

// Python's kissm._candidates.loop_candidates: for each scan j >= gap in order, among the scans i <= j - gap
// with finite positions in j's piece whose distance (sqrt((dx*dx + dy*dy) + dz*dz), numpy's) is at most
// radius + drift * |path_j - path_i|, the `per_scan` nearest (sorted by (distance, i)), emitted by increasing
// i, as pairs (source j, target i).
std::vector<ScanPair> loop_candidates(const DeadReckoning &where, double radius, size_t gap, size_t per_scan,
                                      double drift);

// Round 2 of "sequence": the loop candidates from round 1's records (those of the pairs (k+1, k) among
// `round1`; any order; a pair without a record, an error or a record that is not valid breaks the chain).
// Depends on the records only, so that a resumed run finds the same list.
std::vector<ScanPair> sequence_loops(size_t scans, const std::vector<ScanPair> &round1,
                                     const std::vector<DoneRecord> &records, const SequenceOptions &opt);

// A pairs file: `kissm batch`'s table (source and target columns; blank and '#' lines ignored), naming scans
// by their `scan` names. A UsageError names the line of an unknown scan or a scan paired with itself.
std::vector<ScanPair> pairs_from_file(const std::string &path, const std::vector<Scan> &scans);

// The pairs as `kissm batch` rows, numbered 1, 2, ... in order, named by scan and carrying the scans' files.
std::vector<PairRow> pair_rows(const std::vector<ScanPair> &pairs, const std::vector<Scan> &scans);

} // namespace kissm_cli
