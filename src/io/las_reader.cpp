// SPDX-License-Identifier: MIT
// ASPRS LAS 1.0-1.4, uncompressed: point data record formats 0-10, x y z only. Written from the ASPRS LAS 1.4
// (R15) specification. The public header gives the scale, offset, point count, record format and length and
// where the points start (the VLRs between the header and the points, and the EVLRs after them, are not
// read); each record starts with X, Y, Z as int32 and x = X * scale_x + offset_x is computed in double, so
// georeferenced coordinates (offsets of 1e6 m and more) keep every digit the file stores.
// Points flagged withheld are left out and counted (kissm_cloud_num_withheld).
// LAZ (the same header, the records LASzip-compressed) goes through io/laz_records.hpp when built in.
#include "core/detail_namespace.hpp"
#include "core/failure.hpp"
#include "core/little_endian.hpp"
#include "io/file_bytes.hpp"
#include "io/format_readers.hpp"
#include "io/las_layout.hpp"
#include "io/laz_records.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

KISSM_DETAIL_BEGIN

namespace {

using namespace las; // las_layout.hpp

std::string number_text(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

const std::uint8_t *at(std::string_view bytes, std::size_t offset) {
    return reinterpret_cast<const std::uint8_t *>(bytes.data()) + offset;
}

struct LasHeader {
    int minor = 0;
    std::uint64_t header_size = 0;
    std::uint64_t point_offset = 0;
    int format = 0;
    bool compressed = false; // LAZ
    std::uint32_t vlr_count = 0;
    std::uint64_t record_length = 0;
    std::uint64_t count = 0;
    double scale[3] = {1, 1, 1};
    double offset[3] = {0, 0, 0};
};

LasHeader parse_header(const std::string &path, std::string_view bytes) {
    if (bytes.size() < 4 || std::memcmp(bytes.data(), "LASF", 4) != 0)
        fail_parse(path, "not a LAS file (missing the \"LASF\" signature)");
    if (bytes.size() <= kVersionMinor)
        fail_parse(path, "truncated: the LAS header needs " + std::to_string(kHeader12) + " bytes, found " +
                             std::to_string(bytes.size()));
    LasHeader h;
    const int major = *at(bytes, kVersionMajor);
    h.minor = *at(bytes, kVersionMinor);
    if (major != 1 || h.minor > 4)
        fail_parse(path, "unsupported LAS version " + std::to_string(major) + "." + std::to_string(h.minor) +
                             " (versions 1.0 to 1.4 are read)");
    if (bytes.size() < kHeader12)
        fail_parse(path, "truncated: the LAS header needs " + std::to_string(kHeader12) + " bytes, found " +
                             std::to_string(bytes.size()));

    const std::size_t least = h.minor >= 4 ? kHeader14 : h.minor == 3 ? kHeader13 : kHeader12;
    h.header_size = load_le<std::uint16_t>(at(bytes, kHeaderSize));
    if (h.header_size < least)
        fail_parse(path, "LAS 1." + std::to_string(h.minor) + " header size " + std::to_string(h.header_size) +
                             " is below the " + std::to_string(least) + " bytes of its public header block");
    if (h.header_size > bytes.size())
        fail_parse(path, "truncated: the LAS header size is " + std::to_string(h.header_size) +
                             " bytes, the file has " + std::to_string(bytes.size()));

    h.point_offset = load_le<std::uint32_t>(at(bytes, kOffsetToPoints));
    if (h.point_offset < h.header_size)
        fail_parse(path, "the offset to point data " + std::to_string(h.point_offset) + " is inside the " +
                             std::to_string(h.header_size) + "-byte header");
    if (h.point_offset > bytes.size())
        fail_parse(path, "truncated: the offset to point data " + std::to_string(h.point_offset) +
                             " is beyond the file's " + std::to_string(bytes.size()) + " bytes");

    h.vlr_count = load_le<std::uint32_t>(at(bytes, kVlrCount));
    const int stored_id = *at(bytes, kFormatId);
    // LASzip marks compressed files by setting bit 7 (and, in old versions, bit 6) of the format id.
    h.compressed = (stored_id & 0xC0) != 0;
    if (h.compressed && !kLazBuiltIn)
        fail(ErrorKind::UnsupportedFormat,
             path + ": LAZ support was not built in (point data record format id " + std::to_string(stored_id) +
                 " has the compression bit set; configure kissm with -DKISSM_WITH_LAZ=ON, or convert the file to "
                 ".las)");
    const int id = stored_id & 0x3F;
    if (id > 10)
        fail_parse(path, "unknown LAS point data record format " + std::to_string(id) + " (0 to 10 are defined)");
    h.format = id;
    h.record_length = load_le<std::uint16_t>(at(bytes, kRecordLength));
    if (h.record_length < kMinRecord[id])
        fail_parse(path, "point data record length " + std::to_string(h.record_length) + " is below format " +
                             std::to_string(id) + "'s minimum of " + std::to_string(kMinRecord[id]) + " bytes");

    const std::uint64_t legacy = load_le<std::uint32_t>(at(bytes, kLegacyCount));
    h.count = legacy;
    if (h.minor >= 4) {
        // LAS 1.4 keeps the legacy 32-bit count only for formats 0-5 and files that fit it (else 0); the
        // 64-bit count is the authoritative one.
        const std::uint64_t wide = load_le<std::uint64_t>(at(bytes, kCount64));
        if (wide != 0 && legacy != 0 && wide != legacy)
            fail_parse(path, "the legacy point count " + std::to_string(legacy) + " and the 64-bit point count " +
                                 std::to_string(wide) + " disagree");
        if (wide != 0) h.count = wide;
    }

    static const char axis[3] = {'x', 'y', 'z'};
    for (int k = 0; k < 3; ++k) {
        h.scale[k] = load_le_f64(at(bytes, kScale + 8 * static_cast<std::size_t>(k)));
        h.offset[k] = load_le_f64(at(bytes, kOffset + 8 * static_cast<std::size_t>(k)));
        if (!std::isfinite(h.scale[k]) || h.scale[k] == 0.0)
            fail_parse(path, std::string("the ") + axis[k] + " scale factor is " + number_text(h.scale[k]) +
                                 " (it must be finite and non-zero)");
        if (!std::isfinite(h.offset[k]))
            fail_parse(path, std::string("the ") + axis[k] + " offset is " + number_text(h.offset[k]) +
                                 " (it must be finite)");
    }

    // Every record must be in the file before anything is allocated for it. (Compressed records have no
    // such bound: memory then follows the points decompressed, io/laz_records.hpp.)
    if (h.compressed) return h;
    const std::uint64_t left = bytes.size() - h.point_offset;
    std::uint64_t need = 0;
    if (!checked_mul(h.count, h.record_length, need) || need > left)
        fail_parse(path, "truncated: the header says " + std::to_string(h.count) + " points of " +
                             std::to_string(h.record_length) + " bytes, but " + std::to_string(left) +
                             " bytes follow the offset to point data");
    return h;
}

} // namespace

std::vector<double> parse_las(const std::string &path, std::string_view bytes, std::uint64_t *withheld) {
    const LasHeader h = parse_header(path, bytes);
    const std::size_t len = static_cast<std::size_t>(h.record_length);
    const std::uint8_t withheld_bit = h.format <= 5 ? 0x80 : 0x04;
    std::vector<double> xyz;
    std::uint64_t left_out = 0;
    const auto take = [&](const std::uint8_t *r) {
        if (r[kFlagsByte] & withheld_bit) {
            ++left_out;
            return;
        }
        for (std::size_t k = 0; k < 3; ++k) {
            const double raw = load_le_i32(r + 4 * k);
            xyz.push_back(raw * h.scale[k] + h.offset[k]);
        }
    };
    if (h.compressed) {
        // The header's count is not checked against the compressed bytes: reserve no more than the file
        // could hold at one byte a point, and grow with the points actually decompressed.
        xyz.reserve(3 * static_cast<std::size_t>(std::min<std::uint64_t>(h.count, bytes.size())));
        LazLayout l;
        l.header_size = h.header_size;
        l.vlr_count = h.vlr_count;
        l.point_offset = h.point_offset;
        l.record_length = static_cast<std::uint16_t>(h.record_length);
        l.count = h.count;
        for_each_laz_record(path, bytes, l, take);
        if (withheld) *withheld = left_out;
        return xyz;
    }
    const std::size_t n = static_cast<std::size_t>(h.count);
    xyz.reserve(3 * n);
    const std::uint8_t *r = at(bytes, static_cast<std::size_t>(h.point_offset));
    for (std::size_t i = 0; i < n; ++i, r += len) take(r);
    if (withheld) *withheld = left_out;
    return xyz;
}

KISSM_DETAIL_END
