// SPDX-License-Identifier: MIT
// Headerless little-endian float32 records: KITTI velodyne scans (x y z intensity) and bare x y z triples.
#include "core/detail_namespace.hpp"
#include "io/binary_scalar.hpp"
#include "io/file_bytes.hpp"
#include "io/format_readers.hpp"

#include <string>
#include <vector>

KISSM_DETAIL_BEGIN

namespace {

// The other headerless layout, named as the C API and the CLI (--format) name it, for a size that fits it.
struct RawLayout {
    std::size_t floats;
    const char *name;
};
constexpr RawLayout kRawLayouts[] = {{4, "KISSM_FORMAT_KITTI_BIN, --format kitti_bin (float32 x y z intensity)"},
                                     {3, "KISSM_FORMAT_BIN_XYZ, --format bin_xyz (float32 x y z)"}};

std::vector<double> read_float_records(const std::string &path, std::string_view bytes, std::size_t floats,
                                       const char *layout) {
    const std::size_t record = 4 * floats;
    // With no header, the size is the only integrity check there is; a size that fits the other layout says
    // which one the file more likely is (a KITTI-derived cloud stored without intensity, say).
    if (bytes.size() % record != 0) {
        std::string hint;
        for (const RawLayout &other : kRawLayouts) {
            if (other.floats != floats && bytes.size() % (4 * other.floats) == 0)
                hint = "; it is a multiple of " + std::to_string(4 * other.floats) + ": read it as " + other.name;
        }
        fail_parse(path, "size " + std::to_string(bytes.size()) + " bytes is not a multiple of " +
                             std::to_string(record) + " (" + layout + " records): truncated or not this format" + hint);
    }
    const std::size_t n = bytes.size() / record;
    const bool swap = !host_is_little_endian();
    std::vector<double> xyz(n * 3);
    const char *r = bytes.data();
    for (std::size_t i = 0; i < n; ++i, r += record) {
        xyz[3 * i + 0] = load_scalar(r, Scalar::F32, swap);
        xyz[3 * i + 1] = load_scalar(r + 4, Scalar::F32, swap);
        xyz[3 * i + 2] = load_scalar(r + 8, Scalar::F32, swap);
    }
    return xyz;
}

} // namespace

std::vector<double> parse_kitti_bin(const std::string &path, std::string_view bytes) {
    return read_float_records(path, bytes, 4, "float32 x y z intensity");
}

std::vector<double> parse_bin_xyz(const std::string &path, std::string_view bytes) {
    return read_float_records(path, bytes, 3, "float32 x y z");
}

KISSM_DETAIL_END
