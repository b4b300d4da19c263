// SPDX-License-Identifier: MIT
// `kissm align`'s pose graph: each valid pair record a robust edge, optimised from the first scan, as Python's
// kissm.multiway.align does (docs/multiway.md): the same edges in the same order
// give the same bits.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "align/align_pairs.hpp"
#include "batch/batch_pairs.hpp"

namespace kissm_cli {

// One valid registration as the graph judged it.
struct AlignEdge {
    int64_t pair = 0; // the results' "pair"
    size_t source = 0, target = 0;
    double transform[16];   // T_target_source
    double information[36]; // the record's, or the coarse fallback (edge_information)
    bool accepted = false;
    double residual = 0.0; // xi^T I xi at the solution; NaN where a scan of it is not placed
};

struct Alignment {
    std::vector<double> poses;        // 16 per scan: T_world_scan, world = the first scan's frame; NaN if not placed
    std::vector<uint8_t> placed;      // per scan
    std::vector<uint64_t> components; // per scan: the smallest scan position joined to it by accepted edges
    std::vector<AlignEdge> edges;     // the valid registrations, in pair order
    size_t valid = 0, invalid = 0, errors = 0; // the pairs' records
    std::vector<std::string> skipped;          // valid records the graph refused (a message each)
};

// The edge's information: the record's when it is all finite (refinement ran), else an isotropic one from the
// solver's rotation uncertainty (at least 1e-4 rad) and a translation sigma of the noise bound (at least 1e-9):
// coarse edges then weigh alike, and the graph still rejects those that disagree by far.
void edge_information(const DoneRecord &record, double information[36]);

// Builds the graph of `scans` nodes from the records (any order; each pair of `pairs` exactly once, as
// scan_results(..., with_poses = true) read them), adds the valid ones in pair order as edges (trusted for a
// trusted pair, robust otherwise) and optimises it with anchor 0 and `bound`. A pair whose `held_out` flag is 1
// (empty: none; held_out_pairs) is an edge reported as not accepted with a NaN residual, left out of the graph, as
// Python reports it. A UsageError when a pair has no record or the library fails.
Alignment solve_alignment(size_t scans, const std::vector<ScanPair> &pairs, const std::vector<DoneRecord> &records,
                          double bound, const std::vector<uint8_t> &held_out = {});

} // namespace kissm_cli
