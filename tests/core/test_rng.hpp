// SPDX-License-Identifier: MIT
// Deterministic random numbers for tests (std distributions differ between standard libraries): splitmix64
// seeded with the seed itself, see src/common/splitmix64.h.
#pragma once

#include <cmath> // test_graph.cpp and test_voxelize.cpp get their maths through this header
#include <cstdint>

#include "common/splitmix64.h"

struct TestRng {
    std::uint64_t state;
    explicit TestRng(std::uint64_t seed) : state(seed) {}
    std::uint64_t next() { return splitmix64_next(&state); }
    double uniform() { return splitmix64_uniform(&state); }
    double uniform(double lo, double hi) { return splitmix64_range(&state, lo, hi); }
    double normal() { return splitmix64_gauss(&state); }
};
