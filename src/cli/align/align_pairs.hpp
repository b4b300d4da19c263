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

// "sequence": the scans in order along a trajectory. Each scan is registered to the `window` scans after it
// (source the later one), scan by scan: (i+1, i), ..., (i+window, i), then i+1. Loop-closure candidates will
// join these settings and this list.
struct SequenceOptions {
    int32_t window = 1;
};
std::vector<ScanPair> sequence_candidates(size_t scans, const SequenceOptions &opt);

// A pairs file: `kissm batch`'s table (source and target columns; blank and '#' lines ignored), naming scans
// by their `scan` names. A UsageError names the line of an unknown scan or a scan paired with itself.
std::vector<ScanPair> pairs_from_file(const std::string &path, const std::vector<Scan> &scans);

// The pairs as `kissm batch` rows, numbered 1, 2, ... in order, named by scan and carrying the scans' files.
std::vector<PairRow> pair_rows(const std::vector<ScanPair> &pairs, const std::vector<Scan> &scans);

} // namespace kissm_cli
