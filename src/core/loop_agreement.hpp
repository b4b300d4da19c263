// SPDX-License-Identifier: MIT
// Which registrations between the pieces of a broken sequence join the pose graph (kissm_sequence_corroborated,
// kissm_align_features with KISSM_PAIRS_SEQUENCE). A pair found by similarity has no position to check it, and a
// wrong one on a piece's loose end would be absorbed by the graph at the cost of one consecutive edge; a revisit
// gives several registrations that agree on where the later piece lies, places that merely look alike give one,
// or a few that the revisit outnumbers (docs/multiway.md, "Loop candidates by similarity").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "loop_candidates.hpp"

KISSM_DETAIL_BEGIN

// A valid registration between two scans of a sequence: `transform` (16, row-major) is T_earlier_later, the later
// scan into the earlier one (the names only say which side is which: either may come first in the sequence).
struct PieceLink {
    std::size_t earlier = 0, later = 0;
    const double *transform = nullptr;
};

// For each link, whether the graph takes it: a link within one piece always; the links between two pieces are
// grouped by their (earlier piece, later piece), and in each group link a agrees with link b when b's later scan
// is another scan than a's and a, through the later piece's odometry, puts it within radius + drift x (|path of
// b's earlier scan - path of a's| + |path of b's later scan - path of a's|) of where b puts it. The link most
// others agree with (the first of equals) is kept with those it agrees with, if any; the others are not.
// `reckoned` is dead_reckoned()'s (its poses and paths). Poses are inverted as rigid transforms (R^T, -R^T t).
std::vector<std::uint8_t> corroborated(const std::vector<PieceLink> &links, const ScanPlaces &reckoned, double radius,
                                       double drift);

KISSM_DETAIL_END
