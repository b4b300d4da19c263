// SPDX-License-Identifier: MIT
// Unit tests of the command-line tool's own pieces: checksums, the deflate/PNG encoder, the JSON writer,
// the PLY writer, the transform file, the argument parsers, the result's JSON and summary, the top view and
// its coarse/refined detail, the demo scene simulator, and batch's pairs file, results lines, resume scan and
// progress line.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <kissm.h>

#include "batch/batch_pairs.hpp"
#include "batch/batch_progress.hpp"
#include "batch/batch_run.hpp"
#include "cli_args.hpp"
#include "cli_result_check.hpp"
#include "cli_test_util.hpp"
#include "demo_scene.hpp"
#include "harness.h"
#include "json_writer.hpp"
#include "picture/alignment_figure.hpp"
#include "picture/png_writer.hpp"
#include "picture/raster.hpp"
#include "picture/top_view.hpp"
#include "ply_writer.hpp"
#include "pose_math.hpp"
#include "report.hpp"
#include "rng.hpp"
#include "transform_file.hpp"

using namespace kissm_cli;
using namespace kissm_pose;
using namespace kissm_sim;

namespace {

std::string temp_path(const std::string &name) {
    return (std::filesystem::temp_directory_path() / ("kissm_cli_units_" + name)).string();
}

const uint8_t *bytes_of(const char *s) { return reinterpret_cast<const uint8_t *>(s); }

void test_checksums() {
    CHECK_EQ_INT(crc32(bytes_of("123456789"), 9), 0xCBF43926u); // the standard check value
    CHECK_EQ_INT(crc32(bytes_of(""), 0), 0u);
    CHECK_EQ_INT(crc32(bytes_of("IEND"), 4), 0xAE426082u); // every PNG's last CRC
    const uint32_t split = crc32_update(crc32(bytes_of("1234"), 4), bytes_of("56789"), 5);
    CHECK_EQ_INT(split, 0xCBF43926u);
    CHECK_EQ_INT(adler32_update(1u, bytes_of("Wikipedia"), 9), 0x11E60398u);
    CHECK_EQ_INT(adler32_update(1u, bytes_of(""), 0), 1u);
    std::vector<uint8_t> big(100000, 0xFF); // long enough to need the modular reduction
    CHECK_EQ_INT(adler32_update(1u, big.data(), big.size()), cli_test::test_adler32(big));
}

void check_zlib_roundtrip(const std::vector<uint8_t> &data, const char *what) {
    const std::vector<uint8_t> z = zlib_compress(data.data(), data.size());
    try {
        const std::vector<uint8_t> back = cli_test::zlib_decompress(z);
        CHECK_MSG(back == data, "%s: round trip differs (%zu vs %zu bytes)", what, back.size(), data.size());
    } catch (const std::exception &e) {
        CHECK_MSG(false, "%s: %s", what, e.what());
    }
}

void test_deflate() {
    check_zlib_roundtrip({}, "empty");
    check_zlib_roundtrip({7}, "one byte");
    check_zlib_roundtrip({1, 2}, "two bytes");
    check_zlib_roundtrip(std::vector<uint8_t>(100000, 255), "a long run");
    std::vector<uint8_t> text;
    const char *words[] = {"kissm ", "registers ", "point ", "clouds ", "fast ", "and ", "deterministically. "};
    Rng rng(7);
    for (int i = 0; i < 20000; ++i) {
        const char *w = words[rng.uniform_int(0, 6)];
        text.insert(text.end(), w, w + std::strlen(w));
    }
    check_zlib_roundtrip(text, "words");
    std::vector<uint8_t> noise(70000);
    for (uint8_t &b : noise) b = static_cast<uint8_t>(rng.next() >> 56);
    check_zlib_roundtrip(noise, "random bytes");
    // Repeats at every distance class up to the 32 KiB window, and a repeat just beyond it.
    std::vector<uint8_t> far(noise.begin(), noise.begin() + 40000);
    for (size_t d : {1u, 2u, 3u, 5u, 100u, 1000u, 4097u, 20000u, 32768u, 32769u, 39000u}) {
        for (int k = 0; k < 300; ++k) far.push_back(far[far.size() - d]); // may overlap, as LZ77 copies do
    }
    check_zlib_roundtrip(far, "distances");
    const std::vector<uint8_t> z = zlib_compress(text.data(), text.size());
    CHECK_MSG(z.size() * 3 < text.size(), "repetitive text compresses poorly: %zu -> %zu", text.size(), z.size());
}

void test_png() {
    Image img(37, 23, {255, 255, 255});
    img.fill_rect(3, 4, 10, 6, {255, 127, 14});
    img.set(36, 22, {1, 2, 3});
    img.draw_text(2, 12, "KISSM 0.1", {31, 119, 180}, 1);
    const std::vector<uint8_t> png = encode_png_rgb(img.width(), img.height(), img.data());
    try {
        const cli_test::PngImage back = cli_test::decode_png(std::string(png.begin(), png.end()));
        CHECK_EQ_INT(back.width, 37);
        CHECK_EQ_INT(back.height, 23);
        CHECK(back.rgb == std::vector<uint8_t>(img.data(), img.data() + 37 * 23 * 3));
    } catch (const std::exception &e) {
        CHECK_MSG(false, "decode: %s", e.what());
    }
    const std::string path = temp_path("test.png");
    std::string error;
    CHECK(write_png_rgb(path, img.width(), img.height(), img.data(), &error));
    CHECK(cli_test::read_file(path) == std::string(png.begin(), png.end()));
    std::remove(path.c_str());
    CHECK(!write_png_rgb("/nonexistent_dir_kissm/x.png", 2, 2, img.data(), &error));
    CHECK(cli_test::contains(error, "x.png"));

    // Text is drawn (and lower case maps to upper case).
    Image a(40, 10, {255, 255, 255}), b(40, 10, {255, 255, 255});
    a.draw_text(0, 0, "abc", {0, 0, 0}, 1);
    b.draw_text(0, 0, "ABC", {0, 0, 0}, 1);
    CHECK(std::memcmp(a.data(), b.data(), 40 * 10 * 3) == 0);
    CHECK(a.get(0, 1).r == 0);
    CHECK_EQ_INT(Image::text_width("ABC", 2), 34);
}

void test_json_writer() {
    JsonWriter json;
    json.begin_object();
    json.field("text", "quote \" backslash \\ newline \n tab \t bell \x07");
    json.field("nan", std::nan(""));
    json.field("inf", -HUGE_VAL);
    json.field("third", 0.1 + 0.2);
    json.field("flag", false);
    json.field("count", uint64_t{18446744073709551615ull});
    json.field("negative", int64_t{-5});
    const double m[4] = {1.0, -0.0, 1e-300, 123456789.125};
    json.field_matrix("m", m, 2, 2);
    json.key("empty");
    json.begin_object();
    json.end_object();
    json.key("list");
    json.begin_array();
    json.value(1.5);
    json.null();
    json.end_array();
    json.end_object();
    const std::string &s = json.str();
    std::string error;
    CHECK_MSG(cli_test::json_valid(s, &error), "%s\n%s", error.c_str(), s.c_str());
    CHECK(cli_test::contains(s, "\"nan\": null"));
    CHECK(cli_test::contains(s, "\"inf\": null"));
    CHECK(cli_test::contains(s, "\\u0007"));
    CHECK(cli_test::contains(s, "\"m\": [[1, -0], [1e-300, 123456789.125]]"));
    CHECK(cli_test::contains(s, "\"count\": 18446744073709551615"));
    CHECK(s.back() == '\n');
    CHECK(JsonWriter::number(0.3) == "0.3");
    CHECK(JsonWriter::number(0.1 + 0.2) == "0.30000000000000004");

    // Every double reads back exactly.
    Rng rng(3);
    for (int i = 0; i < 20000; ++i) {
        uint64_t bits = rng.next();
        double v = 0.0;
        std::memcpy(&v, &bits, sizeof v);
        if (!std::isfinite(v)) continue;
        const std::string text = JsonWriter::number(v);
        const double back = std::strtod(text.c_str(), nullptr);
        CHECK_MSG(std::memcmp(&back, &v, sizeof v) == 0, "%s does not read back to %.17g", text.c_str(), v);
    }
}

void test_ply_writer() {
    const std::vector<double> xyz = {1.0, -2.5, 3.25, 1e-7, 1e7, -0.0, 0.1, 0.2, 0.3, -4.0, 5.0, 6.0};
    const std::string path = temp_path("points.ply");
    std::string error;
    REQUIRE(write_ply_xyz(path, xyz.data(), 4, nullptr, {"hello"}, &error));
    const std::string bytes = cli_test::read_file(path);
    const std::string header = "ply\nformat binary_little_endian 1.0\ncomment hello\nelement vertex 4\n"
                               "property double x\nproperty double y\nproperty double z\nend_header\n";
    REQUIRE(bytes.size() == header.size() + 4 * 24);
    CHECK(bytes.compare(0, header.size(), header) == 0);
    for (size_t i = 0; i < xyz.size(); ++i) {
        uint64_t bits = 0;
        for (int k = 0; k < 8; ++k) {
            bits |= static_cast<uint64_t>(static_cast<uint8_t>(bytes[header.size() + 8 * i + static_cast<size_t>(k)]))
                    << (8 * k);
        }
        double v = 0.0;
        std::memcpy(&v, &bits, sizeof v);
        CHECK_MSG(std::memcmp(&v, &xyz[i], sizeof v) == 0, "value %zu: %.17g vs %.17g", i, v, xyz[i]);
    }

    // The library reads the file back exactly.
    kissm_cloud *cloud = nullptr;
    const int32_t status = kissm_read_points(path.c_str(), KISSM_FORMAT_AUTO, &cloud);
    CHECK_MSG(status == KISSM_OK, "kissm_read_points: %s", kissm_last_error_message());
    if (status == KISSM_OK) {
        CHECK_EQ_INT(kissm_cloud_count(cloud), 4);
        const double *data = kissm_cloud_data(cloud);
        CHECK(data != nullptr && std::memcmp(data, xyz.data(), xyz.size() * sizeof(double)) == 0);
    }
    kissm_cloud_destroy(cloud);

    // With a transform.
    const double T[16] = {0, -1, 0, 10, 1, 0, 0, 20, 0, 0, 1, 30, 0, 0, 0, 1};
    REQUIRE(write_ply_xyz(path, xyz.data(), 1, T, {}, &error));
    const std::string moved = cli_test::read_file(path);
    double p[3];
    std::memcpy(p, moved.data() + moved.size() - 24, 24); // little-endian hosts only; fine for this check
    const uint16_t probe = 1;
    if (*reinterpret_cast<const uint8_t *>(&probe) == 1) {
        CHECK_NEAR(p[0], 10.0 + 2.5, 1e-12);
        CHECK_NEAR(p[1], 20.0 + 1.0, 1e-12);
        CHECK_NEAR(p[2], 30.0 + 3.25, 1e-12);
    }
    std::remove(path.c_str());
    CHECK(!write_ply_xyz("/nonexistent_dir_kissm/x.ply", xyz.data(), 1, nullptr, {}, &error));
}

template <typename F>
bool throws_usage(F f) {
    try {
        f();
    } catch (const UsageError &) {
        return true;
    }
    return false;
}

void test_args() {
    CHECK(parse_double("--x", "1.5") == 1.5);
    CHECK(parse_double("--x", "-2e3") == -2000.0);
    CHECK(parse_positive("--x", "0.3") == 0.3);
    for (const char *bad : {"", "abc", "1.5x", " 1", "nan", "inf", "-inf", "1e999"}) {
        CHECK_MSG(throws_usage([&] { parse_double("--x", bad); }), "'%s' accepted", bad);
    }
    for (const char *bad : {"0", "-0", "-1"}) CHECK(throws_usage([&] { parse_positive("--x", bad); }));
    CHECK(parse_int32("--n", "7", 0, 10) == 7);
    for (const char *bad : {"-1", "11", "1.0", "x", "", "99999999999999999999"}) {
        CHECK_MSG(throws_usage([&] { parse_int32("--n", bad, 0, 10); }), "'%s' accepted", bad);
    }
    CHECK(parse_uint64("--seed", "18446744073709551615") == 18446744073709551615ull);
    CHECK(parse_uint64("--seed", "0x10") == 16u);
    for (const char *bad : {"-1", "+1", "x", "", "18446744073709551616"}) {
        CHECK_MSG(throws_usage([&] { parse_uint64("--seed", bad); }), "'%s' accepted", bad);
    }
    CHECK(parse_format("--f", "bin_xyz") == KISSM_FORMAT_BIN_XYZ);
    CHECK(parse_format("--f", "bin_xyz_f32") == KISSM_FORMAT_BIN_XYZ);
    CHECK(parse_format("--f", "kitti_bin_xyzi_f32") == KISSM_FORMAT_KITTI_BIN);
    CHECK(parse_format("--f", "npy_xyz") == KISSM_FORMAT_NPY);
    CHECK(parse_format("--f", "ply") == KISSM_FORMAT_PLY);
    CHECK(parse_format("--f", "pcd") == KISSM_FORMAT_PCD);
    CHECK(parse_format("--f", "xyz") == KISSM_FORMAT_XYZ);
    CHECK(parse_format("--f", "auto") == KISSM_FORMAT_AUTO);
    CHECK(parse_format("--f", "las") == KISSM_FORMAT_LAS);
    CHECK(throws_usage([] { parse_format("--f", "laz"); }));
    CHECK(throws_usage([] { parse_format("--f", "e57"); }));
    CHECK(parse_refine_mode("--refine", "none") == KISSM_REFINE_NONE);
    CHECK(parse_refine_mode("--refine", "gicp") == KISSM_REFINE_GICP);
    CHECK(parse_refine_mode("--refine", "point-to-plane") == KISSM_REFINE_POINT_TO_PLANE);
    CHECK(parse_refine_mode("--refine", "point_to_plane") == KISSM_REFINE_POINT_TO_PLANE);
    for (const char *bad : {"", "GICP", "icp", "point to plane", "1"}) {
        CHECK_MSG(throws_usage([&] { parse_refine_mode("--refine", bad); }), "'%s' accepted", bad);
    }
    for (int32_t mode : {KISSM_REFINE_NONE, KISSM_REFINE_GICP, KISSM_REFINE_POINT_TO_PLANE}) {
        CHECK(parse_refine_mode("--refine", refine_mode_name(mode)) == mode);
    }
    CHECK(std::strcmp(refine_mode_name(99), "unknown") == 0);
    CHECK(parse_viewpoint_mode("--viewpoint", "fixed") == KISSM_VIEWPOINT_FIXED);
    CHECK(parse_viewpoint_mode("--viewpoint", "center") == KISSM_VIEWPOINT_CLOUD_CENTER);
    CHECK(parse_viewpoint_mode("--viewpoint", "cloud-center") == KISSM_VIEWPOINT_CLOUD_CENTER);
    CHECK(parse_viewpoint_mode("--viewpoint", "sign-free") == KISSM_VIEWPOINT_SIGN_FREE);
    CHECK(parse_viewpoint_mode("--viewpoint", "sign_free") == KISSM_VIEWPOINT_SIGN_FREE);
    CHECK(parse_viewpoint_mode("--viewpoint", "local") == KISSM_VIEWPOINT_LOCAL);
    for (const char *bad : {"", "LOCAL", "none", "sensor", "2"}) {
        CHECK_MSG(throws_usage([&] { parse_viewpoint_mode("--viewpoint", bad); }), "'%s' accepted", bad);
    }
    CHECK(one_line("a\nb\r\n") == "a b");

    // --up, --viewpoint X,Y,Z: three finite numbers and two commas, nothing else; *out unchanged on error.
    double v[3] = {7.0, 7.0, 7.0};
    parse_vec3("--up", "0,0,1", v);
    CHECK(v[0] == 0.0 && v[1] == 0.0 && v[2] == 1.0);
    parse_vec3("--up", "-1.5,2e-3,0.1", v);
    CHECK(v[0] == -1.5 && v[1] == 2e-3 && v[2] == 0.1);
    for (const char *bad : {"", "1", "1,2", "1,2,3,4", "1,,3", ",1,2", "1,2,", "a,b,c", "nan,0,1", "0,inf,1",
                            "1e999,0,0", "1;2;3", "1, 2,3"}) {
        double w[3] = {7.0, 7.0, 7.0};
        CHECK_MSG(throws_usage([&] { parse_vec3("--up", bad, w); }), "'%s' accepted", bad);
        CHECK(w[0] == 7.0 && w[1] == 7.0 && w[2] == 7.0);
    }
    CHECK(parse_suppression("--suppression", "none") == KISSM_SUPPRESS_NONE);
    CHECK(parse_suppression("--suppression", "ground") == KISSM_SUPPRESS_GROUND);
    for (const char *bad : {"", "Ground", "1", "planes"}) {
        CHECK_MSG(throws_usage([&] { parse_suppression("--suppression", bad); }), "'%s' accepted", bad);
    }
    for (int32_t preset :
         {KISSM_PRESET_LIDAR_VEHICLE, KISSM_PRESET_LIDAR_HANDHELD, KISSM_PRESET_INDOOR_RGBD, KISSM_PRESET_OBJECT}) {
        CHECK(parse_preset("--preset", preset_name(preset)) == preset);
    }
    CHECK(parse_preset("--preset", "lidar_vehicle") == KISSM_PRESET_LIDAR_VEHICLE);
    CHECK(parse_preset("--preset", "indoor_rgbd") == KISSM_PRESET_INDOOR_RGBD);
    for (const char *bad : {"", "nope", "LIDAR-VEHICLE", "1", "lidar"}) {
        CHECK_MSG(throws_usage([&] { parse_preset("--preset", bad); }), "'%s' accepted", bad);
    }
    CHECK(std::strcmp(preset_name(0), "unknown") == 0);

    ArgCursor cur("register", {"a", "--voxel=0.5", "--json", "--threads", "3", "--", "--b"});
    std::vector<std::string> seen;
    while (cur.next()) {
        if (!cur.is_option()) {
            seen.push_back("pos:" + cur.current());
        } else if (cur.current() == "--json") {
            cur.expect_no_value();
            seen.push_back("json");
        } else {
            seen.push_back(cur.current() + "=" + cur.value());
        }
    }
    const std::vector<std::string> expected = {"pos:a", "--voxel=0.5", "json", "--threads=3", "pos:--b"};
    CHECK(seen == expected);
}

void test_transform_file() {
    const std::string path = temp_path("T.txt");
    std::string error;
    // Written with %.17g, read back to the same bits, including awkward values.
    const double T[16] = {0.1,    -0.0, 1e-300, 123456789.125, 0.30000000000000004,
                          5e-324, -1.0, 2.5,    1.0 / 3.0,     2.0 / 3.0,
                          -7e300, 1e-7, 0.0,    0.0,           0.0,
                          1.0};
    REQUIRE(write_transform_file(path, T, &error));
    const std::string text = cli_test::read_file(path);
    CHECK_EQ_INT(std::count(text.begin(), text.end(), '\n'), 4);
    double back[16];
    REQUIRE(read_transform_file(path, back, &error));
    CHECK(std::memcmp(back, T, sizeof T) == 0);

    // Comments, blank lines, tabs, CRLF line ends and extra spaces are fine.
    REQUIRE(cli_test::write_file(path, "# T_target_source\r\n\r\n\t1  0 0 4\r\n  # between rows\n0 1 0 5\n"
                                       "0 0 1 6   \n\n0 0 0 1"));
    REQUIRE(read_transform_file(path, back, &error));
    const double expected[16] = {1, 0, 0, 4, 0, 1, 0, 5, 0, 0, 1, 6, 0, 0, 0, 1};
    CHECK(std::memcmp(back, expected, sizeof expected) == 0);

    // Each failure names the file, and the line where there is one; nothing is accepted half-read.
    struct Bad {
        const char *text;
        const char *about;
    };
    const Bad bad[] = {
        {"", "0 rows"},
        {"1 0 0 0\n0 1 0 0\n0 0 1 0\n", "3 rows"},
        {"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n1 1 1 1\n", "line 5"},
        {"1 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "line 1 holds 3 values"},
        {"1 0 0 0\n0 1 0 0 # a comment after numbers\n0 0 1 0\n0 0 0 1\n", "line 2 holds 9 values"},
        {"1 0 0 0\n0 1 0 0\n0 0 1 0,\n0 0 0 1\n", "line 3: '0,' is not a number"},
        {"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 NaN\n", "line 4: 'NaN' is not finite"},
        {"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 infinity\n", "not finite"},
        {"1 0 0 0\n0 1 0 0\n0 0 1 -1e400\n0 0 0 1\n", "not finite"},
    };
    for (const Bad &b : bad) {
        REQUIRE(cli_test::write_file(path, b.text));
        error.clear();
        CHECK_MSG(!read_transform_file(path, back, &error), "accepted: %s", b.text);
        CHECK_MSG(cli_test::contains(error, "'" + path + "'") && cli_test::contains(error, b.about),
                  "message [%s] lacks the file or '%s'", error.c_str(), b.about);
        CHECK(error.find('\n') == std::string::npos);
    }
    // Not a transform file at all.
    REQUIRE(cli_test::write_file(path, std::string(2u << 20, ' ')));
    CHECK(!read_transform_file(path, back, &error) && cli_test::contains(error, "too large"));
    std::remove(path.c_str());
    CHECK(!read_transform_file(path, back, &error) && cli_test::contains(error, "cannot open"));
    const std::string dir = std::filesystem::temp_directory_path().string();
    CHECK(!read_transform_file(dir, back, &error) && cli_test::contains(error, "folder"));
    CHECK(!write_transform_file("/nonexistent_dir_kissm/T.txt", T, &error) && cli_test::contains(error, "T.txt"));
}

// The result part of the JSON: the contract's keys in order, null for what the library left NaN.
void test_result_json() {
    kissm_result r{};
    REQUIRE(kissm_result_init(&r, sizeof r) == KISSM_OK);
    const auto object_of = [](const kissm_result &result, int32_t mode, const double *initial) {
        JsonWriter json;
        json.begin_object();
        add_result_json(json, result, mode, initial);
        json.end_object();
        std::string error;
        const cli_test::Json j = cli_test::json_parse(json.str(), &error);
        CHECK_MSG(error.empty(), "%s\n%s", error.c_str(), json.str().c_str());
        return j;
    };
    std::vector<std::string> expected = cli_test::contract_keys(false);
    expected.erase(expected.begin(), expected.begin() + 5); // version .. threads are the command's
    expected.pop_back();                                    // read_ms too
    cli_test::Json j = object_of(r, KISSM_REFINE_NONE, nullptr);
    CHECK_MSG(j.keys() == expected, "keys %s", cli_test::joined(j.keys()).c_str());
    CHECK(j.at("counts").keys() == cli_test::contract_count_keys());
    CHECK(j.at("time_ms").keys() == cli_test::contract_time_keys());
    CHECK(j.at("information").is(cli_test::Json::Type::Null));
    CHECK(j.at("tilt").is(cli_test::Json::Type::Null));      // NaN unless rotation_dof = 1
    CHECK(j.at("ambiguity").is(cli_test::Json::Type::Null)); // NaN unless the solver ran
    CHECK(j.at("counts").at("source_suppressed").text == "0" && j.at("time_ms").at("suppression").text == "0");
    CHECK(j.at("coarse_transform").is_matrix(4, 4, true) &&
          j.at("coarse_transform").items[0].items[0].is(cli_test::Json::Type::Null));
    CHECK(j.at("overlap").is(cli_test::Json::Type::Null) && j.at("refine_rmse").is(cli_test::Json::Type::Null));
    CHECK(j.at("refine").text == "none" && !j.at("refine_converged").boolean);
    CHECK(!refinement_ran(r));
    // kissm_result_init leaves both validity measures NaN: null.
    CHECK(j.at("rotation_uncertainty").is(cli_test::Json::Type::Null) &&
          j.at("inlier_coverage").is(cli_test::Json::Type::Null));
    // +inf (no inliers spread out) is null too; finite values are written exactly.
    r.rotation_uncertainty = std::numeric_limits<double>::infinity();
    CHECK(object_of(r, KISSM_REFINE_NONE, nullptr).at("rotation_uncertainty").is(cli_test::Json::Type::Null));
    r.rotation_uncertainty = 0.1 + 0.2; // 0.30000000000000004: needs 17 digits
    j = object_of(r, KISSM_REFINE_NONE, nullptr);
    cli_test::check_scalar(j.at("rotation_uncertainty"), 0.1 + 0.2, "result json", "rotation_uncertainty");
    CHECK(j.at("rotation_uncertainty").text == "0.30000000000000004");

    // A refined result: information as 6x6, an entry left NaN written as null inside it.
    for (int i = 0; i < 36; ++i) r.information[i] = i == 7 ? std::nan("") : 0.5 * i;
    r.overlap = 0.75;
    r.refine_converged = 1;
    r.refine_iterations = 3;
    CHECK(refinement_ran(r));
    const double initial[16] = {1, 0, 0, 0.1, 0, 1, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 1};
    j = object_of(r, KISSM_REFINE_POINT_TO_PLANE, initial);
    expected.insert(expected.begin() + 3, "initial_transform");
    CHECK_MSG(j.keys() == expected, "keys %s", cli_test::joined(j.keys()).c_str());
    CHECK(j.at("information").is_matrix(6, 6, true));
    CHECK(j.at("information").items[1].items[1].is(cli_test::Json::Type::Null));
    CHECK(j.at("information").items[5].items[5].number == 17.5);
    CHECK(j.at("refine").text == "point-to-plane" && j.at("refine_converged").boolean);
    CHECK(j.at("refine_iterations").text == "3" && j.at("overlap").text == "0.75");
    CHECK(j.at("inlier_coverage").is(cli_test::Json::Type::Null));
    r.inlier_coverage = 0.625;
    CHECK(object_of(r, KISSM_REFINE_GICP, nullptr).at("inlier_coverage").text == "0.625");
    cli_test::check_doubles(j.at("initial_transform").flat(), initial, 16, "result json", "initial_transform");
}

// The summary a result prints, as text.
std::string summary_of(const kissm_result &r, ResultKind kind) {
    std::FILE *f = std::tmpfile();
    if (!f) return std::string();
    print_result_summary(f, r, kind);
    std::string text;
    std::rewind(f);
    for (int c = std::fgetc(f); c != EOF; c = std::fgetc(f)) text.push_back(static_cast<char>(c));
    std::fclose(f);
    return text;
}

// The summary's rotation uncertainty (degrees; "-" without a pose, "unbounded" when infinite) and, for a
// refined registration only, the inlier coverage.
void test_summary_validity_measures() {
    kissm_result r{};
    REQUIRE(kissm_result_init(&r, sizeof r) == KISSM_OK);
    using cli_test::contains;
    CHECK(contains(summary_of(r, ResultKind::Global), "\nrotation uncertainty: -\n"));
    r.rotation_uncertainty = deg_to_rad(1.25);
    std::string text = summary_of(r, ResultKind::Global);
    CHECK_MSG(contains(text, "\nrotation uncertainty: 1.25 deg\n"), "%s", text.c_str());
    CHECK(!contains(text, "inlier coverage"));
    r.rotation_uncertainty = std::numeric_limits<double>::infinity();
    CHECK(contains(summary_of(r, ResultKind::Global), "\nrotation uncertainty: unbounded\n"));

    // Refined: the coverage on the refinement's line; a refinement from a prior has no solver inliers.
    for (int i = 0; i < 36; ++i) r.information[i] = 1.0;
    r.overlap = 0.8;
    r.refine_rmse = 0.01;
    r.refine_condition = 0.2;
    r.inlier_coverage = 0.4375;
    text = summary_of(r, ResultKind::Global);
    CHECK_MSG(contains(text, "overlap 0.8000, inlier coverage 0.4375, rmse 0.01, condition 0.2\n"), "%s", text.c_str());
    r.inlier_coverage = std::nan("");
    CHECK(contains(summary_of(r, ResultKind::Global), "inlier coverage -, "));
    text = summary_of(r, ResultKind::Refine);
    CHECK_MSG(contains(text, "overlap 0.8000, rmse 0.01") && !contains(text, "inlier coverage") &&
                  !contains(text, "rotation uncertainty"),
              "%s", text.c_str());
}

// A cloud in a square of side 40 m: flat ground everywhere (denser than the floor's cells), and a 2 m high
// L-shaped wall near (12, -6).
std::vector<double> yard_with_wall() {
    std::vector<double> xyz;
    for (int i = 0; i <= 160; ++i) {
        for (int k = 0; k <= 160; ++k) xyz.insert(xyz.end(), {-20.0 + 0.25 * i, -20.0 + 0.25 * k, 0.0});
    }
    for (int i = 0; i < 40; ++i) {
        for (int h = 1; h <= 8; ++h) {
            xyz.insert(xyz.end(), {10.0 + 0.1 * i, -8.0, 0.25 * h});
            xyz.insert(xyz.end(), {10.0, -8.0 + 0.1 * i, 0.25 * h});
        }
    }
    return xyz;
}

void test_alignment_detail() {
    const std::vector<double> xyz = yard_with_wall();
    const size_t n = xyz.size() / 3;
    const CloudLayer all{xyz.data(), n, nullptr, kTargetColor, nullptr};
    const ViewBox view{0.0, 0.0, 22.0};
    const HeightFloor floor = height_floor(all, view, 128, 0.6);
    CHECK(floor.above(10.0, -8.0, 1.0));
    CHECK(!floor.above(10.0, -8.0, 0.3) && !floor.above(0.0, 0.0, 0.0));
    CHECK(!floor.above(30.0, 0.0, 5.0)); // outside the grid
    CHECK(std::isinf(floor.min_z[0]));   // the corner cell holds no point

    CloudLayer above = all;
    above.floor = &floor;
    size_t shown = 0;
    for (size_t i = 0; i < n; ++i) {
        double x = 0, y = 0;
        if (project_point(above, i, &x, &y)) {
            ++shown;
            CHECK(x >= 9.9 && x <= 14.0 && y >= -8.1 && y <= -4.0);
        }
    }
    CHECK_EQ_INT(shown, 40 * 2 * 6); // wall points 0.75 m and more above the ground
    const ViewBox detail = detail_view(above, above, view, 3.0);
    CHECK_MSG(std::fabs(detail.half - 3.0) < 0.2, "detail half %g", detail.half);
    CHECK_MSG(detail.cx - detail.half <= 10.0 && detail.cx + detail.half >= 13.0 && detail.cy - detail.half <= -8.0 &&
                  detail.cy + detail.half >= -5.0,
              "detail (%g, %g) +- %g misses the wall", detail.cx, detail.cy, detail.half);

    // The figure: with a coarse pose, four panels in two columns, the details magnified on that region.
    const double pose[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const double coarse[16] = {1, 0, 0, 0.3, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    AlignmentInput in;
    in.source_xyz = in.target_xyz = xyz.data();
    in.source_count = in.target_count = n;
    in.pose = pose;
    in.coarse = coarse;
    in.voxel = 0.3;
    in.before_title = "B";
    in.after_title = "A";
    AlignmentFigure with_detail(in);
    const AlignmentPicture &pic = with_detail.picture();
    CHECK(pic.has_detail);
    REQUIRE(pic.figure.panels.size() == 4);
    CHECK_EQ_INT(pic.figure.columns, 2);
    CHECK(pic.figure.panels[2].has_view && pic.figure.panels[3].has_view && pic.figure.panels[2].dot > 1);
    CHECK(pic.figure.panels[1].outlines.size() == 1);
    CHECK(pic.figure.panels[2].layers[1].transform == coarse && pic.figure.panels[3].layers[1].transform == pose);
    const ViewBox &d = pic.figure.panels[2].view;
    CHECK_MSG(d.cx - d.half <= 10.0 && d.cx + d.half >= 12.0 && d.cy - d.half <= -8.0 && d.cy + d.half >= -6.0,
              "figure detail (%g, %g) +- %g misses the wall", d.cx, d.cy, d.half);
    const Image four = render_top_view(pic.figure, pic.view);

    in.coarse = nullptr; // no refinement: before and after only, in one row
    AlignmentFigure plain(in);
    CHECK(!plain.picture().has_detail && plain.picture().figure.panels.size() == 2);
    const Image two = render_top_view(plain.picture().figure, plain.picture().view);
    CHECK_EQ_INT(four.width(), two.width());
    CHECK_MSG(four.height() > two.height() + plain.picture().figure.panel_size, "%d vs %d", four.height(),
              two.height());

    // In the refined detail the source covers the target (it is drawn on top); in the coarse one, 0.3 m off,
    // the target's blue shows beside it.
    const auto blue_pixels = [&pic](size_t panel) {
        TopViewFigure alone;
        alone.panels = {pic.figure.panels[panel]};
        const Image img = render_top_view(alone, pic.view);
        size_t blue = 0;
        for (int y = 0; y < img.height(); ++y) {
            for (int x = 0; x < img.width(); ++x) {
                const Rgb c = img.get(x, y);
                blue += (c.b > 150 && c.r < 120 && c.g < 170) ? 1u : 0u;
            }
        }
        return blue;
    };
    const size_t coarse_blue = blue_pixels(2), refined_blue = blue_pixels(3);
    CHECK_MSG(coarse_blue > 100 && refined_blue * 10 < coarse_blue, "blue pixels: coarse %zu, refined %zu", coarse_blue,
              refined_blue);
}

void test_rng() {
    Rng a(99), b(99), c(99, 1), d(100), stats(5);
    bool same = true, differs_stream = false, differs_seed = false;
    double sum = 0.0, sum_sq = 0.0, lo = 1.0, hi = 0.0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        const uint64_t x = a.next();
        same = same && x == b.next();
        differs_stream = differs_stream || x != c.next();
        differs_seed = differs_seed || x != d.next();
        const double u = stats.uniform();
        lo = std::fmin(lo, u);
        hi = std::fmax(hi, u);
        const double g = stats.normal();
        sum += g;
        sum_sq += g * g;
    }
    CHECK(same && differs_stream && differs_seed);
    CHECK(lo >= 0.0 && hi < 1.0 && lo < 1e-4 && hi > 1.0 - 1e-4);
    CHECK_NEAR(sum / n, 0.0, 0.01);
    CHECK_NEAR(sum_sq / n, 1.0, 0.02);
}

void test_pose_math() {
    const Pose p = pose_from_ypr(0.3, -0.2, 0.1, 1.0, 2.0, 3.0);
    double T[16], I[16];
    pose_to_matrix(pose_compose(p, pose_inverse(p)), I);
    pose_to_matrix(pose_identity(), T);
    for (int i = 0; i < 16; ++i) CHECK_NEAR(I[i], T[i], 1e-12);
    pose_to_matrix(p, T);
    double yaw = 0, pitch = 0, roll = 0;
    yaw_pitch_roll_deg(T, &yaw, &pitch, &roll);
    CHECK_NEAR(yaw, rad_to_deg(0.3), 1e-9);
    CHECK_NEAR(pitch, rad_to_deg(-0.2), 1e-9);
    CHECK_NEAR(roll, rad_to_deg(0.1), 1e-9);
    double Z[16];
    pose_to_matrix(pose_from_ypr(deg_to_rad(30.0), 0, 0, 0, 0, 0), Z);
    CHECK_NEAR(rotation_angle_deg(Z), 30.0, 1e-9);
    double E[16];
    pose_to_matrix(pose_identity(), E);
    CHECK_NEAR(rotation_error_deg(E, Z), 30.0, 1e-9);
    CHECK_NEAR(rotation_error_deg(Z, Z), 0.0, 1e-6);
    CHECK_NEAR(translation_error(T, Z), std::sqrt(14.0), 1e-12);
}

void test_demo_scene() {
    DemoOptions options;
    options.seed = 1;
    const DemoData a = generate_demo(options);
    const DemoData b = generate_demo(options);
    CHECK(a.source.xyz == b.source.xyz);
    CHECK(a.target.xyz == b.target.xyz);
    CHECK(std::memcmp(a.gt_target_from_source, b.gt_target_from_source, sizeof a.gt_target_from_source) == 0);

    for (uint64_t seed : {1ull, 2ull, 3ull, 12345ull}) {
        options.seed = seed;
        const DemoData d = generate_demo(options);
        for (const DemoScan *scan : {&d.source, &d.target}) {
            const size_t n = scan->xyz.size() / 3;
            CHECK_MSG(n >= 30000 && n <= 60000, "seed %llu: %zu points", static_cast<unsigned long long>(seed), n);
            // Sensor frame: every return lies between the minimum and maximum range (plus noise).
            double rmin = 1e30, rmax = 0.0;
            for (size_t i = 0; i < n; ++i) {
                const double *p = &scan->xyz[3 * i];
                const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
                rmin = std::fmin(rmin, r);
                rmax = std::fmax(rmax, r);
            }
            CHECK(rmin > options.min_range - 0.2 && rmax < options.max_range + 0.2);
        }
        const double *T = d.gt_target_from_source;
        // A rigid transform with the advertised motion: 10-15 m, 120-165 degrees of yaw plus a little tilt.
        double RtR[9];
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                RtR[3 * i + j] = T[i] * T[j] + T[4 + i] * T[4 + j] + T[8 + i] * T[8 + j];
                CHECK_NEAR(RtR[3 * i + j], i == j ? 1.0 : 0.0, 1e-12);
            }
        }
        const double dist = translation_norm(T);
        const double angle = rotation_angle_deg(T);
        CHECK_MSG(dist > 9.0 && dist < 16.5, "seed %llu: %g m apart", static_cast<unsigned long long>(seed), dist);
        CHECK_MSG(angle > 110.0 && angle < 175.0, "seed %llu: %g degrees", static_cast<unsigned long long>(seed),
                  angle);
        CHECK(d.stats.buildings > 20 && d.stats.cars > 5 && d.stats.poles > 2 && d.stats.clutter > 40);
    }
    options.seed = 2;
    const DemoData other = generate_demo(options);
    CHECK(other.source.xyz != a.source.xyz);
}

// The UsageError's message of f(), or "" when it did not throw.
template <typename F>
std::string usage_error_of(F f) {
    try {
        f();
    } catch (const UsageError &e) {
        return e.what();
    }
    return std::string();
}

void test_batch_pairs() {
    const PairsTable t = parse_pairs("# comment\r\n\r\nid\tsource\ttarget\tgt\r\n"
                                     "a\tx y.ply\t/abs/b.ply\tgt1.txt\r\n"
                                     "  # another comment\n"
                                     "b\tsub/c.ply\td.ply\t\n",
                                     "p.tsv");
    CHECK(t.has_gt_column);
    REQUIRE(t.rows.size() == 2);
    CHECK(t.rows[0].index == 1 && t.rows[0].line == 4 && t.rows[0].source == "x y.ply" &&
          t.rows[0].target == "/abs/b.ply" && t.rows[0].gt == "gt1.txt");
    CHECK(t.rows[1].index == 2 && t.rows[1].line == 6 && t.rows[1].source == "sub/c.ply" && t.rows[1].gt.empty());
    const PairsTable no_gt = parse_pairs("target\tsource\nb\ta", "p.tsv"); // any column order, no final newline
    CHECK(!no_gt.has_gt_column && no_gt.rows.size() == 1 && no_gt.rows[0].source == "a" && no_gt.rows[0].target == "b");
    CHECK(parse_pairs("source\ttarget\n", "p.tsv").rows.empty());

    const struct {
        const char *text, *message;
    } bad[] = {
        {"", "p.tsv: no header line"},
        {"source target\na b\n", "p.tsv line 1: the header has no 'source' column"},
        {"source\n", "p.tsv line 1: the header has no 'target' column"},
        {"target\tsource\tgt\tgt\n", "p.tsv line 1: the header names the column 'gt' twice"},
        {"source\ttarget\na\tb\tc\n", "p.tsv line 2: 3 tab-separated fields, the header has 2"},
        {"source\ttarget\na\t\n", "p.tsv line 2: empty target path"},
    };
    for (const auto &b : bad) {
        const std::string message = usage_error_of([&] { parse_pairs(b.text, "p.tsv"); });
        CHECK_MSG(message.find(b.message) == 0, "[%s]: [%s], expected [%s]", b.text, message.c_str(), b.message);
    }
    CHECK(resolve_pair_path("data/pairs.tsv", "a.ply") == (std::filesystem::path("data") / "a.ply").string());
    CHECK(resolve_pair_path("pairs.tsv", "a.ply") == "a.ply");
    const std::string abs = std::filesystem::absolute("x.ply").string();
    CHECK(resolve_pair_path("data/pairs.tsv", abs) == abs);
}

void test_batch_lines_and_resume() {
    PairRow row;
    row.index = 3;
    row.source = "we\"ird\tname\x01.ply";
    row.target = "t.ply";
    row.gt = "gt.txt";
    kissm_result r{};
    REQUIRE(kissm_result_init(&r, sizeof r) == KISSM_OK);
    r.valid = 1;
    r.time_total_ms = 12.5;
    double gt[16] = {1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    for (int i = 0; i < 16; ++i) r.transform[i] = gt[i];
    r.transform[3] = 1.25; // 0.25 off in x
    const std::string ok = batch_line_ok(row, true, r, KISSM_REFINE_NONE, gt);
    CHECK(ok.back() == '\n' && ok.find('\n') == ok.size() - 1);
    CHECK(!cli_test::contains(ok, "time_ms") && !cli_test::contains(ok, "12.5"));
    CHECK(cli_test::starts_with(ok, "{\"pair\": 3, \"source\": \"we\\\"ird\\tname\\u0001.ply\", \"target\": \"t.ply\", "
                                    "\"gt\": \"gt.txt\", \"status\": \"ok\", \"valid\": true, \"reason\": "));
    CHECK(cli_test::contains(ok, "\"rotation_error_deg\": 0, \"translation_error_m\": 0.25}\n"));
    std::string error;
    CHECK_MSG(cli_test::json_valid(ok, &error), "%s", error.c_str());
    PairRow plain = row;
    plain.index = 4;
    plain.source = "s.ply";
    plain.gt.clear();
    const std::string failed = batch_line_error(plain, true, "source 's.ply': cannot read it:\nno such file");
    CHECK(failed == "{\"pair\": 4, \"source\": \"s.ply\", \"target\": \"t.ply\", \"gt\": null, \"status\": \"error\", "
                    "\"message\": \"source 's.ply': cannot read it: no such file\", \"valid\": false, "
                    "\"transform\": null}\n");
    CHECK(!cli_test::contains(batch_line_error(plain, false, "x"), "\"gt\""));

    // The scan reads the lines back, keys and all.
    const std::string two = ok + failed;
    ResultsScan scan = scan_results(two, "r");
    REQUIRE(scan.done.size() == 2);
    CHECK(scan.keep_bytes == two.size() && !scan.dropped_partial);
    CHECK(scan.done[0].pair == 3 && scan.done[0].source == row.source && scan.done[0].target == "t.ply" &&
          scan.done[0].valid && !scan.done[0].error && scan.done[0].line == 1);
    CHECK(scan.done[1].pair == 4 && scan.done[1].error && !scan.done[1].valid && scan.done[1].line == 2);
    // A killed run's last line: cut anywhere, even just before its newline, it is dropped.
    for (size_t cut = 0; cut < failed.size(); ++cut) {
        scan = scan_results(ok + failed.substr(0, cut), "r");
        CHECK_MSG(scan.done.size() == 1 && scan.keep_bytes == ok.size() && scan.dropped_partial == (cut > 0),
                  "cut at %zu: %zu records", cut, scan.done.size());
    }
    scan = scan_results(ok + "{\"pair\": 5}\n", "r"); // complete but not a record: the last line, dropped
    CHECK(scan.done.size() == 1 && scan.dropped_partial && scan.keep_bytes == ok.size());
    CHECK(scan_results("", "r").done.empty());
    const std::string middle = usage_error_of([&] { scan_results(ok + "{\"pair\": 5\n" + failed, "r"); });
    CHECK_MSG(middle.find("r line 2 is not a kissm batch record") == 0, "%s", middle.c_str());
    const std::string blank = usage_error_of([&] { scan_results(ok + "\n" + failed, "r"); });
    CHECK_MSG(blank.find("r line 2 is not") == 0, "%s", blank.c_str());
}

void test_batch_progress() {
    CHECK(progress_text(0, 40, 0.0) == "0/40 pairs (0%)");
    CHECK(progress_text(12, 40, 4.0) == "12/40 pairs (30%), 3 pairs/s, ETA 9 s");
    CHECK(progress_text(1, 1000, 2.0) == "1/1000 pairs (0%), 0.5 pairs/s, ETA 33 min");
    CHECK(progress_text(1, 10000, 2.0) == "1/10000 pairs (0%), 0.5 pairs/s, ETA 5.6 h");
    CHECK(progress_text(40, 40, 8.0) == "40/40 pairs (100%), 5 pairs/s, ETA 0 s");
    // One-line JSON: the batch's records.
    JsonWriter json(true);
    json.begin_object();
    json.field("a", 1.5);
    json.field_vector("v", std::vector<double>{1, 2}.data(), 2);
    json.key("o");
    json.begin_object();
    json.key("n");
    json.null();
    json.end_object();
    json.end_object();
    CHECK(json.str() == "{\"a\": 1.5, \"v\": [1, 2], \"o\": {\"n\": null}}\n");
}

} // namespace

int main() {
    RUN_TEST(test_checksums);
    RUN_TEST(test_deflate);
    RUN_TEST(test_png);
    RUN_TEST(test_json_writer);
    RUN_TEST(test_ply_writer);
    RUN_TEST(test_args);
    RUN_TEST(test_transform_file);
    RUN_TEST(test_result_json);
    RUN_TEST(test_summary_validity_measures);
    RUN_TEST(test_alignment_detail);
    RUN_TEST(test_rng);
    RUN_TEST(test_pose_math);
    RUN_TEST(test_demo_scene);
    RUN_TEST(test_batch_pairs);
    RUN_TEST(test_batch_lines_and_resume);
    RUN_TEST(test_batch_progress);
    return TEST_SUMMARY();
}
