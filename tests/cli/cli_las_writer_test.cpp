// SPDX-License-Identifier: MIT
// The CLI's LAS writer (src/cli/las_writer.cpp), read back with the library's reader (kissm_read_points):
// the header's fields byte by byte, every point on its frame's grid (within half a scale step of R p + t,
// and exactly the value the grid gives), a georeferenced target's frame kept, the frame picked for a cloud
// without one, non-finite points left out, and points that do not fit refused. laspy reads the same files in
// bindings/python/tests/test_las.py.
#include "harness.h"

#include "cli_test_util.hpp"
#include "kissm.h"
#include "las_writer.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

using namespace kissm_cli;

namespace {

std::string scratch(const std::string &name) {
    const auto dir = std::filesystem::temp_directory_path() / "kissm_las_writer_test";
    std::filesystem::create_directories(dir);
    return (dir / name).string();
}

template <typename T>
T field(const std::string &bytes, std::size_t at) {
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof v); // the test host is little-endian (x86_64, aarch64)
    return v;
}

std::vector<double> read_back(const std::string &path) {
    kissm_cloud *cloud = nullptr;
    const int32_t status = kissm_read_points(path.c_str(), KISSM_FORMAT_AUTO, &cloud);
    CHECK_EQ_INT(status, KISSM_OK);
    std::vector<double> xyz;
    if (status == KISSM_OK) {
        const double *p = kissm_cloud_data(cloud);
        xyz.assign(p, p + 3 * kissm_cloud_count(cloud));
    }
    kissm_cloud_destroy(cloud);
    return xyz;
}

// A street-like cloud in a UTM frame, seeded.
std::vector<double> cloud(std::size_t n, double east, double north) {
    std::vector<double> xyz;
    std::uint64_t s = 99;
    auto uniform = [&s] {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(s >> 11) / 9007199254740992.0;
    };
    for (std::size_t i = 0; i < n; ++i) {
        xyz.push_back(east + 80 * uniform() - 40);
        xyz.push_back(north + 80 * uniform() - 40);
        xyz.push_back(120 + 12 * uniform());
    }
    return xyz;
}

void test_header_and_grid() {
    // A scan in its sensor frame moved into a georeferenced target's frame.
    const std::vector<double> xyz = cloud(5000, 0, 0);
    const double T[16] = {0.8, -0.6, 0, 500012.5, 0.6, 0.8, 0, 4499996.75, 0, 0, 1, -20.5, 0, 0, 0, 1};
    LasFrame frame;
    frame.scale[0] = frame.scale[1] = frame.scale[2] = 0.001;
    frame.offset[0] = 500000;
    frame.offset[1] = 4500000;
    frame.offset[2] = 100;
    const std::string path = scratch("aligned.las");
    size_t written = 0;
    std::string error;
    REQUIRE(write_las_xyz(path, xyz.data(), 5000, T, frame, &written, &error));
    CHECK_EQ_INT(written, 5000);

    const std::string bytes = cli_test::read_file(path);
    REQUIRE(bytes.size() == 227 + 20 * 5000);
    CHECK(bytes.compare(0, 4, "LASF") == 0);
    CHECK_EQ_INT(bytes[24], 1);
    CHECK_EQ_INT(bytes[25], 2);
    CHECK_EQ_INT(field<std::uint16_t>(bytes, 94), 227);
    CHECK_EQ_INT(field<std::uint32_t>(bytes, 96), 227);
    CHECK_EQ_INT(field<std::uint32_t>(bytes, 100), 0);
    CHECK_EQ_INT(bytes[104], 0);
    CHECK_EQ_INT(field<std::uint16_t>(bytes, 105), 20);
    CHECK_EQ_INT(field<std::uint32_t>(bytes, 107), 5000);
    CHECK_EQ_INT(field<std::uint32_t>(bytes, 111), 5000);
    CHECK(field<double>(bytes, 131) == 0.001 && field<double>(bytes, 155) == 500000 &&
          field<double>(bytes, 171) == 100);
    CHECK(std::string(bytes.data() + 58).rfind("kissm ", 0) == 0);

    const std::vector<double> back = read_back(path);
    REQUIRE(back.size() == xyz.size());
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    int off_grid = 0, far = 0;
    for (std::size_t i = 0; i < 5000; ++i) {
        const double *p = &xyz[3 * i];
        for (std::size_t k = 0; k < 3; ++k) {
            const double q = T[4 * k] * p[0] + T[4 * k + 1] * p[1] + T[4 * k + 2] * p[2] + T[4 * k + 3];
            const double grid = std::round((q - frame.offset[k]) / 0.001) * 0.001 + frame.offset[k];
            const double got = back[3 * i + k];
            off_grid += got != grid;
            far += std::fabs(got - q) > 0.0005 + 1e-9;
            lo[k] = std::min(lo[k], got);
            hi[k] = std::max(hi[k], got);
        }
        CHECK_EQ_INT(bytes[227 + 20 * i + 14], 0x09); // return 1 of 1
        CHECK_EQ_INT(bytes[227 + 20 * i + 15], 0);    // not withheld
    }
    CHECK_EQ_INT(off_grid, 0);
    CHECK_EQ_INT(far, 0);
    for (std::size_t k = 0; k < 3; ++k) {
        CHECK(field<double>(bytes, 179 + 16 * k) == hi[k]);
        CHECK(field<double>(bytes, 187 + 16 * k) == lo[k]);
    }

    // That file as a target: its frame is read back.
    LasFrame read;
    REQUIRE(read_las_frame(path, &read));
    for (int k = 0; k < 3; ++k) CHECK(read.scale[k] == frame.scale[k] && read.offset[k] == frame.offset[k]);
    LasFrame none;
    CHECK(!read_las_frame(scratch("missing.las"), &none));
}

void test_picked_frame() {
    const std::vector<double> xyz = cloud(100, 1000000.5, -2000000.25);
    const LasFrame f = las_frame_for(xyz.data(), 100, nullptr);
    CHECK(f.scale[0] == 1e-4 && f.scale[1] == 1e-4 && f.scale[2] == 1e-4);
    CHECK(std::fabs(f.offset[0] - 1000000) <= 40 && f.offset[0] == std::round(f.offset[0]));
    CHECK(std::fabs(f.offset[1] + 2000000) <= 40 && f.offset[1] == std::round(f.offset[1]));
    // A span of 1000 km does not fit 0.1 mm steps in int32: the scale grows by tens until it does.
    const double wide[6] = {0, 0, 0, 1e6, 0, 0};
    const LasFrame g = las_frame_for(wide, 2, nullptr);
    CHECK(g.scale[0] == 1e-3 && g.offset[0] == 500000);
    const std::string path = scratch("picked.las");
    size_t written = 0;
    std::string error;
    REQUIRE(write_las_xyz(path, wide, 2, nullptr, g, &written, &error));
    const std::vector<double> back = read_back(path);
    REQUIRE(back.size() == 6);
    CHECK(back[0] == 0 && back[3] == 1e6);
}

void test_nonfinite_and_range() {
    const double xyz[9] = {1, 2, 3, NAN, 0, 0, 4, 5, INFINITY};
    const LasFrame f = las_frame_for(xyz, 3, nullptr);
    CHECK(f.offset[0] == 1 && f.offset[2] == 3); // only the finite point counts
    size_t written = 0;
    std::string error;
    const std::string path = scratch("finite.las");
    REQUIRE(write_las_xyz(path, xyz, 3, nullptr, f, &written, &error));
    CHECK_EQ_INT(written, 1);
    const std::vector<double> back = read_back(path);
    REQUIRE(back.size() == 3);
    CHECK(back[0] == 1 && back[1] == 2 && back[2] == 3);

    // A point 1e6 m away from a 0.1 mm frame's offset does not fit int32 counts.
    const double far[6] = {0, 0, 0, 1e6, 0, 0};
    LasFrame fine;
    fine.scale[0] = fine.scale[1] = fine.scale[2] = 1e-4;
    CHECK(!write_las_xyz(scratch("far.las"), far, 2, nullptr, fine, &written, &error));
    CHECK(error.find("point 1 (1000000, 0, 0) is outside what LAS int32 coordinates hold") != std::string::npos);
    CHECK(!write_las_xyz(scratch("no/such/dir.las"), xyz, 3, nullptr, f, &written, &error));
    CHECK(error.find("cannot create") != std::string::npos);
    CHECK(is_las_path("a.LAS") && is_las_path("b.las") && !is_las_path("c.ply") && !is_las_path("las"));
    CHECK(is_laz_path("d.Laz") && !is_laz_path("e.las"));
}

} // namespace

int main() {
    RUN_TEST(test_header_and_grid);
    RUN_TEST(test_picked_frame);
    RUN_TEST(test_nonfinite_and_range);
    std::filesystem::remove_all(std::filesystem::temp_directory_path() / "kissm_las_writer_test");
    return TEST_SUMMARY();
}
