/* SPDX-License-Identifier: MIT */
/* splitmix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number generators", 2014) and the
 * derived functions that its users share: the one definition behind the demo scene of the CLI
 * (src/sim/rng.hpp seeds xoshiro256** with it), the C API test scenes (tests/capi/scenes.c), the stage
 * tests (tests/core/test_rng.hpp) and the real-data test. tools/make_roundtrip_data.py is a Python copy of
 * this file; the test splitmix64_python checks that both give the same numbers.
 *
 * C99 and C++: static inline functions of a plain uint64_t state, no global state, no libc random numbers.
 * Each user keeps its own seeding (how a seed becomes the state); these functions only advance it. */
#ifndef KISSM_COMMON_SPLITMIX64_H
#define KISSM_COMMON_SPLITMIX64_H

#include <math.h>
#include <stdint.h>

/* The next 64 random bits; the state advances by the golden-ratio increment. */
static inline uint64_t splitmix64_next(uint64_t *state) {
    uint64_t z = (*state += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

/* [0, 1) from the top 53 bits of any 64 random bits (exact: every value is a multiple of 2^-53). */
static inline double splitmix64_unit(uint64_t bits) { return (double)(bits >> 11) * (1.0 / 9007199254740992.0); }

/* Uniform in [0, 1) with 53 random bits. */
static inline double splitmix64_uniform(uint64_t *state) { return splitmix64_unit(splitmix64_next(state)); }

/* Uniform in [lo, hi). */
static inline double splitmix64_range(uint64_t *state, double lo, double hi) {
    return lo + (hi - lo) * splitmix64_uniform(state);
}

/* Standard normal by the Box-Muller transform, cosine branch only (two uniforms per value, nothing kept);
 * the first uniform is clamped to 1e-300 so that its logarithm is finite. */
static inline double splitmix64_gauss(uint64_t *state) {
    double u1 = splitmix64_uniform(state);
    const double u2 = splitmix64_uniform(state);
    if (u1 < 1e-300) u1 = 1e-300;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586476925 * u2);
}

#endif
