// SPDX-License-Identifier: MIT
// Runs the kissm command-line tool as a user would (through the shell) and checks exit codes, messages,
// output files and JSON.
//
//   cli_test KISSM_BINARY WORK_DIR CASE
//
// CASE: usage | errors | malformed | demo | json | threads | realdata | refine_options | refine_register |
// refine_command | refine_initial | refine_roundtrip | validity_options | refine_rule_options | ground_options |
// ground_command. Cases that need
// ../shared/data (KISSM_DATA_DIR) return 77 (skipped) when it is absent; the refine and validity cases use the
// committed pair of tests/data (KISSM_TEST_DATA).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#if !defined(_WIN32)
#  include <sys/wait.h>
#endif

#include <kissm.h>

#include "cli_case_main.hpp"
#include "cli_result_check.hpp"
#include "cli_test_util.hpp"
#include "harness.h"
#include "ply_writer.hpp"
#include "pose_math.hpp"
#include "transform_file.hpp"

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

// The committed pair (tests/data/roundtrip_*) and its ground truth, at golden.json's voxel sizes.
struct CommittedPair {
    std::string source, target, truth_path;
    double truth[16];
};

bool load_committed_pair(CommittedPair *pair) {
    const char *dir = std::getenv("KISSM_TEST_DATA");
    if (!dir || !*dir) return false;
    pair->source = (fs::path(dir) / "roundtrip_source.ply").string();
    pair->target = (fs::path(dir) / "roundtrip_target.ply").string();
    pair->truth_path = (fs::path(dir) / "roundtrip_ground_truth.txt").string();
    std::string error;
    if (!kissm_cli::read_transform_file(pair->truth_path, pair->truth, &error)) {
        std::fprintf(stderr, "%s\n", error.c_str());
        return false;
    }
    return true;
}

std::string pair_args(const CommittedPair &p) { return quote(p.source) + " " + quote(p.target); }

struct PoseError {
    double deg, m;
};

PoseError error_of(const std::vector<double> &T, const double truth[16]) {
    if (T.size() != 16) return {std::nan(""), std::nan("")};
    return {kissm_pose::rotation_error_deg(T.data(), truth), kissm_pose::translation_error(T.data(), truth)};
}

// A run's stdout as JSON, checked against the contract.
Json contract_json(const Run &r, bool refine_command, const char *what) {
    std::string error;
    const Json j = json_parse(r.out, &error);
    CHECK_MSG(error.empty(), "%s: invalid JSON (%s):\n%s", what, error.c_str(), r.out.c_str());
    check_contract(j, refine_command, what);
    return j;
}

std::string help_line(const std::string &help, const std::string &option) {
    const size_t at = help.find("\n  " + option + " ");
    if (at == std::string::npos) return std::string();
    return help.substr(at + 1, help.find('\n', at + 1) - at - 1);
}

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

    // The refinement options, with the defaults kissm_config_init gives.
    kissm_config defaults{};
    REQUIRE(kissm_config_init(&defaults, sizeof defaults) == KISSM_OK);
    char expected[6][64];
    std::snprintf(expected[0], sizeof expected[0], "(default %d)", defaults.refine_max_iterations);
    std::snprintf(expected[1], sizeof expected[1], "(default %g)", defaults.refine_max_distance_gain);
    std::snprintf(expected[2], sizeof expected[2], "(default %g)", defaults.min_overlap);
    std::snprintf(expected[3], sizeof expected[3], "(default %g)", defaults.min_refine_condition);
    std::snprintf(expected[4], sizeof expected[4], "(default %g)", defaults.refine_normal_radius_gain);
    std::snprintf(expected[5], sizeof expected[5], "(default %g)", defaults.max_refine_rmse_gain);
    const char *options[6] = {"--refine-iterations",    "--refine-distance",      "--min-overlap",
                              "--min-refine-condition", "--refine-normal-radius", "--max-refine-rmse"};
    for (const char *command : {"register --help", "refine --help", "help refine"}) {
        r = run(command);
        CHECK_EQ_INT(r.code, 0);
        CHECK(r.err.empty());
        CHECK(contains(r.out, "--refine MODE"));
        for (int i = 0; i < 6; ++i) {
            const std::string line = help_line(r.out, options[i]);
            CHECK_MSG(contains(line, expected[i]), "'kissm %s': [%s] lacks %s", command, line.c_str(), expected[i]);
        }
    }
    CHECK(contains(help_line(run("register --help").out, "--refine"), "(default none)"));
    // The validity rules' options, register only, with the library's defaults.
    char validity[3][64];
    std::snprintf(validity[0], sizeof validity[0], "(default %g, i.e. %.3g deg)", defaults.max_rotation_uncertainty,
                  kissm_pose::rad_to_deg(defaults.max_rotation_uncertainty));
    std::snprintf(validity[1], sizeof validity[1], "(default %d)", defaults.refine_min_inliers);
    std::snprintf(validity[2], sizeof validity[2], "(default %g)", defaults.min_inlier_coverage);
    const char *validity_options[3] = {"--max-rotation-uncertainty", "--refine-min-inliers", "--min-inlier-coverage"};
    const std::string register_help = run("register --help").out, refine_help = run("refine --help").out;
    for (int i = 0; i < 3; ++i) {
        const std::string line = help_line(register_help, validity_options[i]);
        CHECK_MSG(contains(line, validity[i]), "'kissm register --help': [%s] lacks %s", line.c_str(), validity[i]);
        CHECK_MSG(!contains(refine_help, validity_options[i]), "'kissm refine --help' offers %s", validity_options[i]);
    }
    r = run("refine --help");
    CHECK(contains(r.out, "usage: kissm refine"));
    CHECK(contains(help_line(r.out, "--refine"), "(default gicp)"));
    CHECK(contains(r.out, "--initial FILE"));
    CHECK(contains(r.out, "--out-transform"));
    CHECK(!contains(r.out, "--min-inliers"));
    CHECK(contains(run("--help").out, "kissm refine"));

    r = run("demo --help");
    CHECK_EQ_INT(r.code, 0);
    CHECK(contains(r.out, "usage: kissm demo"));
    CHECK(contains(r.out, "--seed"));

    expect_usage_error("", "missing command");
    expect_usage_error("frobnicate", "unknown command");
    CHECK(!contains(run("frobnicate").err, "did you mean")); // nothing near: no guess
    expect_usage_error("--frobnicate", "--frobnicate");
    expect_usage_error("help frobnicate", "frobnicate");
    // Issue 36: a typo names the nearest command or option, taken from the --help texts.
    expect_usage_error("regster a b", "unknown command 'regster' (did you mean 'register'?)");
    expect_usage_error("aling", "(did you mean 'align'?)");
    expect_usage_error("help regster", "(did you mean 'register'?)");
    expect_usage_error("--verison", "(did you mean '--version'?)");
    expect_usage_error("register a b --vxoel 0.3",
                       "unknown option '--vxoel' for 'kissm register' (did you mean '--voxel'?)");
    expect_usage_error("register a b --voxel=0.3 --refne gicp", "(did you mean '--refine'?)");
    expect_usage_error("align s.tsv --voxel 1 --out o --pairz all", "(did you mean '--pairs'?)");
    expect_usage_error("batch p.tsv --voxel 1 --out o --resum", "(did you mean '--resume'?)");
}

void test_errors() {
    const std::string a = work("a.ply"), b = work("b.ply");
    REQUIRE(write_cloud(a, room_points(3000)));
    REQUIRE(write_cloud(b, room_points(3000)));
    const std::string ab = quote(a) + " " + quote(b);

    expect_usage_error("register " + ab + " --voxel 0.3 --bogus", "--bogus");
    expect_usage_error("register " + ab + " --bogus=1 --voxel 0.3", "--bogus");
    expect_usage_error("register " + ab, "--voxel auto"); // the message names the automatic choice
    expect_usage_error("register " + ab + " --voxel Auto", "--voxel");
    {
        // Too few voxels says what the voxel should be (issue 36): the room is 8 wide (its largest side, to the
        // last point drawn) and --voxel auto's choice; the JSON on stdout is unchanged by it.
        const Run coarse = run("register " + ab + " --voxel 50 --json");
        CHECK_EQ_INT(coarse.code, 1);
        CHECK_MSG(contains(coarse.err,
                           "kissm: hint: the clouds span 8 and 8 (their bounding boxes' largest sides), too "
                           "few voxels of 50 to describe; --voxel auto would use "),
                  "%s", coarse.err.c_str());
        CHECK(json_parse(coarse.out).at("reason_code").number == KISSM_REASON_TOO_FEW_VOXELS);
        CHECK(!contains(run("register " + ab + " --voxel 0.3").err, "hint"));
    }
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
    expect_usage_error("register " + ab + " --voxel 0.3 --max-correspondences -1", "--max-correspondences");
    expect_usage_error("register " + ab + " --voxel 0.3 --max-correspondences 2", "--max-correspondences");
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
    CHECK(contains(r.out, "coarse pose (solver): rotation error"));
    CHECK(contains(r.out, "refined pose (gicp):  rotation error"));
    CHECK(contains(r.out, "refinement:"));
    CHECK(contains(r.out, "valid: yes"));
    CHECK(contains(r.out, "SUCCESS"));
    CHECK(r.err.empty());
    check_demo_files(dir);
    std::printf("%s", r.out.c_str());

    // The same seed gives the same files, byte for byte (the picture included), whatever the thread count.
    const std::string again = work("demo_again");
    const Run r2 = run_demo(again, "--threads 1");
    CHECK_EQ_INT(r2.code, 0);
    for (const char *name : {"source.ply", "target.ply", "aligned_source.ply", "demo_topview.png"}) {
        const std::string a = read_file((fs::path(dir) / name).string());
        CHECK_MSG(!a.empty() && a == read_file((fs::path(again) / name).string()), "%s differs between two runs", name);
    }
    // The picture has the coarse and refined details: two rows of two panels.
    try {
        const PngImage png = decode_png(read_file((fs::path(dir) / "demo_topview.png").string()));
        CHECK_MSG(png.width > 1000 && png.height > 1000, "demo_topview.png is %ux%u", png.width, png.height);
    } catch (const std::exception &e) {
        CHECK_MSG(false, "demo_topview.png: %s", e.what());
    }

    // Without refinement the demo still works, with the before/after picture only.
    const Run plain = run_demo(work("demo_plain"), "--refine none --json");
    CHECK_MSG(plain.code == 0, "demo --refine none: exit %d (%s)", plain.code, plain.err.c_str());
    const Json p = json_parse(plain.out);
    CHECK(p.at("refine").text == "none" && p.at("information").is(Json::Type::Null));
    CHECK(p.at("rotation_error_deg").text == p.at("coarse_rotation_error_deg").text);
    try {
        const PngImage png = decode_png(read_file((fs::path(work("demo_plain")) / "demo_topview.png").string()));
        CHECK_MSG(png.width > png.height, "demo --refine none picture is %ux%u", png.width, png.height);
    } catch (const std::exception &e) {
        CHECK_MSG(false, "demo --refine none picture: %s", e.what());
    }
    expect_usage_error("demo --refine bogus", "--refine");
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
    // The refined pose is closer to the truth than the solver's.
    const Json d = json_parse(demo.out);
    CHECK(d.at("refine").text == "gicp" && d.at("information").is_matrix(6, 6, false));
    const double rot = d.at("rotation_error_deg").as_double(),
                 coarse_rot = d.at("coarse_rotation_error_deg").as_double();
    const double tra = d.at("translation_error_m").as_double(),
                 coarse_tra = d.at("coarse_translation_error_m").as_double();
    std::printf("demo: coarse error %.4f deg %.4f m, refined %.4f deg %.4f m\n", coarse_rot, coarse_tra, rot, tra);
    CHECK_MSG(rot < coarse_rot && tra < coarse_tra, "demo: refined %g deg %g m, coarse %g deg %g m", rot, tra,
              coarse_rot, coarse_tra);

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
    CHECK(json_parse(coarse.out).at("voxel_size_used").as_double() == 0.3);
    // --voxel auto: the library's suggestion for the pair (kissm_suggest_voxel_size), the same in voxel_size and
    // voxel_size_used, and the registration at that voxel given.
    const Run automatic = run("register " + quote(source) + " " + quote(target) + " --voxel auto --json");
    CHECK_MSG(automatic.code == 0, "register --voxel auto exited with %d: %s", automatic.code, automatic.err.c_str());
    check_result_json(automatic.out, "register --voxel auto");
    const Json a = json_parse(automatic.out);
    CHECK(a.at("voxel_size").text == a.at("voxel_size_used").text && a.at("voxel_size_used").as_double() > 0.0);
    const Run given =
        run("register " + quote(source) + " " + quote(target) + " --voxel " + a.at("voxel_size_used").text + " --json");
    CHECK(json_line_value(given.out, "transform") == json_line_value(automatic.out, "transform"));
    // ... and `kissm batch --voxel auto` takes one voxel for all the file's clouds: here the pair's.
    const std::string pairs = work("auto_pairs.tsv"), results = work("auto_results.jsonl");
    REQUIRE(write_file(pairs, "source\ttarget\n" + source + "\t" + target + "\n"));
    const Run batch = run("batch " + quote(pairs) + " --voxel auto --quiet --out " + quote(results));
    CHECK_MSG(batch.code == 0, "batch --voxel auto exited with %d: %s", batch.code, batch.err.c_str());
    CHECK(contains(read_file(results), "\"voxel_size_used\": " + a.at("voxel_size_used").text));
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

    // Refinement brings the pose closer to the ground truth.
    const Run refined =
        run("register " + real_pair_args(pair) + " --voxel " + std::to_string(kRealVoxel) + " --refine gicp --json");
    CHECK_MSG(refined.code == 0, "real pair --refine gicp: exit %d\n%s", refined.code, refined.err.c_str());
    const Json j = contract_json(refined, false, "real pair --refine gicp");
    const PoseError coarse = error_of(j.at("coarse_transform").flat(), pair.gt);
    const PoseError fine = error_of(j.at("transform").flat(), pair.gt);
    std::printf("KITTI 07 keyframes with GICP: coarse %.4f deg %.4f m, refined %.4f deg %.4f m\n", coarse.deg, coarse.m,
                fine.deg, fine.m);
    CHECK_MSG(fine.deg < coarse.deg && fine.m < coarse.m, "refined %g deg %g m, coarse %g deg %g m", fine.deg, fine.m,
              coarse.deg, coarse.m);

    // The human summary names every stage.
    const Run human = run("register " + real_pair_args(pair) + " --voxel " + std::to_string(kRealVoxel));
    CHECK_EQ_INT(human.code, r.code);
    for (const char *word : {"valid: yes", "voxels", "keypoints", "final inliers", "inlier ratio", "residual rms",
                             "voxelize", "features", "matching", "pruning", "solver", "refine", "total"}) {
        CHECK_MSG(contains(human.out, word), "summary lacks '%s':\n%s", word, human.out.c_str());
    }
    std::printf("%s", human.out.c_str());
    return TEST_SUMMARY();
}

// ---------------------------------------------------------------------------------------------------
// Refinement: register --refine, refine --initial.
// ---------------------------------------------------------------------------------------------------

void test_refine_options() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    const std::string reg = "register " + pair_args(pair) + " --voxel 0.25 --refine gicp ";
    const std::string ref = "refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(pair.truth_path) + " ";

    // Not numbers, or not a mode: the tool's own message naming the option.
    for (const char *bad : {"bogus", "GICP", "icp", "''"}) expect_usage_error(reg + "--refine " + bad, "--refine");
    for (const char *bad : {"abc", "1.5", "99999999999", "''"}) {
        expect_usage_error(reg + "--refine-iterations " + bad, "--refine-iterations");
    }
    for (const char *bad : {"abc", "nan", "inf", "1e999"}) {
        expect_usage_error(reg + "--refine-distance " + bad, "--refine-distance");
        expect_usage_error(ref + "--min-overlap " + bad, "--min-overlap");
    }
    // Numbers out of range: the library's validation message (it names the config field), after the option.
    for (const char *bad : {"0", "-3", "1001"}) {
        expect_usage_error(reg + "--refine-iterations " + bad, "--refine-iterations: config.refine_max_iterations");
        expect_usage_error(ref + "--refine-iterations " + bad, "config.refine_max_iterations");
    }
    for (const char *bad : {"0", "-1", "100.5"}) {
        expect_usage_error(reg + "--refine-distance " + bad, "--refine-distance: config.refine_max_distance_gain");
    }
    for (const char *bad : {"-0.1", "1.5"}) {
        expect_usage_error(reg + "--min-overlap " + bad, "--min-overlap: config.min_overlap");
        expect_usage_error(ref + "--min-overlap " + bad, "config.min_overlap");
    }
    // The refine command's own rules.
    expect_usage_error("refine " + pair_args(pair) + " --voxel 0.25", "--initial");
    expect_usage_error("refine " + pair_args(pair) + " --voxel 0.25 --initial", "--initial");
    expect_usage_error("refine " + quote(pair.source) + " --voxel 0.25 --initial " + quote(pair.truth_path), "2 files");
    expect_usage_error("refine " + pair_args(pair) + " --initial " + quote(pair.truth_path), "--voxel");
    expect_usage_error(ref + "--refine none", "none");
    expect_usage_error(ref + "--min-inliers 5", "--min-inliers");
    expect_usage_error(ref + "--max-correspondences 50", "--max-correspondences");
    expect_usage_error(reg + "--initial " + quote(pair.truth_path), "--initial");

    // The settings reach the library: each changes the outcome as it should.
    const Run strict = run(reg + "--min-overlap 0.999 --json");
    CHECK_MSG(strict.code == 1, "--min-overlap 0.999: exit %d (%s)", strict.code, strict.err.c_str());
    const Json s = contract_json(strict, false, "--min-overlap 0.999");
    CHECK(!s.at("valid").boolean);
    CHECK_EQ_INT(static_cast<int>(s.at("reason_code").number), KISSM_REASON_LOW_OVERLAP);
    CHECK(s.at("overlap").as_double() < 0.999);
    const Run lenient = run(reg + "--min-overlap 0.5 --json");
    CHECK_MSG(lenient.code == 0, "--min-overlap 0.5: exit %d (%s)", lenient.code, lenient.err.c_str());

    const Run one = run(reg + "--refine-iterations 1 --json");
    CHECK_MSG(one.code == 0 || one.code == 1, "--refine-iterations 1: exit %d (%s)", one.code, one.err.c_str());
    CHECK_EQ_INT(static_cast<int>(contract_json(one, false, "--refine-iterations 1").at("refine_iterations").number),
                 1);

    const Json near_ = contract_json(run(reg + "--refine-distance 0.5 --json"), false, "--refine-distance 0.5");
    const Json far_ = contract_json(run(reg + "--refine-distance 6 --json"), false, "--refine-distance 6");
    CHECK_MSG(near_.at("overlap").as_double() < far_.at("overlap").as_double(),
              "overlap within 0.5 voxel %g, within 6 voxels %g", near_.at("overlap").as_double(),
              far_.at("overlap").as_double());
}

void check_refined_beats_coarse(const Json &j, const double truth[16], const char *what) {
    const PoseError coarse = error_of(j.at("coarse_transform").flat(), truth);
    const PoseError refined = error_of(j.at("transform").flat(), truth);
    std::printf("%s: coarse error %.4f deg %.4f m, refined %.4f deg %.4f m\n", what, coarse.deg, coarse.m, refined.deg,
                refined.m);
    CHECK_MSG(refined.deg < coarse.deg && refined.m < coarse.m, "%s: refined %g deg %g m, coarse %g deg %g m", what,
              refined.deg, refined.m, coarse.deg, coarse.m);
    CHECK_MSG(refined.deg < 0.1 && refined.m < 0.02, "%s: refined %g deg %g m", what, refined.deg, refined.m);
}

void test_refine_register() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    const struct {
        const char *mode;
        int32_t code;
        double voxel;
    } modes[] = {{"gicp", KISSM_REFINE_GICP, 0.25}, {"point-to-plane", KISSM_REFINE_POINT_TO_PLANE, 0.3}};
    for (const auto &m : modes) {
        char voxel[32];
        std::snprintf(voxel, sizeof voxel, "%g", m.voxel);
        const std::string what = std::string("register --refine ") + m.mode;
        const Run r = run("register " + pair_args(pair) + " --voxel " + voxel + " --refine " + m.mode + " --json");
        CHECK_MSG(r.code == 0, "%s: exit %d (%s)", what.c_str(), r.code, r.err.c_str());
        const Json j = contract_json(r, false, what.c_str());
        CHECK(j.at("valid").boolean);
        CHECK(j.at("refine").text == m.mode);
        CHECK(j.at("information").is_matrix(6, 6, false));
        CHECK(j.at("refine_iterations").number >= 1 && j.at("counts").at("refine_correspondences").number > 0);
        CHECK(j.at("overlap").number > 0.5 && j.at("overlap").number <= 1.0);
        CHECK(j.at("time_ms").at("refine").number > 0.0);
        check_refined_beats_coarse(j, pair.truth, what.c_str());
        kissm_result lib{};
        REQUIRE(library_result(pair.source, pair.target, m.voxel, m.code, nullptr, &lib));
        check_matches_library(j, lib, what.c_str());
    }

    // Without refinement: the solver's pose, and the refinement's fields empty.
    const Run plain = run("register " + pair_args(pair) + " --voxel 0.25 --json");
    CHECK_MSG(plain.code == 0, "register: exit %d (%s)", plain.code, plain.err.c_str());
    const Json p = contract_json(plain, false, "register");
    CHECK(p.at("refine").text == "none");
    CHECK(p.at("information").is(Json::Type::Null));
    CHECK(p.at("overlap").is(Json::Type::Null) && p.at("refine_rmse").is(Json::Type::Null) &&
          p.at("refine_condition").is(Json::Type::Null));
    CHECK(p.at("refine_iterations").text == "0" && !p.at("refine_converged").boolean);
    CHECK(p.at("counts").at("refine_correspondences").text == "0" && p.at("time_ms").at("refine").number == 0.0);
    CHECK(json_line_value(plain.out, "coarse_transform") == json_line_value(plain.out, "transform"));
    kissm_result lib{};
    REQUIRE(library_result(pair.source, pair.target, 0.25, KISSM_REFINE_NONE, nullptr, &lib));
    check_matches_library(p, lib, "register");

    // The summary shows the refinement.
    const Run human = run("register " + pair_args(pair) + " --voxel 0.25 --refine gicp");
    CHECK_EQ_INT(human.code, 0);
    for (const char *word :
         {"refinement gicp", "refined transform", "coarse transform", "refinement:", "converged", "overlap",
          "inlier coverage", "rmse", "condition", "moved the coarse pose", "refine ", "rotation uncertainty:"}) {
        CHECK_MSG(contains(human.out, word), "summary lacks '%s':\n%s", word, human.out.c_str());
    }
    const Run human_plain = run("register " + pair_args(pair) + " --voxel 0.25");
    CHECK(!contains(human_plain.out, "refinement:") && !contains(human_plain.out, "coarse transform"));
}

// %.17g: the double itself on the command line.
std::string exact(double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

// A run's reason code, checked against its exit status and reason text.
int reason_of(const Run &r, const char *what, bool refine_command = false) {
    const Json j = contract_json(r, refine_command, what);
    const int code = static_cast<int>(j.at("reason_code").number);
    CHECK_MSG(r.code == (code == KISSM_REASON_NONE ? 0 : 1), "%s: exit %d with reason %d (%s)", what, r.code, code,
              r.err.c_str());
    CHECK_MSG(j.at("reason").text == kissm_reason_string(code), "%s: reason '%s' for code %d", what,
              j.at("reason").text.c_str(), code);
    return code;
}

// A validity setting (`option`, after `command`) at exactly the value `measured` the `base` run reported under
// `key` keeps the pose valid; one ulp toward `beyond` refuses it for `reason`, and only the decision moves: the
// pose and the measure are the base run's.
void check_decision_flips(const std::string &command, const std::string &option, const char *key, double measured,
                          double beyond, int reason, const Run &base, bool refine_command = false) {
    const std::string at = option + " at the measured " + key, past = option + " one ulp past the measured " + key;
    CHECK_EQ_INT(reason_of(run(command + option + " " + exact(measured) + " --json"), at.c_str(), refine_command),
                 KISSM_REASON_NONE);
    const Run beyond_run = run(command + option + " " + exact(std::nextafter(measured, beyond)) + " --json");
    CHECK_EQ_INT(reason_of(beyond_run, past.c_str(), refine_command), reason);
    for (const char *k : {"transform", key}) {
        CHECK_MSG(json_line_value(beyond_run.out, k) == json_line_value(base.out, k), "%s: %s moved", past.c_str(), k);
    }
}

// --max-rotation-uncertainty, --refine-min-inliers and --min-inlier-coverage: the tool's and the library's
// range checks, refused by `refine`, and each moves the decision exactly at the value the JSON reports.
void test_validity_options() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    const std::string plain = "register " + pair_args(pair) + " --voxel 0.25 ";
    const std::string reg = plain + "--refine gicp ";
    const std::string ref = "refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(pair.truth_path) + " ";

    for (const char *bad : {"abc", "nan", "inf", "''"}) {
        expect_usage_error(plain + "--max-rotation-uncertainty " + bad, "--max-rotation-uncertainty");
        expect_usage_error(reg + "--min-inlier-coverage " + bad, "--min-inlier-coverage");
    }
    for (const char *bad : {"abc", "1.5", "99999999999"}) {
        expect_usage_error(reg + "--refine-min-inliers " + bad, "--refine-min-inliers");
    }
    for (const char *bad : {"0", "-0.01", "3.2"}) {
        expect_usage_error(plain + "--max-rotation-uncertainty " + bad,
                           "--max-rotation-uncertainty: config.max_rotation_uncertainty");
    }
    for (const char *bad : {"-0.1", "1.01"}) {
        expect_usage_error(reg + "--min-inlier-coverage " + bad, "--min-inlier-coverage: config.min_inlier_coverage");
    }
    for (const char *bad : {"2", "-5", "100001"}) {
        expect_usage_error(reg + "--refine-min-inliers " + bad, "--refine-min-inliers: config.refine_min_inliers");
    }
    // kissm_refine has no solver inliers to judge.
    for (const char *option : {"--max-rotation-uncertainty", "--min-inlier-coverage", "--refine-min-inliers"}) {
        expect_usage_error(ref + option + " 0.5", option);
    }

    // Without refinement: the rule's boundary is the rotation uncertainty the JSON reports.
    const Run base = run(plain + "--json");
    CHECK_MSG(base.code == 0, "register: exit %d (%s)", base.code, base.err.c_str());
    const Json b = contract_json(base, false, "register");
    const double u = b.at("rotation_uncertainty").as_double();
    const uint64_t inliers = static_cast<uint64_t>(b.at("final_inliers").number);
    CHECK_MSG(std::isfinite(u) && u > 0.0, "rotation_uncertainty %s", b.at("rotation_uncertainty").text.c_str());
    CHECK(b.at("inlier_coverage").is(Json::Type::Null));
    // A bound below twice the uncertainty (kCoarseConfirmSigmas) has the pose verified by refinement (GICP) under the
    // refined rule: held to a coverage no inlier set reaches, the verification fails and the pose is not valid, for
    // the verification's reason; one ulp past the uncertainty itself the coarse rule declines first and its reason
    // stands. The coarse pose is kept either way.
    check_decision_flips(plain + "--min-inlier-coverage 1 ", "--max-rotation-uncertainty", "rotation_uncertainty",
                         2.0 * u, 0.0, KISSM_REASON_CLUSTERED_INLIERS, base);
    {
        const Run declined = run(plain + "--min-inlier-coverage 1 --max-rotation-uncertainty " +
                                 exact(std::nextafter(u, 0.0)) + " --json");
        CHECK_EQ_INT(reason_of(declined, "one ulp past the uncertainty"), KISSM_REASON_UNCERTAIN_ROTATION);
        CHECK(json_line_value(declined.out, "transform") == json_line_value(base.out, "transform"));
        CHECK_EQ_INT(
            reason_of(run(plain + "--min-inlier-coverage 1 --max-rotation-uncertainty " + exact(u) + " --json"),
                      "at the uncertainty, verified and refused"),
            KISSM_REASON_CLUSTERED_INLIERS);
    }
    {
        // Under the default refined rule the verification accepts it: the refined pose, valid, the solver's pose kept
        // as coarse_transform, the refinement's numbers reported.
        const Run verified = run(plain + "--max-rotation-uncertainty " + exact(std::nextafter(u, 0.0)) + " --json");
        CHECK_EQ_INT(reason_of(verified, "verified by refinement"), KISSM_REASON_NONE);
        const Json v = contract_json(verified, false, "verified by refinement");
        CHECK(v.at("refine_iterations").number > 0 && v.at("information").is_matrix(6, 6, false));
        CHECK(json_line_value(verified.out, "coarse_transform") == json_line_value(base.out, "transform"));
        CHECK(json_line_value(verified.out, "transform") != json_line_value(base.out, "transform"));
    }
    // Each rule ignores the other's settings.
    CHECK_EQ_INT(reason_of(run(reg + "--max-rotation-uncertainty " + exact(std::nextafter(u, 0.0)) + " --json"),
                           "refined, strict rotation"),
                 KISSM_REASON_NONE);
    CHECK_EQ_INT(reason_of(run(plain + "--refine-min-inliers " + std::to_string(inliers + 1) +
                               " --min-inlier-coverage 1 --json"),
                           "unrefined, strict refined rule"),
                 KISSM_REASON_NONE);

    // The summary shows the same uncertainty in degrees (4 significant digits).
    const Run human = run(plain);
    const size_t at = human.out.find("\nrotation uncertainty: ");
    REQUIRE(at != std::string::npos);
    const double deg = std::atof(human.out.c_str() + at + 23);
    CHECK_MSG(std::fabs(deg - kissm_pose::rad_to_deg(u)) <= 5e-4 * kissm_pose::rad_to_deg(u),
              "summary says %g deg, the JSON %.17g rad", deg, u);

    // With refinement: at least refine_min_inliers final inliers, covering at least min_inlier_coverage.
    const Run fine = run(reg + "--json");
    CHECK_MSG(fine.code == 0, "register --refine gicp: exit %d (%s)", fine.code, fine.err.c_str());
    const Json f = contract_json(fine, false, "register --refine gicp");
    const double coverage = f.at("inlier_coverage").as_double();
    const uint64_t fine_inliers = static_cast<uint64_t>(f.at("final_inliers").number);
    CHECK_MSG(coverage > 0.0 && coverage < 1.0, "inlier_coverage %s", f.at("inlier_coverage").text.c_str());
    check_decision_flips(reg, "--min-inlier-coverage", "inlier_coverage", coverage, 2.0, KISSM_REASON_CLUSTERED_INLIERS,
                         fine);
    CHECK_EQ_INT(
        reason_of(run(reg + "--refine-min-inliers " + std::to_string(fine_inliers) + " --json"), "at the inliers"),
        KISSM_REASON_NONE);
    CHECK_EQ_INT(reason_of(run(reg + "--refine-min-inliers " + std::to_string(fine_inliers + 1) + " --json"),
                           "one inlier short"),
                 KISSM_REASON_TOO_FEW_INLIERS);
}

// --max-ambiguity: the tool's and the library's range checks, refused by `refine` (no solver, no competitor), and
// the decision moves exactly at the ambiguity the JSON reports, with and without refinement.
void test_ambiguity_option() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    const std::string plain = "register " + pair_args(pair) + " --voxel 0.25 ";
    const std::string ref = "refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(pair.truth_path) + " ";
    for (const char *bad : {"abc", "nan", "inf", "''"})
        expect_usage_error(plain + "--max-ambiguity " + bad, "--max-ambiguity");
    for (const char *bad : {"-0.01", "1.01"}) {
        expect_usage_error(plain + "--max-ambiguity " + bad, "--max-ambiguity: config.max_ambiguity");
    }
    expect_usage_error(ref + "--max-ambiguity 0.5", "--max-ambiguity");
    CHECK(contains(help_line(run("register --help").out, "--max-ambiguity"), "(default 0.7;"));

    const Run base = run(plain + "--json");
    CHECK_MSG(base.code == 0, "register: exit %d (%s)", base.code, base.err.c_str());
    const double a = contract_json(base, false, "register").at("ambiguity").as_double();
    CHECK_MSG(a > 0.0 && a < 0.7, "ambiguity %.17g", a); // a scene with one answer
    check_decision_flips(plain, "--max-ambiguity", "ambiguity", a, 0.0, KISSM_REASON_AMBIGUOUS, base);
    const std::string reg = plain + "--refine gicp ";
    const Run fine = run(reg + "--json");
    check_decision_flips(reg, "--max-ambiguity", "ambiguity", a, 0.0, KISSM_REASON_AMBIGUOUS, fine);
    // kissm_refine runs no solver: no competitor, ambiguity null.
    const Run refined = run(ref + "--json");
    CHECK(contract_json(refined, true, "refine").at("ambiguity").is(Json::Type::Null));
    // The summary shows it.
    CHECK(contains(run(plain).out, "\nambiguity: "));
}

// The ground truth moved by 2 degrees about a skew axis and by (0.15, -0.1, 0.08) m: exactly rigid.
void perturbed(const double truth[16], double out[16]) {
    const double axis[3] = {1.0 / std::sqrt(14.0), 2.0 / std::sqrt(14.0), 3.0 / std::sqrt(14.0)};
    const double a = kissm_pose::deg_to_rad(2.0), c = std::cos(a), s = std::sin(a);
    double D[9];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) D[3 * i + j] = (i == j ? c : 0.0) + (1.0 - c) * axis[i] * axis[j];
    }
    D[1] -= s * axis[2];
    D[2] += s * axis[1];
    D[3] += s * axis[2];
    D[5] -= s * axis[0];
    D[6] -= s * axis[1];
    D[7] += s * axis[0];
    const double shift[3] = {0.15, -0.1, 0.08};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            out[4 * i + j] = D[3 * i] * truth[j] + D[3 * i + 1] * truth[4 + j] + D[3 * i + 2] * truth[8 + j];
        }
        out[4 * i + 3] = truth[4 * i + 3] + shift[i];
    }
    out[12] = out[13] = out[14] = 0.0;
    out[15] = 1.0;
}

void test_refine_command() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    double initial[16];
    perturbed(pair.truth, initial);
    const std::string initial_path = work("perturbed.txt");
    std::string error;
    REQUIRE(kissm_cli::write_transform_file(initial_path, initial, &error));
    const PoseError start = error_of(std::vector<double>(initial, initial + 16), pair.truth);
    CHECK(start.deg > 1.9 && start.m > 0.15);

    const struct {
        const char *mode;
        int32_t code;
        const char *flag;
    } modes[] = {{"gicp", KISSM_REFINE_GICP, ""},
                 {"point-to-plane", KISSM_REFINE_POINT_TO_PLANE, " --refine point-to-plane"}};
    for (const auto &m : modes) {
        const std::string what = std::string("refine (") + m.mode + ")";
        const Run r =
            run("refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(initial_path) + " --json" + m.flag);
        CHECK_MSG(r.code == 0, "%s: exit %d (%s)", what.c_str(), r.code, r.err.c_str());
        const Json j = contract_json(r, true, what.c_str());
        CHECK(j.at("valid").boolean && j.at("refine").text == m.mode);
        check_doubles(j.at("initial_transform").flat(), initial, 16, what.c_str(), "initial_transform");
        const std::vector<double> coarse = j.at("coarse_transform").flat();
        for (size_t i = 0; i < 16 && coarse.size() == 16; ++i) CHECK_NEAR(coarse[i], initial[i], 1e-12);
        CHECK(j.at("counts").at("source_keypoints").text == "0" && j.at("final_inliers").text == "0");
        // No solver inliers: nothing for them to cover.
        CHECK(j.at("inlier_coverage").is(Json::Type::Null));
        CHECK(j.at("refine_converged").boolean);
        const PoseError end = error_of(j.at("transform").flat(), pair.truth);
        std::printf("%s from %.3f deg %.3f m off: %.4f deg %.4f m\n", what.c_str(), start.deg, start.m, end.deg, end.m);
        CHECK_MSG(end.deg < 0.1 && end.m < 0.02, "%s: %g deg %g m from the truth", what.c_str(), end.deg, end.m);
        kissm_result lib{};
        REQUIRE(library_result(pair.source, pair.target, 0.25, m.code, initial, &lib));
        check_matches_library(j, lib, what.c_str());
    }

    // The ground-truth file itself starts with a '#' comment line.
    const Run from_truth = run("refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(pair.truth_path));
    CHECK_MSG(from_truth.code == 0, "refine from the truth: exit %d (%s)", from_truth.code, from_truth.err.c_str());
    for (const char *word : {"kissm", "refine", "initial transform (from", "refined transform",
                             "refinement:", "moved the initial pose", "valid: yes", "normals"}) {
        CHECK_MSG(contains(from_truth.out, word), "summary lacks '%s':\n%s", word, from_truth.out.c_str());
    }
    CHECK(!contains(from_truth.out, "keypoints") && !contains(from_truth.out, "inlier coverage"));

    // Threads do not change the result.
    const std::string base = "refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(initial_path) + " --json";
    const std::string t1 = json_line_value(run(base + " --threads 1").out, "information");
    CHECK(!t1.empty() && t1 != "null");
    CHECK(json_line_value(run(base + " --threads 2").out, "information") == t1);
}

void test_refine_initial() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    const std::string base = "refine " + pair_args(pair) + " --voxel 0.25 --initial ";
    struct Case {
        const char *name;
        const char *text;
        const char *about; // besides the file's name
    };
    const Case cases[] = {
        {"empty.txt", "", "0 rows"},
        {"comments.txt", "# nothing but a comment\n\n", "0 rows"},
        {"three_rows.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n", "3 rows"},
        {"five_rows.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n0 0 0 1\n", "line 5"},
        {"short_row.txt", "1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n", "line 2"},
        {"long_row.txt", "1 0 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "line 1"},
        {"one_line.txt", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n", "line 1"},
        {"words.txt", "1 0 0 0\n0 one 0 0\n0 0 1 0\n0 0 0 1\n", "'one'"},
        {"suffix.txt", "1 0 0 0x\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "'0x'"},
        {"nan.txt", "1 0 0 0\n0 1 0 nan\n0 0 1 0\n0 0 0 1\n", "not finite"},
        {"inf.txt", "1 0 0 -inf\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "not finite"},
        {"overflow.txt", "1 0 0 1e999\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "not finite"},
        // Well-formed but not rigid: the library's message names initial_transform.
        {"scaled.txt", "2 0 0 0\n0 2 0 0\n0 0 2 0\n0 0 0 1\n", "initial_transform"},
        {"mirror.txt", "1 0 0 0\n0 1 0 0\n0 0 -1 0\n0 0 0 1\n", "initial_transform"},
        {"sheared.txt", "1 0.1 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "initial_transform"},
        {"last_row.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n", "initial_transform"},
        {"far.txt", "1 0 0 1e10\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "initial_transform"},
    };
    for (const Case &c : cases) {
        const std::string path = work(c.name);
        REQUIRE(write_file(path, c.text));
        expect_usage_error(base + quote(path), c.name);
        expect_usage_error(base + quote(path), c.about);
    }
    expect_usage_error(base + quote(work("missing.txt")), "missing.txt");
    expect_usage_error(base + quote(g_work), "folder");

    // What --out-transform writes when no pose was estimated is refused as well.
    const double none[16] = {std::nan(""), std::nan(""), std::nan(""), std::nan(""), std::nan(""), std::nan(""),
                             std::nan(""), std::nan(""), std::nan(""), std::nan(""), std::nan(""), std::nan(""),
                             std::nan(""), std::nan(""), std::nan(""), std::nan("")};
    std::string error;
    REQUIRE(kissm_cli::write_transform_file(work("no_pose.txt"), none, &error));
    expect_usage_error(base + quote(work("no_pose.txt")), "not finite");

    // Accepted layouts: comments, blank lines, tabs, CRLF, signs and exponents.
    const std::string loose = work("loose.txt");
    REQUIRE(write_file(loose, "# from a spreadsheet\r\n\r\n  1\t0 0 0\r\n0 1 0 0\r\n  # a comment between rows\n"
                              "0 0 1.0e0 0\r\n+0 -0 0 1\r\n\n"));
    const Run ok = run(base + quote(loose) + " --json");
    CHECK_MSG(ok.code == 0 || ok.code == 1, "loose layout: exit %d (%s)", ok.code, ok.err.c_str());
    CHECK(json_valid(ok.out));
}

void test_refine_roundtrip() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    const std::string coarse_path = work("coarse.txt"), refined_path = work("refined.txt");
    const std::string again_path = work("again.txt"), aligned = work("aligned.ply"), picture = work("refine.png");
    const Run reg = run("register " + pair_args(pair) + " --voxel 0.3 --json --out-transform " + quote(coarse_path));
    CHECK_MSG(reg.code == 0, "register: exit %d (%s)", reg.code, reg.err.c_str());
    const Json r = contract_json(reg, false, "register --out-transform");

    const Run ref =
        run("refine " + pair_args(pair) + " --voxel 0.3 --initial " + quote(coarse_path) + " --json --out-transform " +
            quote(refined_path) + " --out-aligned " + quote(aligned) + " --out-topview " + quote(picture));
    CHECK_MSG(ref.code == 0, "refine --initial register's file: exit %d (%s)", ref.code, ref.err.c_str());
    const Json f = contract_json(ref, true, "refine --initial");
    // %.17g carries register's doubles exactly into refine.
    check_doubles(f.at("initial_transform").flat(), r.at("transform").flat().data(), 16, "round trip",
                  "initial_transform");
    const PoseError coarse = error_of(r.at("transform").flat(), pair.truth);
    const PoseError refined = error_of(f.at("transform").flat(), pair.truth);
    std::printf("register %.4f deg %.4f m, then refine %.4f deg %.4f m\n", coarse.deg, coarse.m, refined.deg,
                refined.m);
    CHECK_MSG(refined.deg < coarse.deg && refined.m < coarse.m && refined.deg < 0.1 && refined.m < 0.02,
              "refined %g deg %g m, coarse %g deg %g m", refined.deg, refined.m, coarse.deg, coarse.m);

    // The refine command's own files: the transform it printed, the source moved by it, the picture.
    double written[16];
    std::string error;
    REQUIRE(kissm_cli::read_transform_file(refined_path, written, &error));
    check_doubles(f.at("transform").flat(), written, 16, "refine --out-transform", "transform");
    CHECK_EQ_INT(read_back(aligned).size(), read_back(pair.source).size());
    try {
        const PngImage png = decode_png(read_file(picture));
        CHECK_MSG(png.width > 1000 && png.height > 1000, "refine --out-topview: %ux%u, expected 2 x 2 panels",
                  png.width, png.height);
    } catch (const std::exception &e) {
        CHECK_MSG(false, "%s: %s", picture.c_str(), e.what());
    }

    // A refined pose is a fixed point: refining it again barely moves it.
    const Run again = run("refine " + pair_args(pair) + " --voxel 0.3 --initial " + quote(refined_path) + " --json");
    CHECK_MSG(again.code == 0, "refine --initial its own output: exit %d (%s)", again.code, again.err.c_str());
    const Json a = contract_json(again, true, "refine again");
    const std::vector<double> first = f.at("transform").flat(), second = a.at("transform").flat();
    REQUIRE(first.size() == 16 && second.size() == 16);
    CHECK_MSG(kissm_pose::rotation_error_deg(first.data(), second.data()) < 0.01 &&
                  kissm_pose::translation_error(first.data(), second.data()) < 1e-3,
              "refining the refined pose moved it by %g deg, %g m",
              kissm_pose::rotation_error_deg(first.data(), second.data()),
              kissm_pose::translation_error(first.data(), second.data()));
}

// --min-refine-condition and --refine-normal-radius, which kissm_refine reads too: the tool's and the library's
// range checks for both commands; the condition moves the decision exactly at the value the JSON reports
// (register --refine and refine alike), never the pose; the normal radius moves the refined pose (not the
// solver's), bit for bit the library's with that setting at every thread count; and a refinement capped at one
// iteration from a perturbed start is not valid (NOT_CONVERGED).
void test_refine_rule_options() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    kissm_config defaults{};
    REQUIRE(kissm_config_init(&defaults, sizeof defaults) == KISSM_OK);
    const std::string plain = "register " + pair_args(pair) + " --voxel 0.25 ";
    const std::string reg = plain + "--refine gicp ";
    const std::string ref = "refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(pair.truth_path) + " ";

    for (const std::string &command : {reg, ref}) {
        for (const char *bad : {"abc", "nan", "inf", "1e999", "''"}) {
            expect_usage_error(command + "--min-refine-condition " + bad, "--min-refine-condition");
            expect_usage_error(command + "--refine-normal-radius " + bad, "--refine-normal-radius");
        }
        for (const char *bad : {"-0.01", "1.01"}) {
            expect_usage_error(command + "--min-refine-condition " + bad,
                               "--min-refine-condition: config.min_refine_condition");
        }
        for (const char *bad : {"0", "-1", "50.5"}) {
            expect_usage_error(command + "--refine-normal-radius " + bad,
                               "--refine-normal-radius: config.refine_normal_radius_gain");
        }
        for (const char *bad : {"abc", "nan", "inf", "''"})
            expect_usage_error(command + "--max-refine-rmse " + bad, "--max-refine-rmse");
        for (const char *bad : {"0", "-1", "100.5"}) {
            expect_usage_error(command + "--max-refine-rmse " + bad, "--max-refine-rmse: config.max_refine_rmse_gain");
        }
    }

    // The refined rule's condition: exactly the measured one is enough, one ulp more is not.
    const Run fine = run(reg + "--json");
    CHECK_MSG(fine.code == 0, "register --refine gicp: exit %d (%s)", fine.code, fine.err.c_str());
    const Json f = contract_json(fine, false, "register --refine gicp");
    const double condition = f.at("refine_condition").as_double();
    CHECK_MSG(condition >= defaults.min_refine_condition && condition < 1.0, "refine_condition %s",
              f.at("refine_condition").text.c_str());
    check_decision_flips(reg, "--min-refine-condition", "refine_condition", condition, 2.0, KISSM_REASON_UNCONSTRAINED,
                         fine);
    // Without refinement there is no condition to judge.
    CHECK_EQ_INT(reason_of(run(plain + "--min-refine-condition 1 --json"), "unrefined, condition 1"),
                 KISSM_REASON_NONE);
    // kissm_refine's rule reads it too.
    const Run prior = run(ref + "--json");
    CHECK_MSG(prior.code == 0, "refine from the truth: exit %d (%s)", prior.code, prior.err.c_str());
    const double prior_condition = contract_json(prior, true, "refine").at("refine_condition").as_double();
    check_decision_flips(ref, "--min-refine-condition", "refine_condition", prior_condition, 2.0,
                         KISSM_REASON_UNCONSTRAINED, prior, true);
    // The residual, for both: a gain of exactly the measured refine_rmse in voxels is enough (the voxel, 0.25, is a
    // power of two, so the gain times it is the residual to the bit), one ulp less is not.
    const double rmse = f.at("refine_rmse").as_double(),
                 prior_rmse = contract_json(prior, true, "refine").at("refine_rmse").as_double();
    CHECK_MSG(rmse > 0.0 && rmse <= defaults.max_refine_rmse_gain * 0.25, "refine_rmse %g", rmse);
    check_decision_flips(reg, "--max-refine-rmse", "refine_rmse", rmse / 0.25, 0.0, KISSM_REASON_LOOSE_ALIGNMENT, fine);
    check_decision_flips(ref, "--max-refine-rmse", "refine_rmse", prior_rmse / 0.25, 0.0, KISSM_REASON_LOOSE_ALIGNMENT,
                         prior, true);

    // The refinement's planes: another radius, another refined pose from the same coarse one, as accurate.
    const double gain = 0.75 * defaults.refine_normal_radius_gain;
    const std::string radius = "--refine-normal-radius " + exact(gain) + " ";
    const auto with_radius = [gain](kissm_config &c) { c.refine_normal_radius_gain = gain; };
    const Run other = run(reg + radius + "--json");
    CHECK_MSG(other.code == 0, "register %s: exit %d (%s)", radius.c_str(), other.code, other.err.c_str());
    const Json o = contract_json(other, false, "--refine-normal-radius");
    CHECK(json_line_value(other.out, "coarse_transform") == json_line_value(fine.out, "coarse_transform"));
    CHECK_MSG(json_line_value(other.out, "transform") != json_line_value(fine.out, "transform"),
              "--refine-normal-radius %g left the refined pose as it was", gain);
    check_refined_beats_coarse(o, pair.truth, "--refine-normal-radius");
    kissm_result lib{};
    REQUIRE(library_result(pair.source, pair.target, 0.25, KISSM_REFINE_GICP, nullptr, &lib, with_radius));
    for (const char *threads : {"1", "2"}) {
        const std::string what = std::string("--refine-normal-radius --threads ") + threads;
        check_matches_library(contract_json(run(reg + radius + "--json --threads " + threads), false, what.c_str()),
                              lib, what.c_str());
    }
    // kissm_refine's planes too.
    double initial[16];
    perturbed(pair.truth, initial);
    const std::string initial_path = work("perturbed.txt");
    std::string error;
    REQUIRE(kissm_cli::write_transform_file(initial_path, initial, &error));
    const std::string from = "refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(initial_path) + " ";
    const Run refined_default = run(from + "--json");
    const Run refined_other = run(from + radius + "--json");
    CHECK_MSG(refined_other.code == 0, "refine %s: exit %d (%s)", radius.c_str(), refined_other.code,
              refined_other.err.c_str());
    CHECK(json_line_value(refined_other.out, "transform") != json_line_value(refined_default.out, "transform"));
    REQUIRE(library_result(pair.source, pair.target, 0.25, KISSM_REFINE_GICP, initial, &lib, with_radius));
    check_matches_library(contract_json(refined_other, true, "refine --refine-normal-radius"), lib,
                          "refine --refine-normal-radius");

    // Stopped by its cap while still moving: kept, reported, not valid.
    const Run capped = run(from + "--refine-iterations 1 --json");
    CHECK_EQ_INT(reason_of(capped, "refine capped at 1 iteration", true), KISSM_REASON_NOT_CONVERGED);
    const Json c = contract_json(capped, true, "refine capped at 1 iteration");
    CHECK(!c.at("refine_converged").boolean && c.at("refine_iterations").text == "1");
    CHECK(json_line_value(capped.out, "transform") != json_line_value(capped.out, "initial_transform"));
}

// ---------------------------------------------------------------------------------------------------
// Ground and up: register --preset/--suppression/--rotation-dof/--up/--sensor-height, kissm ground.
// ---------------------------------------------------------------------------------------------------

constexpr double kGroundZ = -1.7; // the street's ground below the sensor at the origin, metres

// A scan-like street in the sensor's frame (sensor at the origin, up +z): a ground plane z = -1.7 on a
// 0.25 m grid, 32 m square, and boxes standing on it (their sides and tops on a 0.15 m grid). Deterministic.
// Each point's cloud is `yaw` degrees about z and `shift` (x, y) away: p = Rz(yaw)^T (q - shift).
struct Street {
    std::vector<double> xyz;
    size_t plane_points = 0; // the first plane_points points are the plane's
};

Street street_cloud(double yaw_deg, double shift_x, double shift_y) {
    Street s;
    const double c = std::cos(yaw_deg * 3.14159265358979323846 / 180.0), sn = std::sin(yaw_deg * M_PI / 180.0);
    const auto add = [&](double x, double y, double z) {
        const double dx = x - shift_x, dy = y - shift_y;
        s.xyz.push_back(c * dx + sn * dy);
        s.xyz.push_back(-sn * dx + c * dy);
        s.xyz.push_back(z);
    };
    for (int i = -64; i <= 64; ++i) {
        for (int j = -64; j <= 64; ++j) add(0.25 * i, 0.25 * j, kGroundZ);
    }
    s.plane_points = s.xyz.size() / 3;
    struct Box {
        double x, y, w, d, h;
    };
    const Box boxes[] = {{6, 3, 3, 5, 4},   {-9, 5, 5, 3, 7},   {10, -7, 4, 4, 2.5}, {-5, -11, 2, 7, 5},
                         {11, 9, 3, 2, 3},  {-13, -4, 3, 3, 9}, {1, 12, 6, 2, 2},    {-3, 7, 1.5, 1.5, 3},
                         {8, -14, 2, 5, 6}, {-14, 11, 3, 3, 4}};
    const double step = 0.15;
    for (const Box &b : boxes) {
        const double top = kGroundZ + b.h;
        for (double z = kGroundZ + step; z <= top + 1e-9; z += step) { // the four sides
            for (double u = 0.0; u <= b.w + 1e-9; u += step) {
                add(b.x + u, b.y, z);
                add(b.x + u, b.y + b.d, z);
            }
            for (double v = step; v < b.d - 1e-9; v += step) {
                add(b.x, b.y + v, z);
                add(b.x + b.w, b.y + v, z);
            }
        }
        for (double u = step; u < b.w - 1e-9; u += step) { // the top
            for (double v = step; v < b.d - 1e-9; v += step) add(b.x + u, b.y + v, top);
        }
    }
    return s;
}

// x y z text lines (%.17g: the reader gets the exact doubles back).
bool write_xyz_text(const std::string &path, const std::vector<double> &xyz) {
    std::string text;
    char line[128];
    for (size_t i = 0; i < xyz.size(); i += 3) {
        std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", xyz[i], xyz[i + 1], xyz[i + 2]);
        text += line;
    }
    return write_file(path, text);
}

// The errors `register` and `ground` share: --preset, --up, --sensor-height (prefix: the command line before
// the option, ending with a space). Exit 2, one line naming the option (and the library's field when in range
// of the parser but not of the library).
void expect_ground_up_errors(const std::string &prefix) {
    expect_usage_error(prefix + "--up 0,0,0", "--up: config.up is (0, 0, 0)");
    for (const char *bad : {"1,2", "1,2,3,4", "a,b,c", "nan,0,1", "''"})
        expect_usage_error(prefix + "--up " + bad, "--up");
    expect_usage_error(prefix + "--preset nope", "--preset: unknown preset 'nope'");
    expect_usage_error(prefix + "--preset", "--preset");
    for (const char *bad : {"-1", "1001"}) {
        expect_usage_error(prefix + "--sensor-height " + bad, "--sensor-height: config.sensor_height");
    }
    expect_usage_error(prefix + "--sensor-height abc", "--sensor-height");
}

// The committed pair with --rotation-dof 1: a rotation about up only, reported tilt; with 3: tilt null.
void test_ground_options() {
    CommittedPair pair;
    REQUIRE(load_committed_pair(&pair));
    const std::string reg = "register " + pair_args(pair) + " --voxel 0.25 ";

    const Run yaw = run(reg + "--rotation-dof 1 --json");
    CHECK_MSG(yaw.code == 0 || yaw.code == 1, "--rotation-dof 1: exit %d (%s)", yaw.code, yaw.err.c_str());
    const Json y = contract_json(yaw, false, "--rotation-dof 1");
    const std::vector<double> R = y.at("rotation").flat();
    REQUIRE(R.size() == 9);
    for (int k : {2, 5, 6, 7}) CHECK_MSG(std::fabs(R[k]) < 1e-12, "--rotation-dof 1: R[%d] = %.17g", k, R[k]);
    CHECK_MSG(std::fabs(R[8] - 1.0) < 1e-12, "--rotation-dof 1: R[8] = %.17g", R[8]);
    CHECK_MSG(y.at("tilt").is(Json::Type::Number) && y.at("tilt").number >= 0.0, "--rotation-dof 1: tilt %s",
              y.at("tilt").text.c_str());
    // The committed pair is tilted (its truth turns +z by tens of degrees): never a valid yaw-only pose.
    CHECK(!y.at("valid").boolean);
    kissm_result lib{};
    REQUIRE(library_result(pair.source, pair.target, 0.25, KISSM_REFINE_NONE, nullptr, &lib,
                           [](kissm_config &c) { c.rotation_dof = 1; }));
    check_matches_library(y, lib, "--rotation-dof 1");
    // Another up: rotation about x only.
    const Json yx = contract_json(run(reg + "--rotation-dof 1 --up=2,0,0 --json"), false, "--up 2,0,0");
    const std::vector<double> Rx = yx.at("rotation").flat();
    REQUIRE(Rx.size() == 9);
    for (int k : {1, 2, 3, 6}) CHECK_MSG(std::fabs(Rx[k]) < 1e-12, "--up 2,0,0: R[%d] = %.17g", k, Rx[k]);
    CHECK(std::fabs(Rx[0] - 1.0) < 1e-12);
    const Json free_ = contract_json(run(reg + "--json"), false, "--rotation-dof 3");
    CHECK(free_.at("tilt").is(Json::Type::Null));
    CHECK(free_.at("counts").at("source_suppressed").text == "0" && free_.at("time_ms").at("suppression").text == "0");

    // Bad values: exit 2, one line naming the option (the library's message names the field).
    expect_usage_error(reg + "--rotation-dof 2", "--rotation-dof: config.rotation_dof is 2");
    expect_usage_error(reg + "--rotation-dof 0", "--rotation-dof: config.rotation_dof");
    expect_usage_error(reg + "--rotation-dof x", "--rotation-dof");
    expect_ground_up_errors(reg);
    expect_usage_error(reg + "--suppression planes", "--suppression");
    // refine has no solver and no keypoints: these are register's.
    const std::string ref = "refine " + pair_args(pair) + " --voxel 0.25 --initial " + quote(pair.truth_path) + " ";
    for (const char *option :
         {"--preset lidar-vehicle", "--suppression ground", "--rotation-dof 1", "--up 0,0,1", "--sensor-height 1.7"}) {
        expect_usage_error(ref + option, std::string(option).substr(0, std::string(option).find(' ')));
    }
    // --voxel is still required without a preset.
    expect_usage_error("register " + pair_args(pair) + " --suppression ground", "--voxel");

    // A street with a ground plane, seen from two poses 20 degrees and 1.1 m apart (both sensors 1.7 m up).
    const std::string target = work("street_target.xyz"), source = work("street_source.xyz");
    REQUIRE(write_xyz_text(target, street_cloud(0.0, 0.0, 0.0).xyz));
    REQUIRE(write_xyz_text(source, street_cloud(20.0, 1.0, 0.5).xyz));
    const std::string street = "register " + quote(source) + " " + quote(target) + " ";
    const auto street_json = [&](const std::string &options, const char *what) {
        const Run r = run(street + options + " --json");
        CHECK_MSG(r.code == 0 || r.code == 1, "%s: exit %d (%s)", what, r.code, r.err.c_str());
        return contract_json(r, false, what);
    };
    const auto suppressed = [](const Json &j) {
        return std::make_pair(j.at("counts").at("source_suppressed").number,
                              j.at("counts").at("target_suppressed").number);
    };
    const Json off = street_json("--voxel 0.3", "street, no suppression");
    CHECK(suppressed(off).first == 0.0 && suppressed(off).second == 0.0);
    const Json on = street_json("--voxel 0.3 --suppression ground", "street, --suppression ground");
    std::printf("street: %g / %g voxels suppressed of %s / %s; keypoints %s / %s (without: %s / %s)\n",
                suppressed(on).first, suppressed(on).second, on.at("counts").at("source_voxels").text.c_str(),
                on.at("counts").at("target_voxels").text.c_str(), on.at("counts").at("source_keypoints").text.c_str(),
                on.at("counts").at("target_keypoints").text.c_str(),
                off.at("counts").at("source_keypoints").text.c_str(),
                off.at("counts").at("target_keypoints").text.c_str());
    CHECK(suppressed(on).first > 1000.0 && suppressed(on).second > 1000.0);
    CHECK(on.at("time_ms").at("suppression").number > 0.0);
    CHECK(on.at("counts").at("source_keypoints").number < off.at("counts").at("source_keypoints").number);
    kissm_result lib_on{};
    REQUIRE(library_result(source, target, 0.3, KISSM_REFINE_NONE, nullptr, &lib_on,
                           [](kissm_config &c) { c.suppression = KISSM_SUPPRESS_GROUND; }));
    check_matches_library(on, lib_on, "street, --suppression ground");
    // The summary says so too.
    const Run human = run(street + "--voxel 0.3 --suppression ground");
    CHECK_MSG(contains(human.out, "suppressed (ground)") && contains(human.out, "suppression ground"), "%s",
              human.out.c_str());

    // The preset first, then the explicit options, in either order.
    const Json vehicle = street_json("--preset lidar-vehicle", "--preset lidar-vehicle");
    CHECK(vehicle.at("voxel_size").text == "0.3");
    CHECK(suppressed(vehicle) == suppressed(on));
    for (const char *options :
         {"--preset lidar-vehicle --suppression none", "--suppression none --preset lidar-vehicle"}) {
        const Json j = street_json(options, options);
        CHECK_MSG(suppressed(j).first == 0.0 && j.at("voxel_size").text == "0.3", "%s: suppressed %g, voxel %s",
                  options, suppressed(j).first, j.at("voxel_size").text.c_str());
    }
    for (const char *options : {"--preset lidar-vehicle --voxel 0.4", "--voxel 0.4 --preset lidar-vehicle"}) {
        const Json j = street_json(options, options);
        CHECK_MSG(j.at("voxel_size").text == "0.4" && suppressed(j).first > 0.0, "%s: voxel %s, suppressed %g", options,
                  j.at("voxel_size").text.c_str(), suppressed(j).first);
    }
    // lidar-handheld: no suppression, frame-free normals; --suppression ground turns it back on.
    CHECK(suppressed(street_json("--preset lidar-handheld", "--preset lidar-handheld")).first == 0.0);
    const auto handheld_ground = suppressed(street_json("--preset lidar-handheld --suppression ground", "handheld"));
    CHECK(handheld_ground.first > 0.0);
    CHECK(suppressed(street_json("--suppression ground --preset lidar-handheld", "handheld, ground first")) ==
          handheld_ground);
    // --up and --sensor-height reach the ground model: with up along x there is no ground.
    CHECK(suppressed(street_json("--preset lidar-vehicle --up 1,0,0", "--up 1,0,0")).first <
          suppressed(on).first / 10.0);
    const Json known = street_json("--preset lidar-vehicle --sensor-height 1.7", "--sensor-height 1.7");
    CHECK(suppressed(known).first > 1000.0);
    // The yaw-only solver on the street (yaw 20 degrees about up, no tilt).
    const Json street_yaw = street_json("--preset lidar-vehicle --rotation-dof 1", "street --rotation-dof 1");
    const std::vector<double> Rs = street_yaw.at("rotation").flat();
    REQUIRE(Rs.size() == 9);
    CHECK(std::fabs(Rs[8] - 1.0) < 1e-12 && std::fabs(Rs[2]) < 1e-12 && std::fabs(Rs[6]) < 1e-12);
}

// kissm ground: two PLY files that add up to the input, the plane in the ground file, the boxes in the rest.
void test_ground_command() {
    const Street s = street_cloud(0.0, 0.0, 0.0);
    const size_t n = s.xyz.size() / 3;
    const std::string in = work("street.xyz"), g = work("ground.ply"), rest = work("rest.ply");
    REQUIRE(write_xyz_text(in, s.xyz));
    const std::string base = "ground " + quote(in) + " --voxel 0.3 ";

    Run r = run(base + "--out-ground " + quote(g) + " --out-rest " + quote(rest));
    CHECK_MSG(r.code == 0, "kissm ground: exit %d (%s)", r.code, r.err.c_str());
    CHECK(r.err.empty());
    CHECK_MSG(contains(r.out, "ground points: ") && contains(r.out, std::to_string(n) + " points"), "%s",
              r.out.c_str());
    std::printf("%s", r.out.c_str());
    const std::string ground_bytes = read_file(g), rest_bytes = read_file(rest);
    const long long ng = ply_vertex_count(ground_bytes), nr = ply_vertex_count(rest_bytes);
    CHECK_MSG(ng > 0 && nr > 0 && static_cast<size_t>(ng + nr) == n, "ground %lld + rest %lld != %zu", ng, nr, n);
    const std::vector<double> ground = read_back(g), others = read_back(rest);
    REQUIRE(ground.size() == 3 * static_cast<size_t>(ng) && others.size() == 3 * static_cast<size_t>(nr));

    // The ground file: plane points (and at most the lowest box points sharing their voxels), and most of the
    // plane the model covers (2.7 m to 80 m from the sensor).
    size_t ground_on_plane = 0, plane_covered = 0, rest_on_plane = 0;
    for (size_t i = 0; i < ground.size(); i += 3) {
        CHECK_MSG(ground[i + 2] < kGroundZ + 0.61, "ground point at z = %g", ground[i + 2]);
        ground_on_plane += ground[i + 2] == kGroundZ ? 1u : 0u;
    }
    for (size_t i = 0; i < 3 * s.plane_points; i += 3) {
        const double range = std::hypot(s.xyz[i], s.xyz[i + 1]);
        plane_covered += (range > 3.5 && range < 15.5) ? 1u : 0u;
    }
    for (size_t i = 0; i < others.size(); i += 3) rest_on_plane += others[i + 2] == kGroundZ ? 1u : 0u;
    std::printf(
        "ground: %lld points, %zu on the plane; %zu plane points 3.5-15.5 m out; %zu plane points in the rest\n", ng,
        ground_on_plane, plane_covered, rest_on_plane);
    CHECK(ground_on_plane + rest_on_plane == s.plane_points);
    CHECK_MSG(ground_on_plane >= plane_covered * 95 / 100, "only %zu of %zu plane points are ground", ground_on_plane,
              plane_covered);
    CHECK_MSG(static_cast<double>(ground_on_plane) >= 0.95 * static_cast<double>(ng), "%zu of %lld ground points",
              ground_on_plane, ng);
    size_t high = 0;
    for (size_t i = 0; i < others.size(); i += 3) high += others[i + 2] > kGroundZ + 0.7 ? 1u : 0u;
    CHECK_EQ_INT(
        high, n - s.plane_points - [&] {
            size_t low = 0;
            for (size_t i = 3 * s.plane_points; i < s.xyz.size(); i += 3)
                low += s.xyz[i + 2] <= kGroundZ + 0.7 ? 1u : 0u;
            return low;
        }()); // every box point well above the ground is in the rest

    // The same labels as the library's, and for any thread count (the files byte for byte).
    {
        kissm_cloud *cloud = nullptr;
        kissm_matcher *matcher = nullptr;
        kissm_config config{};
        kissm_points points{};
        REQUIRE(kissm_read_points(in.c_str(), KISSM_FORMAT_AUTO, &cloud) == KISSM_OK);
        REQUIRE(kissm_cloud_points(cloud, &points) == KISSM_OK &&
                kissm_config_init(&config, sizeof config) == KISSM_OK);
        config.voxel_size = 0.3;
        REQUIRE(kissm_create(&config, &matcher) == KISSM_OK);
        std::vector<uint8_t> mask(n, 0);
        REQUIRE(kissm_ground_mask(matcher, &points, mask.data()) == KISSM_OK);
        size_t lib_ground = 0;
        for (uint8_t m : mask) lib_ground += m;
        CHECK_EQ_INT(lib_ground, static_cast<size_t>(ng));
        kissm_destroy(matcher);
        kissm_cloud_destroy(cloud);
    }
    for (const char *threads : {"1", "2"}) {
        const std::string g2 = work(std::string("ground_t") + threads + ".ply");
        const std::string r2 = work(std::string("rest_t") + threads + ".ply");
        const Run t = run(base + "--threads " + threads + " --out-ground " + quote(g2) + " --out-rest " + quote(r2));
        CHECK_EQ_INT(t.code, 0);
        CHECK_MSG(read_file(g2) == ground_bytes && read_file(r2) == rest_bytes, "--threads %s: other files", threads);
    }

    // JSON: the counts, the settings, the files (null when not written).
    r = run(base + "--json --out-rest " + quote(work("rest_only.ply")));
    CHECK_MSG(r.code == 0, "kissm ground --json: exit %d (%s)", r.code, r.err.c_str());
    std::string error;
    const Json j = json_parse(r.out, &error);
    CHECK_MSG(error.empty(), "invalid JSON (%s):\n%s", error.c_str(), r.out.c_str());
    const std::vector<std::string> keys = {
        "version",    "input",         "preset",    "voxel_size",    "threads",     "up",
        "viewpoint",  "sensor_height", "points",    "ground_points", "rest_points", "nonfinite_points",
        "out_ground", "out_rest",      "ground_ms", "read_ms"};
    CHECK_MSG(j.keys() == keys, "keys %s", joined(j.keys()).c_str());
    CHECK(j.at("points").text == std::to_string(n));
    CHECK(j.at("ground_points").text == std::to_string(ng) && j.at("rest_points").text == std::to_string(nr));
    CHECK(j.at("nonfinite_points").text == "0" && j.at("preset").text == "none");
    CHECK(j.at("out_ground").is(Json::Type::Null) && j.at("out_rest").text == work("rest_only.ply"));
    CHECK(j.at("up").flat() == std::vector<double>({0.0, 0.0, 1.0}) && j.at("voxel_size").text == "0.3");
    CHECK(ply_vertex_count(read_file(work("rest_only.ply"))) == nr);
    // No file at all: only the counts.
    r = run(base);
    CHECK_EQ_INT(r.code, 0);
    CHECK(contains(r.out, "ground points: " + std::to_string(ng)));

    // The preset gives the voxel; explicit options override it in any order.
    const auto ground_count = [&](const std::string &options) {
        const Run run_ = run("ground " + quote(in) + " " + options + " --json");
        CHECK_MSG(run_.code == 0, "ground %s: exit %d (%s)", options.c_str(), run_.code, run_.err.c_str());
        const Json jj = json_parse(run_.out);
        return std::make_pair(jj.at("ground_points").text, jj.at("voxel_size").text);
    };
    CHECK(ground_count("--preset lidar-vehicle") == std::make_pair(std::to_string(ng), std::string("0.3")));
    CHECK(ground_count("--voxel 0.5 --preset lidar-vehicle") == ground_count("--preset lidar-vehicle --voxel 0.5"));
    CHECK(ground_count("--voxel 0.5 --preset lidar-vehicle").second == "0.5");
    CHECK(ground_count("--voxel 0.3 --sensor-height 1.7").first == std::to_string(ng));
    // Up along x, or the sensor 10 m up: (almost) no ground.
    CHECK(std::stoll(ground_count("--voxel 0.3 --up 1,0,0").first) < ng / 10);
    // The sensor 200 m away: the whole street is beyond the model's 80 m.
    CHECK(ground_count("--voxel 0.3 --viewpoint 200,0,0").first == "0");

    // Non-finite points: an error, or with --drop-nonfinite in neither file.
    std::vector<double> with_nan = s.xyz;
    with_nan.insert(with_nan.end(), {std::nan(""), 1.0, 2.0});
    const std::string nan_in = work("street_nan.ply");
    REQUIRE(write_cloud(nan_in, with_nan));
    expect_usage_error("ground " + quote(nan_in) + " --voxel 0.3", "street_nan.ply");
    r = run("ground " + quote(nan_in) + " --voxel 0.3 --drop-nonfinite --json");
    CHECK_EQ_INT(r.code, 0);
    const Json jn = json_parse(r.out);
    CHECK(jn.at("nonfinite_points").text == "1" && jn.at("points").text == std::to_string(n + 1));
    CHECK(jn.at("ground_points").text == std::to_string(ng) && jn.at("rest_points").text == std::to_string(nr));

    // Help and errors.
    for (const char *help : {"ground --help", "help ground"}) {
        r = run(help);
        CHECK_EQ_INT(r.code, 0);
        CHECK(contains(r.out, "usage: kissm ground") && contains(r.out, "--out-ground") &&
              contains(r.out, "--up X,Y,Z"));
    }
    CHECK(contains(run("--help").out, "kissm ground"));
    expect_usage_error("ground --voxel 0.3", "1 file");
    expect_usage_error("ground " + quote(in) + " " + quote(in) + " --voxel 0.3", "1 file");
    expect_usage_error("ground " + quote(in), "--voxel");
    expect_ground_up_errors(base);
    expect_usage_error(base + "--viewpoint fixed", "--viewpoint");
    expect_usage_error(base + "--viewpoint 0,0", "--viewpoint");
    expect_usage_error(base + "--threads -1", "--threads");
    expect_usage_error(base + "--suppression ground", "--suppression"); // the model is always the ground's
    expect_usage_error(base + "--rotation-dof 1", "--rotation-dof");
    expect_usage_error(base + "--format bogus", "bogus");
    expect_usage_error(base + "--bogus", "--bogus");
    expect_usage_error(base + "--json=1", "--json");
    expect_usage_error("ground " + quote(work("missing.xyz")) + " --voxel 0.3", "missing.xyz");
    expect_usage_error(base + "--out-ground " + quote(work("no/such/dir/g.ply")), "g.ply");
    expect_usage_error("ground " + quote(in) + " --voxel 1e-6", "voxel"); // too many voxels: the library's range
}

} // namespace

int main(int argc, char **argv) {
    std::string which;
    if (!prepare_case(argc, argv, &g_kissm, &g_work, &which)) return 2;
    if (which == "realdata") return test_realdata(); // 77 when the data is absent
    const CliCase cases[] = {{"usage", test_usage},
                             {"errors", test_errors},
                             {"malformed", test_malformed},
                             {"demo", test_demo},
                             {"json", test_json},
                             {"threads", test_threads},
                             {"refine_options", test_refine_options},
                             {"refine_register", test_refine_register},
                             {"refine_command", test_refine_command},
                             {"refine_initial", test_refine_initial},
                             {"refine_roundtrip", test_refine_roundtrip},
                             {"validity_options", test_validity_options},
                             {"ambiguity_option", test_ambiguity_option},
                             {"refine_rule_options", test_refine_rule_options},
                             {"ground_options", test_ground_options},
                             {"ground_command", test_ground_command}};
    return run_named_case(which, cases);
}
