// SPDX-License-Identifier: MIT
// The C++ side of the LAZ decompressor: finds the LASzip VLR ("laszip encoded", record 22204: the
// compressor, chunking and item list) among the VLRs and drives src/io/laz_rs, turning its errors into
// Failure(Parse) with the file's name.
#include "io/laz_records.hpp"

#include "core/failure.hpp"
#include "core/little_endian.hpp"
#include "io/file_bytes.hpp"

#include <cstdio>
#include <cstring>

#ifdef KISSM_WITH_LAZ
// src/io/laz_rs/src/lib.rs
extern "C" {
struct KissmLazReader;
KissmLazReader *kissmlaz_open(const std::uint8_t *data, std::size_t len, std::uint64_t point_offset,
                              const std::uint8_t *vlr, std::size_t vlr_len, std::uint16_t record_length,
                              std::uint64_t count, char *msg, std::size_t cap);
int kissmlaz_read(KissmLazReader *reader, std::uint8_t *out, std::size_t n, char *msg, std::size_t cap);
void kissmlaz_close(KissmLazReader *reader);
}
#else
// Without the option nothing reaches these (las_reader.cpp refuses LAZ first); they keep one code path.
struct KissmLazReader;
static KissmLazReader *kissmlaz_open(const std::uint8_t *, std::size_t, std::uint64_t, const std::uint8_t *,
                                     std::size_t, std::uint16_t, std::uint64_t, char *msg, std::size_t cap) {
    std::snprintf(msg, cap, "LAZ support was not built in (configure kissm with -DKISSM_WITH_LAZ=ON)");
    return nullptr;
}
static int kissmlaz_read(KissmLazReader *, std::uint8_t *, std::size_t, char *, std::size_t) { return -1; }
static void kissmlaz_close(KissmLazReader *) {}
#endif

KISSM_DETAIL_BEGIN

namespace {

// A VLR header: reserved u16, user id char[16], record id u16, payload length u16, description char[32].
constexpr std::size_t kVlrHeader = 54;
constexpr std::uint16_t kLaszipRecordId = 22204;

std::string_view laszip_vlr(const std::string &path, std::string_view bytes, const LazLayout &l) {
    const auto *base = reinterpret_cast<const std::uint8_t *>(bytes.data());
    std::uint64_t pos = l.header_size;
    for (std::uint32_t i = 0; i < l.vlr_count; ++i) {
        if (pos + kVlrHeader > l.point_offset)
            fail_parse(path, "VLR " + std::to_string(i) + " of " + std::to_string(l.vlr_count) +
                                 " runs into the point data at byte " + std::to_string(l.point_offset));
        const std::uint8_t *v = base + pos;
        const std::uint64_t length = load_le<std::uint16_t>(v + 20);
        const std::uint64_t payload = pos + kVlrHeader;
        if (payload + length > l.point_offset)
            fail_parse(path, "VLR " + std::to_string(i) + "'s " + std::to_string(length) +
                                 "-byte payload runs into the point data");
        if (std::memcmp(v + 2, "laszip encoded\0\0", 16) == 0 && load_le<std::uint16_t>(v + 18) == kLaszipRecordId)
            return bytes.substr(static_cast<std::size_t>(payload), static_cast<std::size_t>(length));
        pos = payload + length;
    }
    fail_parse(path, "a compressed (LAZ) file without the LASzip VLR (\"laszip encoded\", record 22204)");
}

} // namespace

LazStream::LazStream(const std::string &path, std::string_view bytes, const LazLayout &l) : path_(path) {
    const std::string_view vlr = laszip_vlr(path, bytes, l);
    char msg[256] = {0};
    reader_ = kissmlaz_open(reinterpret_cast<const std::uint8_t *>(bytes.data()), bytes.size(), l.point_offset,
                            reinterpret_cast<const std::uint8_t *>(vlr.data()), vlr.size(), l.record_length, l.count,
                            msg, sizeof msg);
    if (!reader_) fail_parse(path, msg);
}

LazStream::~LazStream() { kissmlaz_close(static_cast<KissmLazReader *>(reader_)); }

void LazStream::read(std::uint8_t *out, std::size_t n) {
    char msg[256] = {0};
    if (kissmlaz_read(static_cast<KissmLazReader *>(reader_), out, n, msg, sizeof msg) != 0)
        fail_parse(path_, std::string(msg) + " (in the " + std::to_string(n) + " points after point " +
                              std::to_string(done_) + ")");
    done_ += n;
}

KISSM_DETAIL_END
