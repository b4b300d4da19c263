// SPDX-License-Identifier: MIT
// libFuzzer target for kissm_sequence_loops: chains of decoded steps (rigid, spoilt or NaN ones, fuzz_input.hpp)
// with validity flags in and out of range, or priors with unknown positions, under any radius, gap, per_scan and
// capacity. Invariants: a refused call writes no pair (and a count only when the capacity is short); an accepted
// one gives the count-only call's count, pairs (j, i) with j - i >= gap, ordered by j then i, at most per_scan per
// j, none twice; with priors every pair's positions are finite and within the radius; the same bits when repeated.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "fuzz_input.hpp"

namespace {

void require(bool ok) {
    if (!ok) std::abort();
}

constexpr std::uint64_t kSentinel = 0x5A5A5A5A5A5A5A5AULL;

double pick_radius(std::uint8_t b) {
    static const double special[] = {
        0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1e-300, 1e300};
    if (b < 6) return special[b];
    return std::ldexp(1.0 + (b % 16) / 16.0, static_cast<int>(b / 16) - 6);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    kissm_fuzz::Bytes in(data, size);
    const std::uint64_t n = in.u8() % 40; // 0 is refused
    const std::uint8_t mode = in.u8();
    const bool use_priors = mode & 1, flags = mode & 2, null_steps = (mode & 12) == 12;
    const double radius = pick_radius(in.u8());
    const std::uint64_t gap = in.u8() % 12, per_scan = in.u8() % 8;
    const std::uint64_t capacity = in.u8() % 64;
    const std::size_t steps_count = n > 0 ? n - 1 : 0;
    std::vector<double> steps(16 * steps_count + 1), priors(16 * n + 1);
    std::vector<std::uint8_t> valid(steps_count + 1);
    for (std::size_t k = 0; k < steps_count; ++k) {
        kissm_fuzz::make_transform(in, &steps[16 * k]);
        valid[k] = static_cast<std::uint8_t>(in.u8() % 5 == 0 ? in.u8() % 3 : 1);
    }
    for (std::size_t k = 0; k < n && use_priors; ++k) {
        kissm_fuzz::make_transform(in, &priors[16 * k]);
        if (in.u8() % 7 == 0) priors[16 * k + 3 + 4 * (k % 3)] = std::numeric_limits<double>::quiet_NaN();
    }
    const double *s = use_priors || null_steps ? nullptr : steps.data();
    const std::uint8_t *v = flags && s ? valid.data() : nullptr;
    const double *p = use_priors ? priors.data() : nullptr;

    std::uint64_t counted = kSentinel;
    const int32_t first = kissm_sequence_loops(n, s, v, p, radius, gap, per_scan, nullptr, 0, &counted);
    std::vector<std::uint64_t> pairs(2 * capacity + 2, kSentinel);
    std::uint64_t count = kSentinel;
    const int32_t second = kissm_sequence_loops(n, s, v, p, radius, gap, per_scan, pairs.data(), capacity, &count);
    if (first != KISSM_OK) {
        require(second == first && counted == kSentinel && count == kSentinel);
        for (const std::uint64_t x : pairs) require(x == kSentinel);
        return 0;
    }
    require(counted <= n * per_scan);
    if (counted > capacity) {
        require(second == KISSM_ERR_INVALID_ARGUMENT && count == counted);
        for (const std::uint64_t x : pairs) require(x == kSentinel);
        return 0;
    }
    require(second == KISSM_OK && count == counted);
    for (std::size_t k = 2 * count; k < pairs.size(); ++k) require(pairs[k] == kSentinel);
    std::uint64_t last_j = 0, last_i = 0, run = 0;
    for (std::uint64_t k = 0; k < count; ++k) {
        const std::uint64_t j = pairs[2 * k], i = pairs[2 * k + 1];
        require(j < n && i + gap <= j);
        if (k > 0) require(j > last_j || (j == last_j && i > last_i));
        run = k > 0 && j == last_j ? run + 1 : 1;
        require(run <= per_scan);
        if (p) {
            double d2 = 0.0;
            for (int a = 0; a < 3; ++a) {
                const double delta = p[16 * i + 3 + 4 * a] - p[16 * j + 3 + 4 * a];
                require(std::isfinite(delta));
                d2 += delta * delta;
            }
            require(std::sqrt(d2) <= radius * (1.0 + 1e-12));
        }
        last_j = j, last_i = i;
    }
    std::vector<std::uint64_t> again(pairs.size(), kSentinel);
    std::uint64_t count_again = 0;
    require(kissm_sequence_loops(n, s, v, p, radius, gap, per_scan, again.data(), capacity, &count_again) == KISSM_OK &&
            count_again == count && std::memcmp(again.data(), pairs.data(), pairs.size() * sizeof(std::uint64_t)) == 0);
    return 0;
}
