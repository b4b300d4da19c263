// SPDX-License-Identifier: MIT
// Fixed-size numeric fields of binary point formats, loaded from unaligned bytes of either byte order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/detail_namespace.hpp"

KISSM_DETAIL_BEGIN

enum class Scalar { I8, U8, I16, U16, I32, U32, I64, U64, F32, F64 };

inline std::size_t scalar_size(Scalar s) {
    switch (s) {
    case Scalar::I8:
    case Scalar::U8: return 1;
    case Scalar::I16:
    case Scalar::U16: return 2;
    case Scalar::I32:
    case Scalar::U32:
    case Scalar::F32: return 4;
    case Scalar::I64:
    case Scalar::U64:
    case Scalar::F64: return 8;
    }
    return 1;
}

inline bool scalar_is_integer(Scalar s) { return s != Scalar::F32 && s != Scalar::F64; }

inline bool host_is_little_endian() {
    const std::uint16_t probe = 1;
    unsigned char first = 0;
    std::memcpy(&first, &probe, 1);
    return first == 1;
}

// Copies n <= 8 bytes from p into b, reversing them when swap (the file's byte order is not the host's).
inline void load_bytes(const char *p, std::size_t n, bool swap, unsigned char *b) {
    std::memcpy(b, p, n);
    if (swap) {
        for (std::size_t i = 0; i < n / 2; ++i) {
            const unsigned char t = b[i];
            b[i] = b[n - 1 - i];
            b[n - 1 - i] = t;
        }
    }
}

// Reads one value of type s from p (scalar_size(s) readable bytes; the caller has bounds-checked them).
inline double load_scalar(const char *p, Scalar s, bool swap) {
    unsigned char b[8];
    load_bytes(p, scalar_size(s), swap, b);
    switch (s) {
    case Scalar::I8: {
        std::int8_t v;
        std::memcpy(&v, b, 1);
        return v;
    }
    case Scalar::U8: {
        std::uint8_t v;
        std::memcpy(&v, b, 1);
        return v;
    }
    case Scalar::I16: {
        std::int16_t v;
        std::memcpy(&v, b, 2);
        return v;
    }
    case Scalar::U16: {
        std::uint16_t v;
        std::memcpy(&v, b, 2);
        return v;
    }
    case Scalar::I32: {
        std::int32_t v;
        std::memcpy(&v, b, 4);
        return v;
    }
    case Scalar::U32: {
        std::uint32_t v;
        std::memcpy(&v, b, 4);
        return v;
    }
    case Scalar::I64: {
        std::int64_t v;
        std::memcpy(&v, b, 8);
        return static_cast<double>(v);
    }
    case Scalar::U64: {
        std::uint64_t v;
        std::memcpy(&v, b, 8);
        return static_cast<double>(v);
    }
    case Scalar::F32: {
        float v;
        std::memcpy(&v, b, 4);
        return v;
    }
    case Scalar::F64: {
        double v;
        std::memcpy(&v, b, 8);
        return v;
    }
    }
    return 0.0;
}

// An integer field (a PLY list length) as a count; false for a negative or non-integral-typed value.
inline bool load_count(const char *p, Scalar s, bool swap, std::uint64_t &out) {
    if (!scalar_is_integer(s)) return false;
    if (s == Scalar::U64 || s == Scalar::I64) {
        unsigned char b[8];
        load_bytes(p, 8, swap, b);
        std::memcpy(&out, b, 8);
        return s == Scalar::U64 || out < (std::uint64_t(1) << 63);
    }
    // The narrower integer types are exact in a double.
    const double v = load_scalar(p, s, swap);
    if (v < 0) return false;
    out = static_cast<std::uint64_t>(v);
    return true;
}

KISSM_DETAIL_END
