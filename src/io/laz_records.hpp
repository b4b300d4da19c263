// SPDX-License-Identifier: MIT
// LAZ (LASzip-compressed LAS) point records, decompressed by the `laz` crate through kissm's own C ABI
// (src/io/laz_rs), linked in only with KISSM_WITH_LAZ=ON (src/io/laz.cmake). las_reader.cpp parses the
// public header either way and calls this for compressed files.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// Whether this build decompresses LAZ (the CMake option KISSM_WITH_LAZ). Without it every compressed file
// is refused before anything else is read, with a message that says how to build it in.
#ifdef KISSM_WITH_LAZ
constexpr bool kLazBuiltIn = true;
#else
constexpr bool kLazBuiltIn = false;
#endif

// Where the compressed records are and what they hold, from the LAS public header.
struct LazLayout {
    std::uint64_t header_size = 0;  // the VLRs follow the public header
    std::uint32_t vlr_count = 0;    // number of VLRs
    std::uint64_t point_offset = 0; // offset to point data: the chunk table offset, then the chunks
    std::uint16_t record_length = 0;
    std::uint64_t count = 0;
};

// Hands every decompressed record to take(record) in file order. Throws Failure(Parse) naming the file for
// a missing or malformed LASzip VLR and for corrupt or truncated compressed data.
template <class Take>
void for_each_laz_record(const std::string &path, std::string_view bytes, const LazLayout &l, Take take);

// The non-template part: the decompressor over the file's bytes (the LASzip VLR found and checked), read a
// batch of records at a time. Errors are Failure(Parse) naming the file.
class LazStream {
public:
    LazStream(const std::string &path, std::string_view bytes, const LazLayout &l);
    ~LazStream();
    LazStream(const LazStream &) = delete;
    LazStream &operator=(const LazStream &) = delete;
    // Decompresses the next n records into out (n * record_length bytes).
    void read(std::uint8_t *out, std::size_t n);

private:
    const std::string &path_;
    void *reader_ = nullptr;
    std::uint64_t done_ = 0;
};

template <class Take>
void for_each_laz_record(const std::string &path, std::string_view bytes, const LazLayout &l, Take take) {
    LazStream stream(path, bytes, l);
    // About a megabyte of records at a time: memory follows the points kept, not the header's count.
    const std::size_t batch = static_cast<std::size_t>(
        std::max<std::uint64_t>(1, std::min<std::uint64_t>(l.count, (std::size_t{1} << 20) / l.record_length)));
    std::string buffer(batch * l.record_length, '\0');
    auto *out = reinterpret_cast<std::uint8_t *>(&buffer[0]);
    for (std::uint64_t left = l.count; left > 0;) {
        const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, batch));
        stream.read(out, n);
        for (std::size_t i = 0; i < n; ++i) take(out + i * l.record_length);
        left -= n;
    }
}

KISSM_DETAIL_END
