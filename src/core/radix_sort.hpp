// SPDX-License-Identifier: MIT
// Stable sort of (key, index) records by key: LSD radix sort, 11 bits per pass, as many passes as the
// largest key needs. Replaces comparison sorts of voxel and grid keys, which were a large share of a
// registration's instructions (docs/design/performance.md, "Radix sort").
#pragma once

#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

struct KeyIndex {
    std::uint64_t key;
    std::uint32_t index;
};

// Sorts by key; records with equal keys keep their relative order.
void radix_sort_by_key(std::vector<KeyIndex> &records);

KISSM_DETAIL_END
