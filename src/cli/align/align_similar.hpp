// SPDX-License-Identifier: MIT
// `kissm align --pairs sequence` where the chain of consecutive registrations breaks (--similar-per-scan): loop
// candidates between its pieces by the scans' signatures, and the registrations between pieces that join the graph,
// by the library's rules (kissm_sequence_similar, kissm_sequence_corroborated) as Python's kissm.multiway.align
// and kissm_align_features apply them, so that all three give the same bits (docs/multiway.md, "Loop candidates by
// similarity").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <kissm.h>

#include "align/align_pairs.hpp"
#include "align/align_scans.hpp"
#include "batch/batch_pairs.hpp"

namespace kissm_cli {

// Whether a chain (sequence_chain) is broken: a step that is not valid.
bool chain_breaks(const SequenceChain &chain);

// KISSM_SIGNATURE_SIZE numbers per scan: the signature of its features under `config` (the registrations'
// descriptor settings; its thread count does not change the bits); a row of NaN for a scan that cannot be read or
// described, which is nobody's candidate (as Python leaves such a cloud out of every pair).
std::vector<double> scan_signatures(const std::vector<Scan> &scans, const kissm_config &config);

// The candidates by similarity for a broken chain (kissm_sequence_similar with opt.loop_gap and
// opt.similar_per_scan): pairs (j, i) ordered by j, then i. A UsageError if the library fails.
std::vector<ScanPair> similar_loops(const SequenceChain &chain, const std::vector<double> &signatures,
                                    const SequenceOptions &opt);

// `loops` and `similar` (each ordered by source, then target) merged in that order, without repeats.
std::vector<ScanPair> merged_loops(const std::vector<ScanPair> &loops, const std::vector<ScanPair> &similar);

// Per pair of `pairs`, 1 when its valid record (with a finite transform) is held out of the graph: a registration
// between pieces of the broken chain outside the largest set that agrees (kissm_sequence_corroborated with
// opt.loop_radius); all 0 when the chain is not broken. A UsageError if the library fails.
std::vector<uint8_t> held_out_pairs(const SequenceChain &chain, const std::vector<ScanPair> &pairs,
                                    const std::vector<DoneRecord> &records, const SequenceOptions &opt);

} // namespace kissm_cli
