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
    bool trusted = false; // a session's odometry (--pairs sessions): an edge the graph always keeps
};

// "all": every pair once, the later scan the source: (j, i) for i < j, i outer, j inner (the order of Python's
// kissm.multiway.align, so that both build the same graph).
std::vector<ScanPair> all_pairs(size_t scans);

// "sequence": the scans in order along a trajectory. Round 1: each scan registered to the `window` scans after
// it (source the later one), scan by scan: (i+1, i), ..., (i+window, i), then i+1. Round 2: the loop candidates
// that round 1's consecutive registrations give (sequence_loops), numbered after round 1's pairs.
struct SequenceOptions {
    int32_t window = 1;
    int32_t loop_gap = 10;        // a loop candidate's scans are at least this many apart (>= 1)
    int32_t loops_per_scan = 5;   // at most this many candidates per later scan (0: none)
    double loop_radius = 0.0;     // > 0 (the command makes it 30 x the voxel when not given)
    int32_t similar_per_scan = 3; // without priors, where the chain breaks: candidates by similarity (0: none)
    std::vector<double> priors;   // empty, or 16 per scan (read_priors): the positions loop candidates come from
};
std::vector<ScanPair> sequence_candidates(size_t scans, const SequenceOptions &opt);

// Round 2 of "sequence": the loop candidates kissm_sequence_loops() gives for opt.priors when given, else for round
// 1's records (those of the pairs
// (k+1, k) among `round1`; any order; a pair without a record, an error or a record that is not valid breaks the
// chain; a valid record without a transform chains NaN, as a valid result's NaN transform would in Python).
// Depends on the records only, so that a resumed run finds the same list. A UsageError if the library fails.
std::vector<ScanPair> sequence_loops(size_t scans, const std::vector<ScanPair> &round1,
                                     const std::vector<DoneRecord> &records, const SequenceOptions &opt);

// Round 1's valid consecutive registrations (the records of the pairs (k+1, k) among `round1`, as sequence_loops
// reads them) as kissm_sequence_loops() takes a chain: 16 numbers per step and a flag (1 valid) per step; empty
// for fewer than 2 scans.
struct SequenceChain {
    std::vector<double> steps;
    std::vector<uint8_t> valid;
};
SequenceChain sequence_chain(size_t scans, const std::vector<ScanPair> &round1, const std::vector<DoneRecord> &records);

// "sessions" (Python's kissm.multiway.align_sessions): the scans grouped by their session column, in order.
// Round 1: each session's consecutive pairs (k+1, k), trusted. Round 2 (session_loops_and_grid): for each session
// s in order, its loop candidates from its round-1 records (as sequence_loops, within the session), then every
// opt.stride-th scan j of s with every opt.stride-th scan i of each earlier session t (t outer, j, then i).
// Round 3 (sessions_across): from the poses the graph of rounds 1 and 2 gives, each placed scan k of a later
// session (in order) with the loops_per_scan nearest placed scans e of earlier sessions within the radius (by
// distance sqrt((dx*dx + dy*dy) + dz*dz), then e), unless (k, e) was registered already.
std::vector<size_t> session_starts(const std::vector<Scan> &scans); // each session's first scan, then the count
std::vector<ScanPair> session_odometry(const std::vector<size_t> &starts);
std::vector<ScanPair> session_loops_and_grid(const std::vector<size_t> &starts, const std::vector<ScanPair> &round1,
                                             const std::vector<DoneRecord> &records, const SequenceOptions &opt,
                                             size_t stride);
std::vector<ScanPair> sessions_across(const std::vector<size_t> &starts, const std::vector<ScanPair> &so_far,
                                      const std::vector<double> &poses, const std::vector<uint8_t> &placed,
                                      const SequenceOptions &opt);

// A pairs file: `kissm batch`'s table (source and target columns; blank and '#' lines ignored), naming scans
// by their `scan` names. A UsageError names the line of an unknown scan or a scan paired with itself.
std::vector<ScanPair> pairs_from_file(const std::string &path, const std::vector<Scan> &scans);

// The pairs as `kissm batch` rows, numbered 1, 2, ... in order, named by scan and carrying the scans' files.
std::vector<PairRow> pair_rows(const std::vector<ScanPair> &pairs, const std::vector<Scan> &scans);

} // namespace kissm_cli
