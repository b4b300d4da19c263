// SPDX-License-Identifier: MIT
// libFuzzer target for the sequence rules. kissm_sequence_loops: chains of decoded steps (rigid, spoilt or NaN ones,
// fuzz_input.hpp) with validity flags in and out of range, or priors with unknown positions, under any radius, gap,
// per_scan and capacity. Invariants: a refused call writes no pair (and a count only when the capacity is short); an
// accepted one gives the count-only call's count, pairs (j, i) with j - i >= gap, ordered by j then i, at most
// per_scan per j, none twice; with priors every pair's positions are finite and within the radius; the same bits when
// repeated. Then, on the same chain, kissm_sequence_similar (decoded signatures, NaN and infinite ones included):
// the same invariants, and every pair across pieces; and kissm_sequence_corroborated (decoded pairs, in range or
// not, and transforms): a refused call writes no flag, an accepted one flags 0 or 1, 1 for a pair within one piece,
// the same bits when repeated.
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

// The two-call protocol the candidate functions share: a counting call (no buffer), then a filling one. Both refuse
// alike, touching nothing; a buffer too small is refused with the count; otherwise both agree on the count. True when
// the filled pairs are there to check.
bool calls_agree(int32_t first, int32_t second, std::uint64_t counted, std::uint64_t count, std::uint64_t bound,
                 std::uint64_t capacity, const std::vector<std::uint64_t> &pairs) {
    if (first != KISSM_OK) {
        require(second == first && counted == kSentinel && count == kSentinel);
        for (const std::uint64_t x : pairs) require(x == kSentinel);
        return false;
    }
    require(counted <= bound);
    if (counted > capacity) {
        require(second == KISSM_ERR_INVALID_ARGUMENT && count == counted);
        for (const std::uint64_t x : pairs) require(x == kSentinel);
        return false;
    }
    require(second == KISSM_OK && count == counted);
    return true;
}

// kissm_sequence_loops' checks (see the file comment).
void check_loops(std::uint64_t n, const double *s, const std::uint8_t *v, const double *p, double radius,
                 std::uint64_t gap, std::uint64_t per_scan, std::uint64_t capacity) {
    std::uint64_t counted = kSentinel;
    const int32_t first = kissm_sequence_loops(n, s, v, p, radius, gap, per_scan, nullptr, 0, &counted);
    std::vector<std::uint64_t> pairs(2 * capacity + 2, kSentinel);
    std::uint64_t count = kSentinel;
    const int32_t second = kissm_sequence_loops(n, s, v, p, radius, gap, per_scan, pairs.data(), capacity, &count);
    if (!calls_agree(first, second, counted, count, n * per_scan, capacity, pairs)) return;
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
}

// Each scan's piece under the flags (a flag other than 1 breaks the chain here; the calls refuse flags above 1).
std::vector<std::uint64_t> pieces_of(std::uint64_t n, const std::uint8_t *v) {
    std::vector<std::uint64_t> piece(n, 0);
    for (std::uint64_t k = 1; k < n; ++k) piece[k] = piece[k - 1] + (v && v[k - 1] != 1 ? 1 : 0);
    return piece;
}

bool flags_in_range(std::uint64_t n, const std::uint8_t *v) {
    for (std::uint64_t k = 0; v && k + 1 < n; ++k)
        if (v[k] > 1) return false;
    return true;
}

void check_similar(kissm_fuzz::Bytes &in, std::uint64_t n, const std::uint8_t *v, std::uint64_t gap,
                   std::uint64_t per_scan, std::uint64_t capacity) {
    // A few numbers per scan from the input, the rest zero: near and far signatures, ties, NaN and infinity.
    static const double special[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                                     1e300, 0.0};
    std::vector<double> signatures(KISSM_SIGNATURE_SIZE * n + 1, 0.0);
    for (std::uint64_t k = 0; k < n; ++k) {
        for (int c = 0; c < 3; ++c) {
            const std::uint8_t b = in.u8();
            signatures[KISSM_SIGNATURE_SIZE * k + static_cast<std::uint64_t>(c) * 40] =
                b < 8 ? special[b % 4] : static_cast<double>(b % 16) / 8.0;
        }
    }
    std::vector<std::uint64_t> pairs(2 * capacity + 2, kSentinel);
    std::uint64_t counted = kSentinel, count = kSentinel;
    const int32_t first = kissm_sequence_similar(n, v, signatures.data(), gap, per_scan, nullptr, 0, &counted);
    const int32_t second =
        kissm_sequence_similar(n, v, signatures.data(), gap, per_scan, pairs.data(), capacity, &count);
    if (first != KISSM_OK)
        require(first == KISSM_ERR_INVALID_ARGUMENT && (n == 0 || gap == 0 || !flags_in_range(n, v)));
    if (!calls_agree(first, second, counted, count, n * per_scan, capacity, pairs)) return;
    const std::vector<std::uint64_t> piece = pieces_of(n, v);
    std::uint64_t last_j = 0, last_i = 0, run = 0;
    for (std::uint64_t k = 0; k < count; ++k) {
        const std::uint64_t j = pairs[2 * k], i = pairs[2 * k + 1];
        require(j < n && i + gap <= j && piece[i] != piece[j]);
        require(std::isfinite(signatures[KISSM_SIGNATURE_SIZE * i]) &&
                std::isfinite(signatures[KISSM_SIGNATURE_SIZE * j]));
        if (k > 0) require(j > last_j || (j == last_j && i > last_i));
        run = k > 0 && j == last_j ? run + 1 : 1;
        require(run <= per_scan);
        last_j = j, last_i = i;
    }
    std::vector<std::uint64_t> again(pairs.size(), kSentinel);
    std::uint64_t count_again = 0;
    require(kissm_sequence_similar(n, v, signatures.data(), gap, per_scan, again.data(), capacity, &count_again) ==
                KISSM_OK &&
            count_again == count && std::memcmp(again.data(), pairs.data(), pairs.size() * sizeof(std::uint64_t)) == 0);
}

void check_corroborated(kissm_fuzz::Bytes &in, std::uint64_t n, const double *s, const std::uint8_t *v, double radius) {
    const std::uint64_t num_pairs = in.u8() % 9;
    std::vector<std::uint64_t> pairs(2 * num_pairs + 1);
    std::vector<double> transforms(16 * num_pairs + 1);
    bool in_range = true;
    for (std::uint64_t k = 0; k < num_pairs; ++k) {
        pairs[2 * k] = in.u8() % 44, pairs[2 * k + 1] = in.u8() % 44; // beyond 40 scans: refused
        in_range = in_range && pairs[2 * k] < n && pairs[2 * k + 1] < n;
        kissm_fuzz::make_transform(in, &transforms[16 * k]);
    }
    std::vector<std::uint8_t> kept(num_pairs + 1, 0xA5), again(num_pairs + 1, 0xA5);
    const int32_t st =
        kissm_sequence_corroborated(n, s, v, radius, num_pairs, pairs.data(), transforms.data(), kept.data());
    if (st != KISSM_OK) {
        require(st == KISSM_ERR_INVALID_ARGUMENT || st == KISSM_ERR_NULL_ARGUMENT);
        require(!in_range || n == 0 || !flags_in_range(n, v) || !(radius > 0.0) || !std::isfinite(radius) ||
                (n > 1 && !s) || (v && !s));
        for (const std::uint8_t x : kept) require(x == 0xA5);
        return;
    }
    const std::vector<std::uint64_t> piece = pieces_of(n, v);
    for (std::uint64_t k = 0; k < num_pairs; ++k) {
        require(kept[k] <= 1);
        if (piece[pairs[2 * k]] == piece[pairs[2 * k + 1]]) require(kept[k] == 1);
    }
    require(kept[num_pairs] == 0xA5);
    require(kissm_sequence_corroborated(n, s, v, radius, num_pairs, pairs.data(), transforms.data(), again.data()) ==
                KISSM_OK &&
            again == kept);
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

    check_loops(n, s, v, p, radius, gap, per_scan, capacity);
    // The rules of a broken chain: the chain's flags (none with priors), its steps.
    const std::uint8_t *flags_only = p ? nullptr : v;
    check_similar(in, n, flags_only, gap, per_scan, capacity);
    check_corroborated(in, n, p ? nullptr : s, flags_only, radius);
    return 0;
}
