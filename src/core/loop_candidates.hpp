// SPDX-License-Identifier: MIT
// Loop candidates of a sequence of scans (kissm_sequence_loops, kissm_align_features with KISSM_PAIRS_SEQUENCE):
// pairs of scans far apart in the sequence but near each other in space, by given positions (priors) or by the
// consecutive registrations chained (dead reckoning). The arithmetic is numpy's as Python's kissm._candidates
// computes it on the machines we test, so that C, the CLI and Python choose the same pairs (docs/multiway.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// The radius of a dead-reckoned loop candidate grows by this share of the path between its scans (the odometry's
// drift; Python's kissm._candidates.DRIFT, measured in docs/reports/multiway-drive.md).
constexpr double kLoopDrift = 0.02;

// Positions in the sequence; the source is the later scan (the one the pair's transform moves).
struct ScanPair {
    std::size_t source = 0, target = 0;
};

// Where each scan is: 3 coordinates per scan (NaN where unknown), the path length from the start, and the piece of
// the sequence it belongs to (a break in the chain starts a new piece in a frame of its own); dead reckoning also
// keeps each scan's whole pose in its piece's frame (16 per scan, row-major; empty for priors).
struct ScanPlaces {
    std::vector<double> positions;
    std::vector<double> poses;
    std::vector<double> path;
    std::vector<std::int64_t> piece;
};

// The consecutive registrations chained: steps[k] is T_k_(k+1) (16, row-major), or null when that registration
// is missing or not valid (a new piece starts at k+1 with the identity). Each product is a fused multiply-add
// chain over the inner index from 0 (numpy's matmul with OpenBLAS), each step's length sqrt((x*x + y*y) + z*z).
ScanPlaces dead_reckoned(const std::vector<const double *> &steps, std::size_t scans);

// Given poses (16 per scan, world <- scan): their translations, NaN for a pose with a non-finite translation; one
// piece, no path.
ScanPlaces prior_places(const double *poses, std::size_t scans);

// For each scan j >= gap in order, among the scans i <= j - gap with known positions in j's piece whose distance
// (sqrt((dx*dx + dy*dy) + dz*dz)) is at most radius + drift * |path_j - path_i|, the `per_scan` nearest (by
// distance, then i), emitted by increasing i as pairs (source j, target i).
std::vector<ScanPair> loop_candidates(const ScanPlaces &where, double radius, std::size_t gap, std::size_t per_scan,
                                      double drift);

// Of `near` ((distance, i) for one scan j; each i once), the `per_scan` nearest (by distance, then i) appended to
// `out` as pairs (source j, target i) by increasing i: the choice every candidate rule shares. Reorders `near`.
void append_nearest(std::vector<std::pair<double, std::size_t>> &near, std::size_t per_scan, std::size_t j,
                    std::vector<ScanPair> &out);

KISSM_DETAIL_END
