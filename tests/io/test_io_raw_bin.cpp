// SPDX-License-Identifier: MIT
// Headerless float32 readers: KITTI .bin (x y z intensity) and BinXyz (x y z).
#include "io_test_util.hpp"

#include <limits>

using namespace iotest;

namespace {

const std::vector<double> kPoints = {1.5, -2.25, 1e-3f, 0, -0.0, 3.4e38f, -7, 8, 9};

std::string records(bool intensity, const std::vector<double> &xyz) {
    Bytes b;
    for (std::size_t i = 0; i < xyz.size(); ++i) {
        b.put<float>(static_cast<float>(xyz[i]));
        if (intensity && i % 3 == 2) b.put<float>(0.75f);
    }
    return b.s;
}

void test_exact() {
    TempDir dir;
    EXPECT_POINTS(dir.write("k.bin", records(true, kPoints)), FileFormat::KittiBin, kPoints);
    EXPECT_POINTS(dir.write("k.bin", records(true, kPoints)), FileFormat::Auto, kPoints);
    EXPECT_POINTS(dir.write("p.raw", records(false, kPoints)), FileFormat::BinXyz, kPoints);
    // Non-finite values are returned as they are.
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    EXPECT_POINTS(dir.write("nf.bin", records(true, {nan, inf, -inf})), FileFormat::KittiBin, {nan, inf, -inf});
    // 48 bytes fit both layouts; .bin means KITTI (4 floats per point).
    EXPECT_POINTS(dir.write("both.bin", records(false, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12})), FileFormat::Auto,
                  {1, 2, 3, 5, 6, 7, 9, 10, 11});
}

void test_sizes() {
    TempDir dir;
    const std::string k = records(true, kPoints);
    EXPECT_FAILURE(dir.write("k.bin", k + "x"), FileFormat::KittiBin, ErrorKind::Parse,
                   "size 49 bytes is not a multiple of 16");
    EXPECT_FAILURE(dir.write("k.bin", k.substr(0, 12)), FileFormat::KittiBin, ErrorKind::Parse, "not a multiple of 16");
    const std::string x = records(false, kPoints);
    EXPECT_FAILURE(dir.write("p.raw", x.substr(0, 35)), FileFormat::BinXyz, ErrorKind::Parse,
                   "size 35 bytes is not a multiple of 12");
    // A size that fits the other layout names it (issue 36): x y z triples read as KITTI, and the reverse.
    EXPECT_FAILURE(dir.write("xyz.bin", x.substr(0, 36)), FileFormat::KittiBin, ErrorKind::Parse,
                   "size 36 bytes is not a multiple of 16 (float32 x y z intensity records): truncated or not this "
                   "format; it is a multiple of 12: read it as KISSM_FORMAT_BIN_XYZ, --format bin_xyz (float32 x y z)");
    EXPECT_FAILURE(dir.write("xyzi.raw", k.substr(0, 32)), FileFormat::BinXyz, ErrorKind::Parse,
                   "is not a multiple of 12 (float32 x y z records): truncated or not this format; it is a multiple of "
                   "16: read it as KISSM_FORMAT_KITTI_BIN, --format kitti_bin");
    CHECK_EVERY_CUT(dir, "cut.bin", k, FileFormat::KittiBin, kPoints, CutRule::ParseOrPrefix);
    CHECK_EVERY_CUT(dir, "cut.raw", x, FileFormat::BinXyz, kPoints, CutRule::ParseOrPrefix);
    // A prefix holding exactly two records reads as those two points.
    EXPECT_POINTS(dir.write("two.bin", k.substr(0, 32)), FileFormat::KittiBin,
                  std::vector<double>(kPoints.begin(), kPoints.begin() + 6));
}

void test_io_errors() {
    TempDir dir;
    for (FileFormat f : {FileFormat::KittiBin, FileFormat::BinXyz}) {
        EXPECT_FAILURE(dir.file("missing.bin"), f, ErrorKind::Io, "No such file or directory");
        std::filesystem::create_directory(dir.file("adir.bin"));
        EXPECT_FAILURE(dir.file("adir.bin"), f, ErrorKind::Io, "Is a directory");
        EXPECT_FAILURE(dir.write("empty.bin", ""), f, ErrorKind::Parse, "the file is empty");
    }
}

} // namespace

int main() {
    RUN_TEST(test_exact);
    RUN_TEST(test_sizes);
    RUN_TEST(test_io_errors);
    return TEST_SUMMARY();
}
