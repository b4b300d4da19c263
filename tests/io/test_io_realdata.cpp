// SPDX-License-Identifier: MIT
// The real scans in $KISSM_DATA_DIR (../shared/data): point counts, finiteness, a known first point. Skipped
// with a message when the directory is absent.
#include "io_test_util.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>

using namespace iotest;

namespace {

std::string data_dir() {
    const char *d = std::getenv("KISSM_DATA_DIR");
    if (!d || !*d) return "";
    std::error_code ec;
    return std::filesystem::is_directory(d, ec) ? std::string(d) : std::string();
}

void check_file(const std::string &dir, const char *relative, FileFormat format, std::size_t expected_points,
                int line) {
    const std::string path = dir + "/" + relative;
    const auto t0 = std::chrono::steady_clock::now();
    const Outcome o = try_read(path, format);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!o.ok) {
        iotest::record(false, __FILE__, line, std::string("cannot read ") + relative + ": " + o.message);
        return;
    }
    iotest::record(o.points.size() == 3 * expected_points, __FILE__, line,
                   std::string(relative) + ": " + std::to_string(o.points.size() / 3) + " points, expected " +
                       std::to_string(expected_points));
    std::size_t nonfinite = 0;
    for (double v : o.points) nonfinite += std::isfinite(v) ? 0 : 1;
    iotest::record(nonfinite == 0, __FILE__, line,
                   std::string(relative) + ": " + std::to_string(nonfinite) + " non-finite values");
    printf("  %-48s %7zu points %8.2f ms\n", relative, o.points.size() / 3, ms);
}

void test_real_files() {
    const std::string dir = data_dir();
    if (dir.empty()) {
        printf("KISSM_DATA_DIR is not set to an existing directory: skipping the real-file checks\n");
        return;
    }
    check_file(dir, "stanford_bunny_scans/bun000.ply", FileFormat::Auto, 40256, __LINE__);
    check_file(dir, "stanford_bunny_scans/bun045.ply", FileFormat::Ply, 40097, __LINE__);
    check_file(dir, "stanford_bunny_scans/bun090.ply", FileFormat::Auto, 30379, __LINE__);
    check_file(dir, "stanford_bunny_scans/bun315.ply", FileFormat::Auto, 35336, __LINE__);
    // Three "bye" lines before the first element (_0, _48, _72, _96), and a plain header (_24).
    check_file(dir, "stanford_happy_stand_scans/happyStandRight_0.ply", FileFormat::Auto, 78056, __LINE__);
    check_file(dir, "stanford_happy_stand_scans/happyStandRight_48.ply", FileFormat::Ply, 69158, __LINE__);
    check_file(dir, "stanford_happy_stand_scans/happyStandRight_24.ply", FileFormat::Auto, 75582, __LINE__);
    check_file(dir, "small_gicp_lidar/target.ply", FileFormat::Auto, 69088, __LINE__);
    check_file(dir, "small_gicp_lidar/source.ply", FileFormat::Auto, 69792, __LINE__);
    check_file(dir, "kitti_demo_scans_unverified/000000.bin", FileFormat::KittiBin, 124668, __LINE__);
    check_file(dir, "kitti_demo_scans_unverified/000015.bin", FileFormat::Auto, 121023, __LINE__);
    check_file(dir, "kitti07_keyframes_gtsam_points/000000/points.bin", FileFormat::BinXyz, 21562, __LINE__);
    check_file(dir, "kitti07_keyframes_gtsam_points/000001/points.bin", FileFormat::BinXyz, 24703, __LINE__);
    check_file(dir, "3dmatch_geotransformer_demo/ref.npy", FileFormat::Auto, 18977, __LINE__);
    check_file(dir, "3dmatch_geotransformer_demo/src.npy", FileFormat::Npy, 15953, __LINE__);

    // The first vertex line of bun000.ply is "-0.06325 0.0359793 0.0420873 ".
    const Outcome bunny = try_read(dir + "/stanford_bunny_scans/bun000.ply", FileFormat::Auto);
    if (bunny.ok && bunny.points.size() >= 3) {
        CHECK(bunny.points[0] == -0.06325);
        CHECK(bunny.points[1] == 0.0359793);
        CHECK(bunny.points[2] == 0.0420873);
    }
    // Without an explicit format, points.bin is taken as KITTI (x y z intensity): 21562 * 12 bytes is not a
    // multiple of 16, which is what tells the caller to pass KISSM_FORMAT_BIN_XYZ.
    EXPECT_FAILURE(dir + "/kitti07_keyframes_gtsam_points/000000/points.bin", FileFormat::Auto, ErrorKind::Parse,
                   "not a multiple of 16");
}

} // namespace

int main() {
    RUN_TEST(test_real_files);
    return TEST_SUMMARY();
}
