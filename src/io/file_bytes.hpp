// SPDX-License-Identifier: MIT
// Whole-file loading and the error helpers every reader shares. Readers parse from one in-memory buffer:
// a single read is faster than streaming and lets every header count be checked against the real size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// The file's bytes. Throws Failure(Io) naming the path and the OS reason when it cannot be opened or read
// (missing, a directory, no permission, read error).
std::string read_file_bytes(const std::string &path);

// Failure(Parse) with "<path>: <what>".
[[noreturn]] void fail_parse(const std::string &path, const std::string &what);

// a * b, or false when it does not fit in 64 bits.
inline bool checked_mul(std::uint64_t a, std::uint64_t b, std::uint64_t &out) {
    if (a != 0 && b > UINT64_MAX / a) return false;
    out = a * b;
    return true;
}

inline bool checked_add(std::uint64_t a, std::uint64_t b, std::uint64_t &out) {
    if (b > UINT64_MAX - a) return false;
    out = a + b;
    return true;
}

KISSM_DETAIL_END
