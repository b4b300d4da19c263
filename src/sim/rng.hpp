// SPDX-License-Identifier: MIT
// Deterministic pseudo-random numbers for the demo scene: xoshiro256** seeded through splitmix64
// (src/common/splitmix64.h), with our own uniform and normal transforms. std::random_device is never used,
// and std:: distributions are avoided because their output is implementation-defined: the same seed must
// give the same scene everywhere.
#pragma once

#include <cmath>
#include <cstdint>

#include "splitmix64.h"

namespace kissm_sim {

class Rng {
public:
    // `stream` selects an independent sequence for the same seed (scene layout, each scan, ...).
    explicit Rng(uint64_t seed, uint64_t stream = 0) {
        uint64_t sm = seed ^ (stream * 0xD1B54A32D192ED03ull);
        for (uint64_t &word : s_) word = splitmix64_next(&sm);
    }

    uint64_t next() {
        const uint64_t result = rotl(s_[1] * 5, 7) * 9;
        const uint64_t t = s_[1] << 17;
        s_[2] ^= s_[0];
        s_[3] ^= s_[1];
        s_[1] ^= s_[2];
        s_[0] ^= s_[3];
        s_[2] ^= t;
        s_[3] = rotl(s_[3], 45);
        return result;
    }

    // Uniform in [0, 1) with 53 random bits.
    double uniform() { return splitmix64_unit(next()); }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    // Uniform integer in [lo, hi] (the modulo bias is negligible for the small spans used here).
    int uniform_int(int lo, int hi) {
        const uint64_t span = static_cast<uint64_t>(static_cast<int64_t>(hi) - lo) + 1u;
        return lo + static_cast<int>(next() % span);
    }
    bool chance(double p) { return uniform() < p; }
    double sign() { return chance(0.5) ? 1.0 : -1.0; }

    // Standard normal by the Box-Muller transform (the second value is kept for the next call).
    double normal() {
        if (has_spare_) {
            has_spare_ = false;
            return spare_;
        }
        const double u1 = 1.0 - uniform(); // (0, 1]: log is finite
        const double u2 = uniform();
        const double radius = std::sqrt(-2.0 * std::log(u1));
        const double angle = 6.283185307179586476925 * u2;
        spare_ = radius * std::sin(angle);
        has_spare_ = true;
        return radius * std::cos(angle);
    }

    // Exponentially distributed with the given mean.
    double exponential(double mean) { return -mean * std::log(1.0 - uniform()); }

private:
    static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

    uint64_t s_[4];
    double spare_ = 0.0;
    bool has_spare_ = false;
};

} // namespace kissm_sim
