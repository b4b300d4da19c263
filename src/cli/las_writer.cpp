// SPDX-License-Identifier: MIT
#include "las_writer.hpp"

#include "core/little_endian.hpp"
#include "io/las_layout.hpp"
#include "kissm.h"
#include "pose_math.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <vector>

namespace kissm_cli {
namespace {

namespace las = kissm::detail::las;
using kissm::detail::load_le_f64;
using kissm::detail::store_le;
using kissm::detail::store_le_f64;

constexpr std::uint16_t kRecord0 = las::kMinRecord[0];

struct FileCloser {
    void operator()(std::FILE *f) const { std::fclose(f); }
};

bool has_extension(const std::string &path, const char *ext) {
    const std::size_t n = std::strlen(ext);
    if (path.size() < n) return false;
    for (std::size_t i = 0; i < n; ++i) {
        if (std::tolower(static_cast<unsigned char>(path[path.size() - n + i])) != ext[i]) return false;
    }
    return true;
}

// The point p moved by transform (or p itself).
void moved(const double *p, const double *transform, double q[3]) {
    if (transform) {
        kissm_pose::transform_point(transform, p, q);
    } else {
        q[0] = p[0];
        q[1] = p[1];
        q[2] = p[2];
    }
}

bool finite3(const double q[3]) { return std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]); }

} // namespace

bool is_las_path(const std::string &path) { return has_extension(path, ".las"); }
bool is_laz_path(const std::string &path) { return has_extension(path, ".laz"); }

bool read_las_frame(const std::string &path, LasFrame *frame) {
    std::ifstream in(path, std::ios::binary);
    unsigned char h[las::kHeader12] = {0};
    if (!in.read(reinterpret_cast<char *>(h), sizeof h) || std::memcmp(h, "LASF", 4) != 0) return false;
    LasFrame f;
    for (std::size_t k = 0; k < 3; ++k) {
        f.scale[k] = load_le_f64(h + las::kScale + 8 * k);
        f.offset[k] = load_le_f64(h + las::kOffset + 8 * k);
        if (!std::isfinite(f.scale[k]) || f.scale[k] == 0.0 || !std::isfinite(f.offset[k])) return false;
    }
    *frame = f;
    return true;
}

LasFrame las_frame_for(const double *xyz, size_t count, const double *transform) {
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
    double hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (size_t i = 0; i < count; ++i) {
        double q[3];
        moved(xyz + 3 * i, transform, q);
        if (!finite3(q)) continue;
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], q[k]);
            hi[k] = std::max(hi[k], q[k]);
        }
    }
    LasFrame f;
    for (int k = 0; k < 3; ++k) {
        if (!(lo[k] <= hi[k])) { // no finite point
            f.scale[k] = 1e-4;
            f.offset[k] = 0;
            continue;
        }
        f.offset[k] = std::round(lo[k] / 2 + hi[k] / 2);
        // Half the span (plus the rounding of the offset) in counts must stay below 2^31 with room to spare.
        const double half = std::max(hi[k] - f.offset[k], f.offset[k] - lo[k]);
        double scale = 1e-4;
        while (half / scale > 2e9) scale *= 10;
        f.scale[k] = scale;
    }
    return f;
}

// The record of point i in `frame`, or false when it is not finite (*fits false when it does not fit).
bool record_of(const double *xyz, size_t i, const double *transform, const LasFrame &frame, std::int32_t c[3],
               bool *fits) {
    double q[3];
    moved(xyz + 3 * i, transform, q);
    *fits = true;
    if (!finite3(q)) return false;
    for (std::size_t k = 0; k < 3; ++k) {
        const double counts = std::round((q[k] - frame.offset[k]) / frame.scale[k]);
        if (!(counts >= -2147483648.0 && counts <= 2147483647.0)) {
            *fits = false;
            return false;
        }
        c[k] = static_cast<std::int32_t>(counts);
    }
    return true;
}

bool write_las_xyz(const std::string &path, const double *xyz, size_t count, const double *transform,
                   const LasFrame &frame, size_t *written, std::string *error) {
    // Two passes: the header's count and bounds precede the points, and the records are written in chunks
    // rather than held (the arithmetic is the same both times).
    std::uint64_t n = 0;
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
    double hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (size_t i = 0; i < count; ++i) {
        std::int32_t c[3];
        bool fits = true;
        if (!record_of(xyz, i, transform, frame, c, &fits)) {
            if (fits) continue; // non-finite: left out
            double q[3];
            moved(xyz + 3 * i, transform, q);
            char buf[360];
            std::snprintf(buf, sizeof buf,
                          "cannot write '%s': point %zu (%.17g, %.17g, %.17g) is outside what LAS int32 "
                          "coordinates hold with this scale and offset (write .ply instead)",
                          path.c_str(), i, q[0], q[1], q[2]);
            *error = buf;
            return false;
        }
        for (std::size_t k = 0; k < 3; ++k) {
            // The header's bounds are those of the stored coordinates.
            const double stored = c[k] * frame.scale[k] + frame.offset[k];
            lo[k] = std::min(lo[k], stored);
            hi[k] = std::max(hi[k], stored);
        }
        ++n;
    }
    if (n > std::numeric_limits<std::uint32_t>::max()) {
        *error = "cannot write '" + path + "': LAS 1.2 holds at most 4294967295 points";
        return false;
    }
    if (n == 0) {
        for (int k = 0; k < 3; ++k) lo[k] = hi[k] = 0;
    }

    unsigned char h[las::kHeader12] = {0};
    std::memcpy(h, "LASF", 4);
    h[las::kVersionMajor] = 1;
    h[las::kVersionMinor] = 2;
    std::snprintf(reinterpret_cast<char *>(h + las::kSystemId), 32, "%s", "kissm");
    // snprintf's terminating NUL lands inside the 32 bytes; the rest of the field stays zero as the spec wants.
    char software[32];
    std::snprintf(software, sizeof software, "kissm %s", kissm_version_string());
    std::memcpy(h + las::kGeneratingSoftware, software, std::strlen(software));
    store_le(static_cast<std::uint16_t>(las::kHeader12), h + las::kHeaderSize);
    store_le(static_cast<std::uint32_t>(las::kHeader12), h + las::kOffsetToPoints);
    h[las::kFormatId] = 0;
    store_le(kRecord0, h + las::kRecordLength);
    store_le(static_cast<std::uint32_t>(n), h + las::kLegacyCount);
    store_le(static_cast<std::uint32_t>(n), h + las::kLegacyByReturn);
    for (std::size_t k = 0; k < 3; ++k) {
        store_le_f64(frame.scale[k], h + las::kScale + 8 * k);
        store_le_f64(frame.offset[k], h + las::kOffset + 8 * k);
        store_le_f64(hi[k], h + las::kBounds + 16 * k);
        store_le_f64(lo[k], h + las::kBounds + 16 * k + 8);
    }

    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
    const auto fail = [&](const char *what) {
        *error = std::string("cannot ") + what + " '" + path + "': " + std::strerror(errno);
        return false;
    };
    if (!file) return fail("create");
    if (std::fwrite(h, 1, sizeof h, file.get()) != sizeof h) return fail("write");
    constexpr size_t kChunk = 4096; // records per write
    std::vector<unsigned char> buffer(kChunk * kRecord0);
    size_t in_buffer = 0;
    for (size_t i = 0; i < count; ++i) {
        std::int32_t c[3];
        bool fits = true;
        if (!record_of(xyz, i, transform, frame, c, &fits)) continue;
        unsigned char *r = &buffer[in_buffer * kRecord0];
        std::memset(r, 0, kRecord0);
        for (std::size_t k = 0; k < 3; ++k) store_le(static_cast<std::uint32_t>(c[k]), r + 4 * k);
        r[las::kReturnsByte] = 0x09; // return 1 of 1
        if (++in_buffer == kChunk || i + 1 == count) {
            if (std::fwrite(buffer.data(), kRecord0, in_buffer, file.get()) != in_buffer) return fail("write");
            in_buffer = 0;
        }
    }
    if (in_buffer && std::fwrite(buffer.data(), kRecord0, in_buffer, file.get()) != in_buffer) return fail("write");
    std::FILE *raw = file.release();
    if (std::fclose(raw) != 0) return fail("write");
    *written = static_cast<size_t>(n);
    return true;
}

} // namespace kissm_cli
