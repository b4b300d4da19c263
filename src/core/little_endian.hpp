// SPDX-License-Identifier: MIT
// Little-endian fields, byte by byte, whatever the host's byte order: the features format (features_codec.cpp),
// the .npy preamble (io/npy_reader.cpp) and the fuzzers that forge those bytes share these. Header only, inline:
// the loops have a constant length and compile to one load or store on a little-endian host.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>

#include "detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// The unsigned integer U stored in sizeof(U) bytes at p, least significant first.
template <class U>
inline U load_le(const std::uint8_t *p) {
    static_assert(std::is_unsigned<U>::value, "load_le reads unsigned integers");
    U v = 0;
    for (std::size_t i = 0; i < sizeof(U); ++i) v = static_cast<U>(v | static_cast<U>(static_cast<U>(p[i]) << (8 * i)));
    return v;
}

// Stores the unsigned integer v at p in sizeof(U) bytes, least significant first.
template <class U>
inline void store_le(U v, std::uint8_t *p) {
    static_assert(std::is_unsigned<U>::value, "store_le writes unsigned integers");
    for (std::size_t i = 0; i < sizeof(U); ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// IEEE-754 binary32 / binary64 and two's-complement int32 as their little-endian bit patterns.
inline float load_le_f32(const std::uint8_t *p) {
    const std::uint32_t b = load_le<std::uint32_t>(p);
    float v;
    std::memcpy(&v, &b, 4);
    return v;
}
inline double load_le_f64(const std::uint8_t *p) {
    const std::uint64_t b = load_le<std::uint64_t>(p);
    double v;
    std::memcpy(&v, &b, 8);
    return v;
}
inline std::int32_t load_le_i32(const std::uint8_t *p) {
    const std::uint32_t b = load_le<std::uint32_t>(p);
    std::int32_t v;
    std::memcpy(&v, &b, 4);
    return v;
}
inline void store_le_f32(float v, std::uint8_t *p) {
    std::uint32_t b;
    std::memcpy(&b, &v, 4);
    store_le(b, p);
}
inline void store_le_f64(double v, std::uint8_t *p) {
    std::uint64_t b;
    std::memcpy(&b, &v, 8);
    store_le(b, p);
}

KISSM_DETAIL_END
