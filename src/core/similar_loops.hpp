// SPDX-License-Identifier: MIT
// Loop candidates by similarity (kissm_sequence_similar, kissm_align_features with KISSM_PAIRS_SEQUENCE): where the
// chained odometry of a sequence breaks into pieces, nothing relates the pieces' frames, so the candidates between
// them come from the clouds' signatures (signature.hpp) instead of their positions (docs/multiway.md, "Loop
// candidates by similarity").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "loop_candidates.hpp"

KISSM_DETAIL_BEGIN

// `signatures` holds `size` numbers per scan (a row with a non-finite number: a scan without one, nobody's
// candidate); `piece` (one per scan) the piece of the chain each scan belongs to. For each scan j >= gap in order,
// among the scans i <= j - gap of other pieces, the `per_scan` whose signatures are nearest (squared distances
// summed over the columns in order, from 0; then the lower i), emitted by increasing i as pairs (source j,
// target i). Within a piece the odometry judges (loop_candidates), so pairs of one piece are never given.
std::vector<ScanPair> similar_candidates(const double *signatures, std::size_t size,
                                         const std::vector<std::int64_t> &piece, std::size_t gap, std::size_t per_scan);

KISSM_DETAIL_END
