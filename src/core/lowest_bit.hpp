// SPDX-License-Identifier: MIT
// The index of a word's lowest set bit: one instruction where the compiler offers it.
#pragma once

#include <cstddef>
#include <cstdint>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// `m` must not be 0.
inline std::size_t lowest_bit(std::uint64_t m) {
#if defined(__GNUC__) || defined(__clang__)
    return static_cast<std::size_t>(__builtin_ctzll(m));
#else
    std::size_t i = 0;
    for (; !(m & 1u); m >>= 1) ++i;
    return i;
#endif
}

KISSM_DETAIL_END
