// SPDX-License-Identifier: MIT
// Runs the kissm command-line tool as a user would (through the shell) and checks exit codes, messages,
// output files and JSON.
//
//   cli_test KISSM_BINARY WORK_DIR CASE
//
// CASE: usage | errors | malformed | demo | json | threads | realdata. Cases that need ../shared/data
// (KISSM_DATA_DIR) return 77 (skipped) when it is absent.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#if !defined(_WIN32)
#  include <sys/wait.h>
#endif

#include <kissm.h>

#include "cli_test_util.hpp"
#include "harness.h"
#include "ply_writer.hpp"

namespace fs = std::filesystem;
using namespace cli_test;

namespace {

std::string g_kissm; // the binary under test
std::string g_work;  // scratch folder of this case
int g_run_counter = 0;

constexpr double kRealVoxel = 0.5; // metres, for the KITTI keyframe pair

std::string quote(const std::string &s) {
#if defined(_WIN32)
    return "\"" + s + "\"";
#else
    std::string out = "'";
    for (char c : s) {
        if (c == '\'') {
            out += "'\\''";
        } else {
            out.push_back(c);
        }
    }
    return out + "'";
#endif
}

std::string work(const std::string &name) { return (fs::path(g_work) / name).string(); }

struct Run {
    int code = -1;
    std::string out, err;
};

// args is appended to the command line as is: quote paths with quote().
Run run(const std::string &args) {
    const int n = ++g_run_counter;
    const std::string out_path = work("run" + std::to_string(n) + ".out");
    const std::string err_path = work("run" + std::to_string(n) + ".err");
    const std::string command = quote(g_kissm) + " " + args + " >" + quote(out_path) + " 2>" + quote(err_path);
    const int status = std::system(command.c_str());
    Run r;
#if defined(_WIN32)
    r.code = status;
#else
    r.code = (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
#endif
    r.out = read_file(out_path);
    r.err = read_file(err_path);
    return r;
}

bool one_kissm_line(const std::string &err) {
    if (!starts_with(err, "kissm: ") || err.back() != '\n') return false;
    size_t lines = 0;
    for (char c : err) lines += c == '\n' ? 1u : 0u;
    return lines == 1;
}

// Expects exit status 2, nothing on stdout and exactly one "kissm: ..." line on stderr mentioning `about`.
void expect_usage_error(const std::string &args, const std::string &about) {
    const Run r = run(args);
    CHECK_MSG(r.code == 2, "'kissm %s' exited with %d, expected 2 (stderr: %s)", args.c_str(), r.code, r.err.c_str());
    CHECK_MSG(one_kissm_line(r.err), "'kissm %s': stderr is not one 'kissm: ' line: [%s]", args.c_str(), r.err.c_str());
    CHECK_MSG(r.out.empty(), "'kissm %s' printed on stdout: [%s]", args.c_str(), r.out.c_str());
    CHECK_MSG(about.empty() || contains(r.err, about), "'kissm %s': message [%s] does not mention '%s'", args.c_str(),
              r.err.c_str(), about.c_str());
}

// A small deterministic cloud (a box-shaped room) for the argument tests.
std::vector<double> room_points(size_t n) {
    std::vector<double> xyz;
    uint64_t state = 12345;
    const auto next = [&state]() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1.0p-53;
    };
    for (size_t i = 0; i < n; ++i) {
        double p[3] = {next() * 8.0, next() * 6.0, next() * 3.0};
        const size_t face = i % 3;
        p[face] = next() < 0.5 ? 0.0 : (face == 0 ? 8.0 : (face == 1 ? 6.0 : 3.0));
        xyz.insert(xyz.end(), p, p + 3);
    }
    return xyz;
}

bool write_cloud(const std::string &path, const std::vector<double> &xyz) {
    std::string error;
    const bool ok = kissm_cli::write_ply_xyz(path, xyz.data(), xyz.size() / 3, nullptr, {"cli_test"}, &error);
    if (!ok) std::fprintf(stderr, "%s\n", error.c_str());
    return ok;
}

// "element vertex N" of a PLY header, or -1.
long long ply_vertex_count(const std::string &bytes) {
    const size_t end = bytes.find("end_header\n");
    if (!starts_with(bytes, "ply\n") || end == std::string::npos) return -1;
    const std::string header = bytes.substr(0, end);
    if (!contains(header, "format binary_little_endian 1.0\n")) return -1;
    const size_t at = header.find("element vertex ");
    if (at == std::string::npos) return -1;
    return std::atoll(header.c_str() + at + 15);
}

// Reads a cloud back through the library's own reader (the tool's PLY files must be readable by it).
std::vector<double> read_back(const std::string &path) {
    kissm_cloud *cloud = nullptr;
    std::vector<double> xyz;
    if (kissm_read_points(path.c_str(), KISSM_FORMAT_AUTO, &cloud) == KISSM_OK) {
        const double *data = kissm_cloud_data(cloud);
        if (data) xyz.assign(data, data + 3 * kissm_cloud_count(cloud));
    } else {
        std::fprintf(stderr, "kissm_read_points(%s): %s\n", path.c_str(), kissm_last_error_message());
    }
    kissm_cloud_destroy(cloud);
    return xyz;
}

// Runs the demo into a folder of this case and returns its run.
Run run_demo(const std::string &dir, const std::string &extra) { return run("demo --out " + quote(dir) + " " + extra); }

// ---------------------------------------------------------------------------------------------------

void test_usage() {
    Run r = run("--help");
    CHECK_EQ_INT(r.code, 0);
    CHECK(contains(r.out, "usage"));
    CHECK(contains(r.out, "kissm register"));
    CHECK(contains(r.out, "kissm demo"));
    CHECK(r.err.empty());

    r = run("-h");
    CHECK_EQ_INT(r.code, 0);

    r = run("--version");
    CHECK_EQ_INT(r.code, 0);
    CHECK(contains(r.out, kissm_version_string()));
    CHECK(r.err.empty());

    r = run("register --help");
    CHECK_EQ_INT(r.code, 0);
    CHECK(contains(r.out, "usage: kissm register"));
    CHECK(contains(r.out, "--voxel"));
    CHECK(contains(r.out, "--json"));
    CHECK(contains(r.out, "--out-transform"));
    CHECK(contains(r.out, "--out-aligned"));
    CHECK(contains(r.out, "--format-src"));
    CHECK(r.err.empty());

    r = run("help register");
    CHECK_EQ_INT(r.code, 0);
    CHECK(contains(r.out, "usage: kissm register"));

    r = run("demo --help");
    CHECK_EQ_INT(r.code, 0);
    CHECK(contains(r.out, "usage: kissm demo"));
    CHECK(contains(r.out, "--seed"));

    expect_usage_error("", "missing command");
    expect_usage_error("frobnicate", "unknown command");
    expect_usage_error("--frobnicate", "--frobnicate");
    expect_usage_error("help frobnicate", "frobnicate");
}

void test_errors() {
    const std::string a = work("a.ply"), b = work("b.ply");
    REQUIRE(write_cloud(a, room_points(3000)));
    REQUIRE(write_cloud(b, room_points(3000)));
    const std::string ab = quote(a) + " " + quote(b);

    expect_usage_error("register " + ab + " --voxel 0.3 --bogus", "--bogus");
    expect_usage_error("register " + ab + " --bogus=1 --voxel 0.3", "--bogus");
    expect_usage_error("register " + ab, "--voxel");
    for (const char *bad : {"0", "-1", "-0.5", "nan", "NaN", "inf", "-inf", "abc", "0.3x", "1e999", "''", "' 0.3'"}) {
        expect_usage_error("register " + ab + " --voxel " + bad, "--voxel");
    }
    expect_usage_error("register " + ab + " --voxel=", "--voxel");
    expect_usage_error("register " + ab + " --voxel", "--voxel");
    expect_usage_error("register " + quote(a) + " --voxel 0.3", "2 files");
    expect_usage_error("register --voxel 0.3", "2 files");
    expect_usage_error("register " + ab + " " + quote(a) + " --voxel 0.3", "2 files");
    expect_usage_error("register " + ab + " --voxel 0.3 --threads -1", "--threads");
    expect_usage_error("register " + ab + " --voxel 0.3 --threads abc", "--threads");
    expect_usage_error("register " + ab + " --voxel 0.3 --threads 1.5", "--threads");
    expect_usage_error("register " + ab + " --voxel 0.3 --min-inliers 2", "--min-inliers");
    expect_usage_error("register " + ab + " --voxel 0.3 --max-correspondences x", "--max-correspondences");
    expect_usage_error("register " + ab + " --voxel 0.3 --format-src bogus", "bogus");
    expect_usage_error("register " + ab + " --voxel 0.3 --format-tgt", "--format-tgt");
    expect_usage_error("register " + ab + " --voxel 0.3 --json=yes", "--json");
    expect_usage_error("register " + ab + " --voxel 0.3 --out-transform", "--out-transform");

    // Missing and unreadable inputs.
    const std::string missing = work("does_not_exist.ply");
    expect_usage_error("register " + quote(missing) + " " + quote(b) + " --voxel 0.3", "source");
    expect_usage_error("register " + quote(a) + " " + quote(missing) + " --voxel 0.3", "target");
    expect_usage_error("register " + quote(g_work) + " " + quote(b) + " --voxel 0.3", "source");

    // Output that cannot be written.
    expect_usage_error("register " + ab + " --voxel 0.3 --out-transform " + quote(work("no/such/dir/T.txt")), "T.txt");

    expect_usage_error("demo --threads -2", "--threads");
    expect_usage_error("demo --seed abc", "--seed");
    expect_usage_error("demo --voxel 0", "--voxel");
    expect_usage_error("demo extra", "extra");
    expect_usage_error("demo --bogus", "--bogus");
}

void test_malformed() {
    const std::string good = work("good.ply");
    REQUIRE(write_cloud(good, room_points(3000)));

    // A binary PLY whose header promises more vertices than the file holds.
    std::string truncated = "ply\nformat binary_little_endian 1.0\nelement vertex 1000\n"
                            "property double x\nproperty double y\nproperty double z\nend_header\n";
    truncated.append(24 * 3, '\0');
    struct Case {
        const char *name;
        std::string bytes;
        const char *flags;
    };
    const std::vector<Case> cases = {
        {"truncated.ply", truncated, ""},
        {"garbage.ply", "this is not a point cloud\n", ""},
        {"header_only.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", ""},
        {"empty.xyz", "", ""},
        {"words.xyz", "1 2 3\n4 5 six\n7 8 9\n", ""},
        {"short.bin", "1234567", "--format-src bin_xyz"},
        {"short_kitti.bin", std::string(20, '\x01'), "--format-src kitti_bin"},
        {"bad.npy", "\x93NUMPY\x01\x00garbage", ""},
        {"bad.pcd", "# .PCD v0.7\nFIELDS x y z\nDATA ascii\n", ""},
    };
    for (const Case &c : cases) {
        const std::string path = work(c.name);
        REQUIRE(write_file(path, c.bytes));
        expect_usage_error("register " + quote(path) + " " + quote(good) + " --voxel 0.3 " + c.flags, "");
    }

    // Well-formed files the registration refuses: too few points, a NaN coordinate.
    const std::string two = work("two_points.ply");
    REQUIRE(write_cloud(two, {0, 0, 0, 1, 1, 1}));
    expect_usage_error("register " + quote(two) + " " + quote(good) + " --voxel 0.3", "");

    std::vector<double> with_nan = room_points(3000);
    with_nan[3 * 100 + 1] = std::nan("");
    const std::string nan_path = work("with_nan.ply");
    REQUIRE(write_cloud(nan_path, with_nan));
    expect_usage_error("register " + quote(nan_path) + " " + quote(good) + " --voxel 0.3", "");
    const Run dropped = run("register " + quote(nan_path) + " " + quote(good) + " --voxel 0.3 --drop-nonfinite --json");
    CHECK_MSG(dropped.code == 0 || dropped.code == 1, "--drop-nonfinite: exit %d, stderr %s", dropped.code,
              dropped.err.c_str());
    CHECK(json_valid(dropped.out));
    CHECK(contains(dropped.out, "\"source_nonfinite\": 1"));
}

void check_demo_files(const std::string &dir) {
    const std::string names[] = {"source.ply", "target.ply", "aligned_source.ply"};
    long long counts[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
        const std::string path = (fs::path(dir) / names[i]).string();
        std::string bytes;
        CHECK_MSG(read_file(path, &bytes), "%s is missing", path.c_str());
        counts[i] = ply_vertex_count(bytes);
        CHECK_MSG(counts[i] >= 20000 && counts[i] <= 80000, "%s: %lld vertices", path.c_str(), counts[i]);
        const size_t header = bytes.find("end_header\n") + 11;
        CHECK_MSG(bytes.size() == header + 24u * static_cast<size_t>(counts[i] > 0 ? counts[i] : 0),
                  "%s: %zu bytes for %lld float64 vertices", path.c_str(), bytes.size(), counts[i]);
        CHECK(contains(bytes.substr(0, header), "property double x\nproperty double y\nproperty double z\n"));
        const std::vector<double> back = read_back(path);
        CHECK_MSG(static_cast<long long>(back.size() / 3) == counts[i], "%s read back with %zu points", path.c_str(),
                  back.size() / 3);
    }
    CHECK_EQ_INT(counts[0], counts[2]);

    std::string png_bytes;
    const std::string png_path = (fs::path(dir) / "demo_topview.png").string();
    CHECK_MSG(read_file(png_path, &png_bytes), "%s is missing", png_path.c_str());
    try {
        const PngImage png = decode_png(png_bytes);
        CHECK(png.width >= 800 && png.height >= 400);
        size_t white = 0, orange = 0, blue = 0;
        for (size_t i = 0; i + 2 < png.rgb.size(); i += 3) {
            const int r = png.rgb[i], g = png.rgb[i + 1], b = png.rgb[i + 2];
            white += (r == 255 && g == 255 && b == 255) ? 1u : 0u;
            orange += (r > 200 && g > 90 && g < 200 && b < 120) ? 1u : 0u;
            blue += (b > 150 && r < 120 && g < 170) ? 1u : 0u;
        }
        const size_t pixels = png.rgb.size() / 3;
        CHECK_MSG(white > pixels / 2, "only %zu of %zu pixels are white", white, pixels);
        CHECK_MSG(orange > 1000, "only %zu orange (source) pixels", orange);
        CHECK_MSG(blue > 1000, "only %zu blue (target) pixels", blue);
    } catch (const std::exception &e) {
        CHECK_MSG(false, "%s: %s", png_path.c_str(), e.what());
    }
}

void test_demo() {
    const std::string dir = work("demo_out");
    const Run r = run_demo(dir, "");
    CHECK_MSG(r.code == 0, "kissm demo exited with %d\nstdout:\n%s\nstderr:\n%s", r.code, r.out.c_str(), r.err.c_str());
    CHECK(contains(r.out, "rotation error"));
    CHECK(contains(r.out, "translation error"));
    CHECK(contains(r.out, "valid: yes"));
    CHECK(contains(r.out, "SUCCESS"));
    CHECK(r.err.empty());
    check_demo_files(dir);
    std::printf("%s", r.out.c_str());
}

void check_result_json(const std::string &json, const char *what) {
    std::string error;
    CHECK_MSG(json_valid(json, &error), "%s: invalid JSON (%s):\n%s", what, error.c_str(), json.c_str());
    CHECK(starts_with(json, "{"));
    for (const char *key : {"\"version\"", "\"valid\"", "\"reason\"", "\"transform\"", "\"final_inliers\"",
                            "\"time_ms\"", "\"counts\"", "\"inlier_ratio\"", "\"residual_rms\"", "\"voxelize\"",
                            "\"features\"", "\"matching\"", "\"pruning\"", "\"solver\"", "\"total\""}) {
        CHECK_MSG(contains(json, key), "%s: %s is missing", what, key);
    }
    std::string values = json; // the literals nan/inf, not the key "information"
    for (size_t at = values.find("\"information\""); at != std::string::npos; at = values.find("\"information\""))
        values.erase(at, 13);
    CHECK_MSG(!contains(values, "nan") && !contains(values, "NaN") && !contains(values, "inf"),
              "%s: non-finite literal", what);
    CHECK_EQ_INT(numbers_in(json_line_value(json, "transform")).size(), 16);
}

void test_json() {
    const std::string dir = work("demo_out");
    const Run demo = run_demo(dir, "--json");
    CHECK_MSG(demo.code == 0, "kissm demo --json exited with %d: %s", demo.code, demo.err.c_str());
    check_result_json(demo.out, "demo --json");
    CHECK(contains(demo.out, "\"success\": true"));
    CHECK(contains(demo.out, "\"ground_truth\""));
    CHECK(contains(demo.out, "\"rotation_error_deg\""));

    const std::string source = (fs::path(dir) / "source.ply").string();
    const std::string target = (fs::path(dir) / "target.ply").string();
    const std::string transform_path = work("T.txt"), aligned_path = work("aligned.ply");
    const Run r =
        run("register " + quote(source) + " " + quote(target) + " --voxel 0.3 --refine gicp --json --out-transform " +
            quote(transform_path) + " --out-aligned " + quote(aligned_path));
    CHECK_MSG(r.code == 0, "register --json exited with %d: %s", r.code, r.err.c_str());
    check_result_json(r.out, "register --json");
    CHECK(contains(r.out, "\"valid\": true"));
    // The demo's PLY files hold float64 coordinates, so registering them reproduces the demo's refined pose
    // exactly, and its coarse pose without refinement.
    for (const char *key : {"transform", "coarse_transform", "information", "overlap"}) {
        CHECK_MSG(json_line_value(r.out, key) == json_line_value(demo.out, key),
                  "register on the demo files: %s %s\ndemo: %s", key, json_line_value(r.out, key).c_str(),
                  json_line_value(demo.out, key).c_str());
    }
    const Run coarse = run("register " + quote(source) + " " + quote(target) + " --voxel 0.3 --json");
    CHECK_EQ_INT(coarse.code, 0);
    CHECK(json_line_value(coarse.out, "transform") == json_line_value(demo.out, "coarse_transform"));
    CHECK(json_line_value(coarse.out, "information") == "null");

    // --out-transform: 4 lines of 4 numbers, the same doubles as the JSON.
    const std::string text = read_file(transform_path);
    const std::vector<double> from_file = numbers_in(text);
    const std::vector<double> from_json = numbers_in(json_line_value(r.out, "transform"));
    size_t lines = 0;
    for (char c : text) lines += c == '\n' ? 1u : 0u;
    CHECK_EQ_INT(lines, 4);
    REQUIRE(from_file.size() == 16 && from_json.size() == 16);
    for (int i = 0; i < 16; ++i)
        CHECK_MSG(from_file[i] == from_json[i], "element %d: %.17g vs %.17g", i, from_file[i], from_json[i]);

    // --out-aligned: the source moved by that transform.
    const std::vector<double> src = read_back(source), aligned = read_back(aligned_path);
    REQUIRE(src.size() == aligned.size() && !src.empty());
    double worst = 0.0;
    for (size_t i = 0; i < src.size(); i += 3) {
        for (int k = 0; k < 3; ++k) {
            const double *T = from_file.data() + 4 * k;
            const double expected = T[0] * src[i] + T[1] * src[i + 1] + T[2] * src[i + 2] + T[3];
            worst = std::fmax(worst, std::fabs(expected - aligned[i + static_cast<size_t>(k)]));
        }
    }
    CHECK_MSG(worst < 1e-9, "aligned cloud deviates by %g", worst);
}

struct RealPair {
    std::string source, target, source_format, target_format;
    double gt[16];
};

// The first KITTI keyframe pair of ../shared/data, or false when the data is absent.
bool load_real_pair(RealPair *pair) {
    const char *root = std::getenv("KISSM_DATA_DIR");
    if (!root || !*root) return false;
    const fs::path dataset = fs::path(root) / "kitti07_keyframes_gtsam_points";
    const fs::path dir = dataset / "pairs" / "000000__000001";
    std::string text;
    if (!read_file((dir / "pair.txt").string(), &text)) return false;
    const auto field = [&text](const std::string &key) {
        const size_t at = text.find(key + ": ");
        if (at == std::string::npos) return std::string();
        const size_t begin = at + key.size() + 2;
        return text.substr(begin, text.find('\n', begin) - begin);
    };
    pair->source = (dataset / field("source")).string();
    pair->target = (dataset / field("target")).string();
    pair->source_format = field("source_format");
    pair->target_format = field("target_format");
    const std::vector<double> gt = numbers_in(read_file((dir / "gt_T_target_source.txt").string()));
    if (gt.size() != 16 || !fs::exists(pair->source) || !fs::exists(pair->target)) return false;
    for (int i = 0; i < 16; ++i) pair->gt[i] = gt[static_cast<size_t>(i)];
    return true;
}

std::string real_pair_args(const RealPair &p) {
    return quote(p.source) + " " + quote(p.target) + " --format-src " + p.source_format + " --format-tgt " +
           p.target_format;
}

void test_threads() {
    // On the demo's scans (always available).
    const std::string dir = work("demo_out");
    std::string first;
    for (const char *threads : {"1", "2", "4"}) {
        const Run demo = run_demo(dir, std::string("--json --threads ") + threads);
        CHECK_MSG(demo.code == 0, "demo --threads %s exited with %d: %s", threads, demo.code, demo.err.c_str());
        const std::string t = json_line_value(demo.out, "transform");
        CHECK(!t.empty());
        if (first.empty()) first = t;
        CHECK_MSG(t == first, "demo --threads %s: %s\nvs %s", threads, t.c_str(), first.c_str());
    }
    const std::string files =
        quote((fs::path(dir) / "source.ply").string()) + " " + quote((fs::path(dir) / "target.ply").string());
    for (const char *threads : {"1", "2", "4"}) {
        const Run r = run("register " + files + " --voxel 0.3 --refine gicp --json --threads " + threads);
        CHECK_MSG(r.code == 0, "register --threads %s exited with %d: %s", threads, r.code, r.err.c_str());
        const std::string t = json_line_value(r.out, "transform");
        CHECK_MSG(t == first, "register --threads %s: %s\nvs %s", threads, t.c_str(), first.c_str());
    }

    // On a real pair when the data is there.
    RealPair pair;
    if (!load_real_pair(&pair)) {
        std::fprintf(stderr, "KISSM_DATA_DIR not set or incomplete: real-pair thread check skipped\n");
        return;
    }
    std::string real_first;
    for (const char *threads : {"1", "2", "4"}) {
        const Run r = run("register " + real_pair_args(pair) + " --voxel " + std::to_string(kRealVoxel) +
                          " --json --threads " + threads);
        CHECK_MSG(r.code == 0 || r.code == 1, "real pair --threads %s exited with %d: %s", threads, r.code,
                  r.err.c_str());
        const std::string t = json_line_value(r.out, "transform");
        if (real_first.empty()) real_first = t;
        CHECK_MSG(t == real_first, "real pair --threads %s: %s\nvs %s", threads, t.c_str(), real_first.c_str());
    }
}

int test_realdata() {
    RealPair pair;
    if (!load_real_pair(&pair)) {
        std::fprintf(stderr, "skipped: KISSM_DATA_DIR (../shared/data) is not available\n");
        return 77;
    }
    const Run r = run("register " + real_pair_args(pair) + " --voxel " + std::to_string(kRealVoxel) + " --json");
    CHECK_MSG(r.code == 0, "real pair: exit %d\n%s%s", r.code, r.out.c_str(), r.err.c_str());
    check_result_json(r.out, "real pair");
    const std::vector<double> T = numbers_in(json_line_value(r.out, "transform"));
    if (T.size() == 16) {
        double trace = 0.0;
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) trace += T[static_cast<size_t>(4 * i + j)] * pair.gt[4 * i + j];
        }
        const double rot_err =
            std::acos(std::fmax(-1.0, std::fmin(1.0, 0.5 * (trace - 1.0)))) * 57.295779513082320876798;
        const double trans_err = std::sqrt(std::pow(T[3] - pair.gt[3], 2) + std::pow(T[7] - pair.gt[7], 2) +
                                           std::pow(T[11] - pair.gt[11], 2));
        std::printf(
            "KITTI 07 keyframes 000001 -> 000000 (voxel %g): rotation error %.4f deg, translation error %.4f m\n",
            kRealVoxel, rot_err, trans_err);
        CHECK_MSG(rot_err < 5.0 && trans_err < 2.0, "rotation error %g deg, translation error %g m", rot_err,
                  trans_err);
    }

    // The human summary names every stage.
    const Run human = run("register " + real_pair_args(pair) + " --voxel " + std::to_string(kRealVoxel));
    CHECK_EQ_INT(human.code, r.code);
    for (const char *word : {"valid: yes", "voxels", "keypoints", "final inliers", "inlier ratio", "residual rms",
                             "voxelize", "features", "matching", "pruning", "solver", "total"}) {
        CHECK_MSG(contains(human.out, word), "summary lacks '%s':\n%s", word, human.out.c_str());
    }
    std::printf("%s", human.out.c_str());
    return TEST_SUMMARY();
}

} // namespace

int main(int argc, char **argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: cli_test KISSM_BINARY WORK_DIR CASE\n");
        return 2;
    }
    g_kissm = argv[1];
    g_work = argv[2];
    const std::string which = argv[3];
    std::error_code ec;
    fs::remove_all(g_work, ec);
    fs::create_directories(g_work, ec);
    if (ec) {
        std::fprintf(stderr, "cannot create %s: %s\n", g_work.c_str(), ec.message().c_str());
        return 2;
    }
    if (which == "usage") {
        RUN_TEST(test_usage);
    } else if (which == "errors") {
        RUN_TEST(test_errors);
    } else if (which == "malformed") {
        RUN_TEST(test_malformed);
    } else if (which == "demo") {
        RUN_TEST(test_demo);
    } else if (which == "json") {
        RUN_TEST(test_json);
    } else if (which == "threads") {
        RUN_TEST(test_threads);
    } else if (which == "realdata") {
        return test_realdata();
    } else {
        std::fprintf(stderr, "unknown case '%s'\n", which.c_str());
        return 2;
    }
    return TEST_SUMMARY();
}
