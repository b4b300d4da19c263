// SPDX-License-Identifier: MIT
// 125K-point files in every format: exact values, and the read time printed (a single whole-file read and
// a parse from memory should take a few milliseconds for the binary formats).
#include "io_test_util.hpp"

#include <chrono>

using namespace iotest;

namespace {

constexpr std::size_t kN = 125000;

// Deterministic float-valued coordinates with varied magnitudes and signs.
std::vector<double> make_points() {
    std::vector<double> v(3 * kN);
    std::uint32_t s = 12345;
    for (double &x : v) {
        s = s * 1664525u + 1013904223u;
        x = static_cast<float>((static_cast<double>(s >> 8) / 16777216.0 - 0.5) * 200.0);
    }
    return v;
}

std::string text_rows(const std::vector<double> &v, const char *extra) {
    std::string out;
    out.reserve(v.size() * 26);
    char line[128];
    for (std::size_t i = 0; i < v.size(); i += 3) {
        snprintf(line, sizeof line, "%.17g %.17g %.17g%s\n", v[i], v[i + 1], v[i + 2], extra);
        out += line;
    }
    return out;
}

void timed(const char *what, const std::string &path, FileFormat f, const std::vector<double> &expected,
           double limit_ms, int line) {
    const auto t0 = std::chrono::steady_clock::now();
    iotest::expect_points(__FILE__, line, path, f, expected);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    printf("  %-24s %8.2f ms (%zu points)\n", what, ms, expected.size() / 3);
    // Generous: sanitizer and debug builds are slow; this only catches quadratic behaviour.
    CHECK_MSG(ms < limit_ms, "%s took %.1f ms", what, ms);
}

void test_large() {
    TempDir dir;
    const std::vector<double> v = make_points();
    const std::string nstr = std::to_string(kN);

    Bytes kitti, raw, ply_le, ply_be, pcd_bin, npy_f4;
    for (std::size_t i = 0; i < v.size(); ++i) {
        kitti.put<float>(static_cast<float>(v[i]));
        raw.put<float>(static_cast<float>(v[i]));
        if (i % 3 == 2) kitti.put<float>(1.0f);
    }
    const std::string ply_header = "element vertex " + nstr +
                                   "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\n"
                                   "end_header\n";
    ply_le.text("ply\nformat binary_little_endian 1.0\n" + ply_header);
    ply_be.text("ply\nformat binary_big_endian 1.0\n" + ply_header);
    pcd_bin.text("VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH " + nstr +
                 "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + nstr + "\nDATA binary\n");
    for (std::size_t i = 0; i < v.size(); i += 3) {
        for (int a = 0; a < 3; ++a) {
            ply_le.put<float>(static_cast<float>(v[i + a]));
            ply_be.put<float>(static_cast<float>(v[i + a]), true);
            pcd_bin.put<float>(static_cast<float>(v[i + a]));
        }
        ply_le.put<float>(2.0f);
        ply_be.put<float>(2.0f, true);
        pcd_bin.put<float>(2.0f);
    }
    std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + nstr + ", 3), }";
    while ((10 + header.size() + 1) % 64 != 0) header += ' ';
    header += '\n';
    Bytes npy;
    npy.text("\x93NUMPY")
        .put<std::uint8_t>(1)
        .put<std::uint8_t>(0)
        .put<std::uint16_t>(static_cast<std::uint16_t>(header.size()));
    npy.text(header);
    for (double d : v) npy.put<double>(d);

    timed("kitti .bin", dir.write("k.bin", kitti.s), FileFormat::Auto, v, 2000, __LINE__);
    timed("raw xyz float32", dir.write("r.raw", raw.s), FileFormat::BinXyz, v, 2000, __LINE__);
    timed("binary LE PLY", dir.write("le.ply", ply_le.s), FileFormat::Auto, v, 2000, __LINE__);
    timed("binary BE PLY", dir.write("be.ply", ply_be.s), FileFormat::Auto, v, 2000, __LINE__);
    timed("binary PCD", dir.write("b.pcd", pcd_bin.s), FileFormat::Auto, v, 2000, __LINE__);
    timed(".npy float64", dir.write("n.npy", npy.s), FileFormat::Auto, v, 2000, __LINE__);
    const std::string rows = text_rows(v, " 0.5");
    timed("ascii PLY", dir.write("a.ply", "ply\nformat ascii 1.0\n" + ply_header + rows), FileFormat::Auto, v, 5000,
          __LINE__);
    timed("ascii PCD",
          dir.write("a.pcd", "FIELDS x y z i\nSIZE 4 4 4 4\nTYPE F F F F\nPOINTS " + nstr + "\nDATA ascii\n" + rows),
          FileFormat::Auto, v, 5000, __LINE__);
    timed("xyz text", dir.write("a.xyz", rows), FileFormat::Auto, v, 5000, __LINE__);
}

} // namespace

int main() {
    RUN_TEST(test_large);
    return TEST_SUMMARY();
}
