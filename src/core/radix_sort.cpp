// SPDX-License-Identifier: MIT
#include "radix_sort.hpp"

#include <algorithm>

KISSM_DETAIL_BEGIN

void radix_sort_by_key(std::vector<KeyIndex> &records) {
    const std::size_t n = records.size();
    if (n < 2) return;
    std::uint64_t max_key = 0;
    for (const auto &r : records) max_key = std::max(max_key, r.key);
    constexpr int kBits = 11;
    constexpr std::size_t kBuckets = std::size_t(1) << kBits;
    std::vector<KeyIndex> buffer(n);
    std::vector<std::size_t> count(kBuckets);
    for (int shift = 0; shift < 64 && (max_key >> shift) != 0; shift += kBits) {
        std::fill(count.begin(), count.end(), 0);
        for (const auto &r : records) ++count[(r.key >> shift) & (kBuckets - 1)];
        std::size_t sum = 0;
        for (auto &c : count) {
            const std::size_t here = c;
            c = sum;
            sum += here;
        }
        for (const auto &r : records) buffer[count[(r.key >> shift) & (kBuckets - 1)]++] = r;
        records.swap(buffer);
    }
}

KISSM_DETAIL_END
