// SPDX-License-Identifier: MIT
// Runs `kissm align` as a user would and checks exit codes, messages, the poses against known ones and the
// outputs byte for byte across --jobs and --resume.
//
//   cli_align_test KISSM_BINARY WORK_DIR CASE
//
// CASE: align_usage | align_run | align_resume | align_realdata (loop candidates of --pairs sequence in the last
// three). The scans of align_run and align_resume are
// made here from the committed cloud of tests/data (KISSM_TEST_DATA): four overlapping slabs of it, each moved by
// a known pose, so every scan's pose in the first one's frame is known exactly. align_realdata aligns the five
// KITTI 07 keyframes of ../shared/data (KISSM_DATA_DIR; 77 when absent). POSIX only (77 elsewhere).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <kissm.h>

#include "align/align_writers.hpp"
#include "cli_case_main.hpp"
#include "cli_test_util.hpp"
#include "harness.h"
#include "ply_writer.hpp"
#include "pose_math.hpp"
#include "splitmix64.h"

#if defined(_WIN32)
int main() {
    std::fprintf(stderr, "cli_align_test: POSIX only; skipped\n");
    return 77;
}
#else
#  include <fcntl.h>
#  include <spawn.h>
#  include <sys/wait.h>
#  include <unistd.h>

extern char **environ;

namespace fs = std::filesystem;
using namespace cli_test;
using kissm_pose::Pose;

namespace {

std::string g_kissm, g_work;
int g_runs = 0;

std::string work(const std::string &name) { return (fs::path(g_work) / name).string(); }

struct Run {
    int code = -1; // exit status; -1 when killed by a signal
    std::string out, err;
};

// Runs the binary with `args` (no shell), stdout and stderr through files of the work folder.
Run run(const std::vector<std::string> &args) {
    const int n = ++g_runs;
    const std::string out_path = work("run" + std::to_string(n) + ".out");
    const std::string err_path = work("run" + std::to_string(n) + ".err");
    std::vector<std::string> all = {g_kissm};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char *> argv;
    for (std::string &a : all) argv.push_back(&a[0]);
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = -1;
    if (posix_spawn(&pid, g_kissm.c_str(), &actions, nullptr, argv.data(), environ) != 0) pid = -1;
    posix_spawn_file_actions_destroy(&actions);
    if (pid <= 0) {
        std::fprintf(stderr, "cannot start %s\n", g_kissm.c_str());
        std::exit(1);
    }
    int status = 0;
    Run r;
    if (waitpid(pid, &status, 0) == pid && WIFEXITED(status)) r.code = WEXITSTATUS(status);
    r.out = read_file(out_path);
    r.err = read_file(err_path);
    return r;
}

std::string joined(const std::vector<std::string> &args) {
    std::string s;
    for (const std::string &a : args) s += " " + a;
    return s;
}

// Exit 2, nothing on stdout, one "kissm: ..." line on stderr that mentions `about`.
void expect_usage_error(const std::vector<std::string> &args, const std::string &about) {
    const Run r = run(args);
    const std::string cmd = joined(args);
    CHECK_MSG(r.code == 2, "'kissm%s' exited with %d, expected 2 (stderr: %s)", cmd.c_str(), r.code, r.err.c_str());
    CHECK_MSG(r.out.empty(), "'kissm%s' printed on stdout: [%s]", cmd.c_str(), r.out.c_str());
    const bool one_line =
        starts_with(r.err, "kissm: ") && std::count(r.err.begin(), r.err.end(), '\n') == 1 && r.err.back() == '\n';
    CHECK_MSG(one_line, "'kissm%s': stderr is not one 'kissm: ' line: [%s]", cmd.c_str(), r.err.c_str());
    CHECK_MSG(contains(r.err, about), "'kissm%s': [%s] does not mention '%s'", cmd.c_str(), r.err.c_str(),
              about.c_str());
}

std::vector<std::string> lines_of(const std::string &text) {
    std::vector<std::string> lines;
    size_t start = 0;
    while (start < text.size()) {
        const size_t nl = text.find('\n', start);
        if (nl == std::string::npos) {
            lines.push_back(text.substr(start));
            break;
        }
        lines.push_back(text.substr(start, nl - start));
        start = nl + 1;
    }
    return lines;
}

std::vector<std::string> split(const std::string &line, char separator) {
    std::vector<std::string> fields;
    size_t start = 0;
    for (;;) {
        const size_t at = line.find(separator, start);
        fields.push_back(line.substr(start, at == std::string::npos ? std::string::npos : at - start));
        if (at == std::string::npos) return fields;
        start = at + 1;
    }
}

std::vector<std::string> sorted_lines(const std::string &text) {
    std::vector<std::string> lines = lines_of(text);
    std::sort(lines.begin(), lines.end());
    return lines;
}

// ---------------------------------------------------------------------------------------------------
// The poses file

struct PoseRow {
    std::string scan;
    bool placed = false;
    long component = -1;
    double T[16]; // the 3 rows read, then 0 0 0 1
};

// Parses poses.tsv strictly into *out: the header, then `scans` rows of 15 tab-separated fields.
void parse_poses(const std::string &text, size_t scans, std::vector<PoseRow> *out) {
    const std::vector<std::string> lines = lines_of(text);
    std::vector<PoseRow> &rows = *out;
    rows.clear();
    CHECK_MSG(!text.empty() && text.back() == '\n', "poses file does not end with a newline");
    REQUIRE(lines.size() == scans + 1);
    CHECK_MSG(lines[0] == "scan\tplaced\tcomponent\tT00\tT01\tT02\tT03\tT10\tT11\tT12\tT13\tT20\tT21\tT22\tT23",
              "header: %s", lines[0].c_str());
    for (size_t k = 1; k < lines.size(); ++k) {
        const std::vector<std::string> f = split(lines[k], '\t');
        REQUIRE(f.size() == 15);
        PoseRow row;
        row.scan = f[0];
        CHECK(f[1] == "0" || f[1] == "1");
        row.placed = f[1] == "1";
        char *end = nullptr;
        row.component = std::strtol(f[2].c_str(), &end, 10);
        CHECK(*end == '\0');
        for (int i = 0; i < 12; ++i) {
            const std::string &v = f[static_cast<size_t>(3 + i)];
            row.T[i] = std::strtod(v.c_str(), &end);
            CHECK_MSG(*end == '\0' && !v.empty(), "not a number: %s", v.c_str());
            CHECK_MSG(row.placed ? std::isfinite(row.T[i]) : v == "nan", "scan %s entry %s", row.scan.c_str(),
                      v.c_str());
        }
        row.T[12] = row.T[13] = row.T[14] = 0.0;
        row.T[15] = 1.0;
        rows.push_back(row);
    }
}

// The worst rotation (degrees) and translation error of the placed rows against the truth (T_first_scan).
void worst_error(const std::vector<PoseRow> &rows, const std::vector<std::array<double, 16>> &truth, double *deg,
                 double *m) {
    *deg = *m = 0.0;
    for (size_t k = 0; k < rows.size() && k < truth.size(); ++k) {
        if (!rows[k].placed) continue;
        *deg = std::max(*deg, kissm_pose::rotation_error_deg(rows[k].T, truth[k].data()));
        *m = std::max(*m, kissm_pose::translation_error(rows[k].T, truth[k].data()));
    }
}

// ---------------------------------------------------------------------------------------------------
// The scans: four slabs of the committed cloud along x (70% of its extent each, 10% apart, so every pair
// overlaps by 40% or more), each written in its own frame.

constexpr const char *kVoxel = "0.25"; // golden.json's for the committed cloud
const char *const kNames[4] = {"a", "b", "c", "d"};

struct Scene {
    std::vector<std::array<double, 16>> truth; // per scan: T_first_scan, the poses align must find
    std::vector<size_t> counts;                // points per scan
};

std::string scans_tsv_text() {
    // One absolute path, one without a format (auto by extension), comments and a CRLF line.
    return "# kissm align test scans\n"
           "scan\tnote\tfile\tformat\n"
           "a\tfirst\tscan_a.ply\tply\n"
           "\n"
           "b\t\tscan_b.ply\t\r\n"
           "c\t\t" +
           work("scan_c.ply") +
           "\tply\n"
           "d\tlast\tscan_d.ply\tply\n";
}

bool make_scene(Scene *scene) {
    const char *dir = std::getenv("KISSM_TEST_DATA");
    if (!dir || !*dir) return false;
    kissm_cloud *cloud = nullptr;
    const std::string source = (fs::path(dir) / "roundtrip_source.ply").string();
    if (kissm_read_points(source.c_str(), KISSM_FORMAT_AUTO, &cloud) != KISSM_OK) return false;
    const double *xyz = kissm_cloud_data(cloud);
    const size_t n = static_cast<size_t>(kissm_cloud_count(cloud));
    double lo = xyz[0], hi = xyz[0];
    for (size_t i = 0; i < n; ++i) {
        lo = std::min(lo, xyz[3 * i]);
        hi = std::max(hi, xyz[3 * i]);
    }
    using namespace kissm_pose;
    // world_from_scan per scan: turns about every axis and metres of travel.
    const Pose world_from_scan[4] = {pose_from_ypr(deg_to_rad(20.0), deg_to_rad(3.0), deg_to_rad(-2.0), 1.0, 2.0, 0.0),
                                     pose_from_ypr(deg_to_rad(75.0), deg_to_rad(-4.0), deg_to_rad(5.0), 4.0, -2.0, 0.5),
                                     pose_from_ypr(deg_to_rad(-110.0), deg_to_rad(6.0), 0.0, -3.0, 6.0, 1.0),
                                     pose_from_ypr(deg_to_rad(160.0), 0.0, deg_to_rad(-7.0), 8.0, 1.0, -1.0)};
    for (int k = 0; k < 4; ++k) {
        const double from = lo + 0.1 * k * (hi - lo), to = from + 0.7 * (hi - lo);
        std::vector<double> slab;
        for (size_t i = 0; i < n; ++i) {
            if (xyz[3 * i] >= from && xyz[3 * i] <= to) slab.insert(slab.end(), xyz + 3 * i, xyz + 3 * i + 3);
        }
        double scan_from_world[16];
        pose_to_matrix(pose_inverse(world_from_scan[k]), scan_from_world);
        std::string error;
        const std::string path = work(std::string("scan_") + kNames[k] + ".ply");
        CHECK_MSG(
            kissm_cli::write_ply_xyz(path, slab.data(), slab.size() / 3, scan_from_world, {"cli_align_test"}, &error),
            "%s", error.c_str());
        std::array<double, 16> truth;
        pose_to_matrix(pose_compose(pose_inverse(world_from_scan[0]), world_from_scan[k]), truth.data());
        scene->truth.push_back(truth);
        scene->counts.push_back(slab.size() / 3);
    }
    kissm_cloud_destroy(cloud);
    write_file(work("scans.tsv"), scans_tsv_text());
    return true;
}

void need_scene(Scene *scene) {
    if (!make_scene(scene)) {
        std::fprintf(stderr, "cli_align_test: KISSM_TEST_DATA (tests/data) is not available\n");
        std::exit(77);
    }
}

// Placed within these of the truth: a quarter of a degree and a fifth of a voxel on clean copies.
constexpr double kMaxDeg = 0.25, kMaxM = 0.05;

void check_placed(const std::string &poses_text, const Scene &scene, const char *what) {
    std::vector<PoseRow> rows;
    parse_poses(poses_text, 4, &rows);
    REQUIRE(rows.size() == 4);
    for (size_t k = 0; k < rows.size(); ++k) {
        CHECK_MSG(rows[k].scan == kNames[k], "%s: row %zu is %s", what, k, rows[k].scan.c_str());
        CHECK_MSG(rows[k].placed && rows[k].component == 0, "%s: scan %s not placed", what, kNames[k]);
    }
    double deg = 0.0, m = 0.0;
    worst_error(rows, scene.truth, &deg, &m);
    CHECK_MSG(deg < kMaxDeg && m < kMaxM, "%s: worst error %g deg, %g m", what, deg, m);
    std::fprintf(stderr, "%s: worst error %.4f deg, %.4f m\n", what, deg, m);
    // The anchor is exactly the identity.
    for (int i = 0; i < 12; ++i) CHECK(rows[0].T[i] == (i % 5 == 0 ? 1.0 : 0.0));
}

// ---------------------------------------------------------------------------------------------------

void test_align_usage() {
    const std::string scans = work("scans.tsv");
    write_file(scans, scans_tsv_text()); // the clouds need not exist: every check here comes first
    const std::string out = work("poses.tsv");
    const std::vector<std::string> base = {"align", scans, "--voxel", "1", "--out", out};
    const auto with = [&base](std::vector<std::string> extra) {
        std::vector<std::string> args = base;
        args.insert(args.end(), extra.begin(), extra.end());
        return args;
    };
    expect_usage_error({"align"}, "align expects 1 scans file, got 0");
    write_file(work("priors_bad.tsv"), "scan\tT00\nx\t1\n");
    expect_usage_error(with({"--priors", work("priors_bad.tsv")}), "--priors applies to --pairs sequence only");
    expect_usage_error(with({"--pairs", "sequence", "--priors", out}), "--priors and --out are both");
    expect_usage_error(with({"--pairs", "sequence", "--priors", work("absent.tsv")}), "cannot read the priors file");
    expect_usage_error(with({"--pairs", "sequence", "--priors", work("priors_bad.tsv")}), "no 'T01' column");
    std::string header = "scan";
    for (int k = 0; k < 12; ++k) header += "\tT" + std::to_string(k / 4) + std::to_string(k % 4);
    const std::string ones = "\t1\t0\t0\t0\t0\t1\t0\t0\t0\t0\t1\t0\n";
    write_file(work("priors_bad.tsv"), header + "\nx" + ones);
    expect_usage_error(with({"--pairs", "sequence", "--priors", work("priors_bad.tsv")}), "line 2: unknown scan 'x'");
    write_file(work("priors_bad.tsv"), header + "\na" + ones + "# again\na" + ones);
    expect_usage_error(with({"--pairs", "sequence", "--priors", work("priors_bad.tsv")}),
                       "line 4: the scan 'a' is given twice");
    write_file(work("priors_bad.tsv"), header + "\na\t1\t0\t0\t0\t0\t1\t0\t0\t0\t0\t1\tsix\n");
    expect_usage_error(with({"--pairs", "sequence", "--priors", work("priors_bad.tsv")}), "T23 is 'six', not a number");

    expect_usage_error({"align", scans, scans, "--voxel", "1", "--out", out}, "align expects 1 scans file, got 2");
    expect_usage_error({"align", scans, "--out", out}, "align needs --voxel V");
    expect_usage_error({"align", scans, "--voxel", "1"}, "align needs --out FILE");
    for (const char *bad : {"0", "-2", "x", "1.5"}) {
        expect_usage_error(with({"--pairs", "sequence", "--window", bad}), "--window");
    }
    expect_usage_error(with({"--window", "2"}), "--window applies to --pairs sequence only");
    expect_usage_error(with({"--stride", "2"}), "--stride applies to --pairs sessions only");
    expect_usage_error(with({"--pairs", "sessions", "--stride", "0"}), "--stride");
    expect_usage_error(with({"--pairs", "sessions", "--priors", out}), "--priors applies to --pairs sequence only");
    // Loop candidates' options: their ranges, --pairs sequence only, a window that would repeat them.
    expect_usage_error(with({"--pairs", "sequence", "--similar-per-scan", "-1"}), "--similar-per-scan");
    expect_usage_error(with({"--pairs", "sequence", "--similar-per-scan", "1000001"}), "--similar-per-scan");
    expect_usage_error(with({"--similar-per-scan", "2"}), "--similar-per-scan applies to --pairs sequence only");
    expect_usage_error(with({"--pairs", "sequence", "--priors", work("priors_bad.tsv"), "--similar-per-scan", "2"}),
                       "--similar-per-scan applies without --priors only");
    expect_usage_error(with({"--pairs", "sequence", "--loop-gap", "0"}), "--loop-gap");
    expect_usage_error(with({"--pairs", "sequence", "--loop-gap", "x"}), "--loop-gap");
    expect_usage_error(with({"--pairs", "sequence", "--loop-radius", "-1"}), "--loop-radius");
    expect_usage_error(with({"--pairs", "sequence", "--loop-radius", "0"}), "--loop-radius");
    expect_usage_error(with({"--pairs", "sequence", "--loops-per-scan", "-1"}), "--loops-per-scan");
    expect_usage_error(with({"--loop-gap", "2"}), "--loop-gap applies to --pairs sequence and sessions only");
    expect_usage_error(with({"--pairs", "all", "--loops-per-scan", "0"}),
                       "--loops-per-scan applies to --pairs sequence and sessions only");
    expect_usage_error(with({"--loop-radius", "3"}), "--loop-radius applies to --pairs sequence and sessions only");
    expect_usage_error(with({"--pairs", "sequence", "--window", "3", "--loop-gap", "3"}),
                       "--window 3 with loop candidates needs --loop-gap above 3");
    expect_usage_error(with({"--jobs", "0"}), "--jobs");
    expect_usage_error(with({"--map-voxel", "0.1"}), "--map-voxel needs --map FILE");
    expect_usage_error(with({"--map", work("m.ply"), "--map-voxel", "0"}), "--map-voxel");
    expect_usage_error(with({"--bound", "-1"}), "--bound");
    expect_usage_error(with({"--format-src", "ply"}), "--format-src and --format-tgt do not apply");
    expect_usage_error(with({"--json"}), "unknown option");
    expect_usage_error(with({"--resume=yes"}), "--resume takes no value");
    expect_usage_error(with({"--rotation-dof", "2"}), "invalid --rotation-dof: config.rotation_dof is 2");
    expect_usage_error(with({"--results", out}), "is the results file too");
    expect_usage_error(with({"--g2o", out + ".pairs.jsonl"}), "is the results file too");

    // The scans file.
    expect_usage_error({"align", work("nope.tsv"), "--voxel", "1", "--out", out}, "cannot read the scans file");
    const auto bad_scans = [&](const std::string &text, const std::string &about) {
        write_file(work("bad.tsv"), text);
        expect_usage_error({"align", work("bad.tsv"), "--voxel", "1", "--out", out}, about);
    };
    bad_scans("", "no header line");
    bad_scans("scan\tpath\na\ta.ply\n", "line 1: the header has no 'file' column");
    bad_scans("name\tfile\na\ta.ply\n", "line 1: the header has no 'scan' column");
    bad_scans("scan\tfile\n# none\n", "no scans");
    bad_scans("scan\tfile\na\ta.ply\nb\n", "line 3: 1 tab-separated fields, the header has 2");
    bad_scans("scan\tfile\na\ta.ply\na\tb.ply\n", "line 3: the scan 'a' is named twice (line 2 too)");
    bad_scans("scan\tfile\n\ta.ply\n", "line 2: empty scan name");
    bad_scans("scan\tfile\tformat\na\ta.ply\te57\n", "line 2: format: unknown format 'e57'");

    // The pairs: a file naming scans.
    const std::string pairs = work("pairs.tsv");
    write_file(pairs, "source\ttarget\nb\ta\nc\tzz\n");
    expect_usage_error(with({"--pairs", pairs}), "pairs.tsv line 3: unknown scan 'zz'");
    write_file(pairs, "# star\nsource\ttarget\nb\tb\n");
    expect_usage_error(with({"--pairs", pairs}), "line 3: the scan 'b' is paired with itself");
    write_file(pairs, "from\tto\nb\ta\n");
    expect_usage_error(with({"--pairs", pairs}), "the header has no 'source' column");
    expect_usage_error(with({"--pairs", work("none.tsv")}), "cannot read the pairs file");
    CHECK_MSG(!fs::exists(out) && !fs::exists(out + ".pairs.jsonl"), "a usage error wrote an output");

    // Finished work is never overwritten: an existing results file needs --resume, and must be this pair list's.
    write_file(out + ".pairs.jsonl", "{\"pair\": 1, \"source\": \"b\", \"target\": \"a\", \"status\": \"ok\", "
                                     "\"valid\": false}\n");
    expect_usage_error(base, "exists and is not empty: --resume completes it");
    write_file(work("other.jsonl"), "{\"pair\": 1, \"source\": \"c\", \"target\": \"a\", \"status\": \"ok\", "
                                    "\"valid\": false}\n");
    expect_usage_error(with({"--resume", "--pairs", "sequence", "--results", work("other.jsonl")}),
                       "results of another pair list?");
    CHECK(!fs::exists(out));

    // Help, in both spellings, and in the overview.
    const Run help = run({"align", "--help"});
    CHECK_EQ_INT(help.code, 0);
    CHECK(starts_with(help.out, "usage: kissm align SCANS.tsv"));
    CHECK(contains(help.out, "--pairs all|sequence|sessions|FILE") && contains(help.out, "default gicp here") &&
          contains(help.out, "Exit status: 0"));
    CHECK(help.err.empty());
    const Run help2 = run({"help", "align"});
    CHECK_EQ_INT(help2.code, 0);
    CHECK(help2.out == help.out);
    CHECK(contains(run({"--help"}).out, "kissm align SCANS.tsv"));

    // Python's repr() of floats, which the g2o, TUM and KITTI files use.
    using kissm_cli::python_float_text;
    const std::pair<double, const char *> reprs[] = {{1.0, "1.0"},
                                                     {-0.0, "-0.0"},
                                                     {0.0, "0.0"},
                                                     {0.1, "0.1"},
                                                     {1e-4, "0.0001"},
                                                     {1e-5, "1e-05"},
                                                     {-1.5e-7, "-1.5e-07"},
                                                     {1e16, "1e+16"},
                                                     {1e15, "1000000000000000.0"},
                                                     {123456789.0, "123456789.0"},
                                                     {1.0 / 3.0, "0.3333333333333333"},
                                                     {2.5e-300, "2.5e-300"},
                                                     {22.4577, "22.4577"},
                                                     {std::nan(""), "nan"},
                                                     {-HUGE_VAL, "-inf"}};
    for (const auto &r : reprs) {
        CHECK_MSG(python_float_text(r.first) == r.second, "repr %s: got %s", r.second,
                  python_float_text(r.first).c_str());
    }
}

void test_align_run() {
    Scene scene;
    need_scene(&scene);
    const std::string scans = work("scans.tsv");
    const auto t0 = std::chrono::steady_clock::now();
    const Run one = run({"align", scans, "--voxel", kVoxel, "--out", work("one.tsv"), "--g2o", work("one.g2o"), "--tum",
                         work("one.tum"), "--kitti", work("one.kitti"), "--map", work("map.ply")});
    const double one_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    CHECK_MSG(one.code == 0, "exit %d: %s", one.code, one.err.c_str());
    CHECK(one.out.empty());
    CHECK_MSG(contains(one.err, "kissm align: 4 scans: 4 placed, 1 component; 6 pairs: 6 valid (6 edges accepted, "
                                "0 rejected), 0 not valid, 0 errors; ran 6 in "),
              "summary: %s", one.err.c_str());
    const std::string poses = read_file(work("one.tsv"));
    check_placed(poses, scene, "--pairs all");

    // The results: batch's lines named by scan, "all" in Python's order, GICP by default.
    const std::vector<std::string> results = lines_of(read_file(work("one.tsv.pairs.jsonl")));
    REQUIRE(results.size() == 6);
    const char *const order[6][2] = {{"b", "a"}, {"c", "a"}, {"d", "a"}, {"c", "b"}, {"d", "b"}, {"d", "c"}};
    for (const std::string &line : results) {
        std::string error;
        const Json j = json_parse(line, &error);
        CHECK_MSG(error.empty(), "not JSON (%s): %s", error.c_str(), line.c_str());
        const size_t k = static_cast<size_t>(j.at("pair").as_double());
        REQUIRE(k >= 1 && k <= 6);
        CHECK_MSG(j.at("source").text == order[k - 1][0] && j.at("target").text == order[k - 1][1], "pair %zu: %s", k,
                  line.c_str());
        CHECK(j.at("refine").text == "gicp" && j.at("information").is(Json::Type::Array) && !j.find("time_ms"));
    }

    // The other files agree with the poses: KITTI the same numbers, TUM and g2o a line per placed scan.
    std::vector<PoseRow> rows;
    parse_poses(poses, 4, &rows);
    REQUIRE(rows.size() == 4);
    const std::vector<std::string> kitti = lines_of(read_file(work("one.kitti")));
    REQUIRE(kitti.size() == 4);
    for (size_t k = 0; k < 4; ++k) {
        const std::vector<std::string> f = split(kitti[k], ' ');
        REQUIRE(f.size() == 12);
        for (size_t i = 0; i < 12; ++i) CHECK(std::strtod(f[i].c_str(), nullptr) == rows[k].T[i]);
    }
    CHECK(starts_with(kitti[0], "1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 0.0"));
    const std::vector<std::string> tum = lines_of(read_file(work("one.tum")));
    REQUIRE(tum.size() == 4);
    CHECK(tum[0] == "0.0 0.0 0.0 0.0 0.0 0.0 0.0 1.0");
    CHECK(starts_with(tum[3], "3.0 ") && split(tum[3], ' ').size() == 8);
    const std::vector<std::string> g2o = lines_of(read_file(work("one.g2o")));
    REQUIRE(g2o.size() == 4 + 6);
    CHECK(g2o[0] == "VERTEX_SE3:QUAT 0 0.0 0.0 0.0 0.0 0.0 0.0 1.0");
    CHECK(starts_with(g2o[4], "EDGE_SE3:QUAT 0 1 ") && split(g2o[4], ' ').size() == 3 + 7 + 21);
    const std::string map = read_file(work("map.ply"));
    size_t total = 0;
    for (size_t c : scene.counts) total += c;
    const std::string vertices = "element vertex " + std::to_string(total) + "\n";
    CHECK_MSG(contains(map.substr(0, 400), vertices), "map header lacks %s", vertices.c_str());
    CHECK(map.size() > 24 * total && map.size() < 24 * total + 400);

    // Two jobs, 2 threads each: the same poses, byte for byte; a voxelised map is smaller.
    const Run two = run({"align", scans, "--voxel", kVoxel, "--out", work("two.tsv"), "--jobs", "2", "--threads=2",
                         "-q", "--map", work("map_voxel.ply"), "--map-voxel", "0.5"});
    CHECK_EQ_INT(two.code, 0);
    CHECK_MSG(two.err.empty(), "--quiet printed: %s", two.err.c_str());
    CHECK(read_file(work("two.tsv")) == poses);
    CHECK(sorted_lines(read_file(work("two.tsv.pairs.jsonl"))) == sorted_lines(read_file(work("one.tsv.pairs.jsonl"))));
    const std::string voxel_map = read_file(work("map_voxel.ply"));
    CHECK(voxel_map.size() > 400 && voxel_map.size() < map.size() / 2);

    // Consecutive pairs only, then with a window of 2.
    const Run seq = run({"align", scans, "--voxel", kVoxel, "--out", work("seq.tsv"), "--pairs", "sequence", "-q"});
    CHECK_MSG(seq.code == 0, "sequence: exit %d: %s", seq.code, seq.err.c_str());
    check_placed(read_file(work("seq.tsv")), scene, "--pairs sequence");
    CHECK_EQ_INT(lines_of(read_file(work("seq.tsv.pairs.jsonl"))).size(), 3);
    const Run seq2 = run(
        {"align", scans, "--voxel", kVoxel, "--out", work("seq2.tsv"), "--pairs", "sequence", "--window", "2", "-q"});
    CHECK_EQ_INT(seq2.code, 0);
    CHECK_EQ_INT(lines_of(read_file(work("seq2.tsv.pairs.jsonl"))).size(), 5);

    // Loop candidates: gap 2 gives c-a, d-a and d-b (every scan lies within 30 voxels of the others), numbered
    // after the consecutive pairs, all valid and accepted; one per scan keeps the nearest of a and b for d.
    const Run loops = run({"align", scans, "--voxel", kVoxel, "--out", work("loops.tsv"), "--pairs", "sequence",
                           "--loop-gap", "2", "--g2o", work("loops.g2o")});
    CHECK_MSG(loops.code == 0, "loops: exit %d: %s", loops.code, loops.err.c_str());
    CHECK_MSG(contains(loops.err, "4 placed, 1 component; 6 pairs: 6 valid (6 edges accepted, 0 rejected)"), "%s",
              loops.err.c_str());
    check_placed(read_file(work("loops.tsv")), scene, "--pairs sequence --loop-gap 2");
    const std::vector<std::string> loop_lines = lines_of(read_file(work("loops.tsv.pairs.jsonl")));
    const char *const loop_order[6] = {"b a", "c b", "d c", "c a", "d a", "d b"};
    REQUIRE(loop_lines.size() == 6);
    for (size_t k = 0; k < 6; ++k) {
        std::string error;
        const Json j = json_parse(loop_lines[k], &error);
        CHECK_MSG(j.at("pair").as_double() == static_cast<double>(k + 1) &&
                      j.at("source").text + " " + j.at("target").text == loop_order[k],
                  "loop pair %zu: %s", k + 1, loop_lines[k].c_str());
    }
    const std::vector<std::string> loop_g2o = lines_of(read_file(work("loops.g2o")));
    REQUIRE(loop_g2o.size() == 4 + 6);
    CHECK(starts_with(loop_g2o[7], "EDGE_SE3:QUAT 0 2 ") && starts_with(loop_g2o[9], "EDGE_SE3:QUAT 1 3 "));
    const Run nearest = run({"align", scans, "--voxel", kVoxel, "--out", work("nearest.tsv"), "--pairs", "sequence",
                             "--loop-gap", "2", "--loops-per-scan", "1", "-q"});
    CHECK_EQ_INT(nearest.code, 0);
    const std::vector<std::string> nearest_lines = lines_of(read_file(work("nearest.tsv.pairs.jsonl")));
    REQUIRE(nearest_lines.size() == 5);
    CHECK(contains(nearest_lines[3], "\"pair\": 4, \"source\": \"c\", \"target\": \"a\""));
    CHECK(contains(nearest_lines[4], "\"pair\": 5, \"source\": \"d\", \"target\": \"b\""));
    // A radius nothing meets: no candidate, the consecutive pairs only.
    const Run none = run({"align", scans, "--voxel", kVoxel, "--out", work("none.tsv"), "--pairs", "sequence",
                          "--loop-gap", "2", "--loop-radius", "0.01", "-q"});
    CHECK_EQ_INT(none.code, 0);
    CHECK_EQ_INT(lines_of(read_file(work("none.tsv.pairs.jsonl"))).size(), 3);
    // --loops-per-scan 0: the first round only, the bytes of the plain sequence run.
    const Run zero = run({"align", scans, "--voxel", kVoxel, "--out", work("zero.tsv"), "--pairs", "sequence",
                          "--loop-gap", "2", "--loops-per-scan", "0", "-q"});
    CHECK_EQ_INT(zero.code, 0);
    CHECK(read_file(work("zero.tsv")) == read_file(work("seq.tsv")));
    CHECK(read_file(work("zero.tsv.pairs.jsonl")) == read_file(work("seq.tsv.pairs.jsonl")));
    // With a window below the gap: the window's pairs, then the candidates (d-a only at gap 3).
    const Run window = run({"align", scans, "--voxel", kVoxel, "--out", work("window.tsv"), "--pairs", "sequence",
                            "--window", "2", "--loop-gap", "3", "-q"});
    CHECK_EQ_INT(window.code, 0);
    const std::vector<std::string> window_lines = lines_of(read_file(work("window.tsv.pairs.jsonl")));
    REQUIRE(window_lines.size() == 6);
    CHECK(contains(window_lines[5], "\"pair\": 6, \"source\": \"d\", \"target\": \"a\""));

    // Priors: an earlier run's poses table as the positions (no drift): the same candidates as dead reckoning here;
    // a scan whose prior is nan (a row of an unplaced scan) gets and gives none.
    const Run priors = run({"align", scans, "--voxel", kVoxel, "--out", work("priors.tsv"), "--pairs", "sequence",
                            "--loop-gap", "2", "--priors", work("loops.tsv"), "-q"});
    CHECK_MSG(priors.code == 0, "priors: exit %d: %s", priors.code, priors.err.c_str());
    CHECK(read_file(work("priors.tsv.pairs.jsonl")) == read_file(work("loops.tsv.pairs.jsonl")));
    std::vector<std::string> table = lines_of(read_file(work("loops.tsv")));
    REQUIRE(table.size() == 5 && starts_with(table[1], "a\t"));
    table[1] = "a\t0\t0";
    for (int i = 0; i < 12; ++i) table[1] += "\tnan";
    std::string no_a = "# a without a prior, the other rows in another order\n" + table[0] + "\n";
    for (const size_t k : {4, 3, 1, 2}) no_a += table[k] + "\n";
    write_file(work("no_a.tsv"), no_a);
    const Run partial = run({"align", scans, "--voxel", kVoxel, "--out", work("partial.tsv"), "--pairs", "sequence",
                             "--loop-gap", "2", "--priors", work("no_a.tsv"), "-q"});
    CHECK_EQ_INT(partial.code, 0);
    const std::vector<std::string> partial_lines = lines_of(read_file(work("partial.tsv.pairs.jsonl")));
    REQUIRE(partial_lines.size() == 4); // the consecutive pairs, then d-b alone (c-a and d-a need a's prior)
    CHECK(contains(partial_lines[3], "\"pair\": 4, \"source\": \"d\", \"target\": \"b\""));

    // Two sessions (a, b) and (c, d), as Python's align_sessions: each session's odometry trusted (b-a, d-c), the
    // grid across at stride 1 (c-a, c-b, d-a, d-b), then nothing left to pair from the merged poses.
    write_file(work("sessions.tsv"), "scan\tfile\tsession\na\tscan_a.ply\tfirst\nb\tscan_b.ply\tfirst\n"
                                     "c\tscan_c.ply\tsecond\nd\tscan_d.ply\tsecond\n");
    const Run two_sessions = run({"align", work("sessions.tsv"), "--voxel", kVoxel, "--out", work("sessions_out.tsv"),
                                  "--pairs", "sessions", "--stride", "1"});
    CHECK_MSG(two_sessions.code == 0, "sessions: exit %d: %s", two_sessions.code, two_sessions.err.c_str());
    CHECK_MSG(contains(two_sessions.err, "4 placed, 1 component; 6 pairs: 6 valid (6 edges accepted"), "%s",
              two_sessions.err.c_str());
    check_placed(read_file(work("sessions_out.tsv")), scene, "--pairs sessions");
    const std::vector<std::string> session_lines = lines_of(read_file(work("sessions_out.tsv.pairs.jsonl")));
    const char *const session_order[6] = {"b a", "d c", "c a", "c b", "d a", "d b"};
    REQUIRE(session_lines.size() == 6);
    for (size_t k = 0; k < 6; ++k) {
        std::string error;
        const Json j = json_parse(session_lines[k], &error);
        CHECK_MSG(j.at("pair").as_double() == static_cast<double>(k + 1) &&
                      j.at("source").text + " " + j.at("target").text == session_order[k],
                  "session pair %zu: %s", k + 1, session_lines[k].c_str());
    }
    // Stride 2: the grid is c-a alone; the merged poses then pair c and d with their nearest of a and b.
    const Run strided = run({"align", work("sessions.tsv"), "--voxel", kVoxel, "--out", work("strided.tsv"), "--pairs",
                             "sessions", "--stride", "2", "--loops-per-scan", "1", "-q"});
    CHECK_EQ_INT(strided.code, 0);
    check_placed(read_file(work("strided.tsv")), scene, "--pairs sessions --stride 2");
    const std::vector<std::string> strided_lines = lines_of(read_file(work("strided.tsv.pairs.jsonl")));
    REQUIRE(strided_lines.size() >= 3);
    CHECK(contains(strided_lines[2], "\"pair\": 3, \"source\": \"c\", \"target\": \"a\""));
    // A session interrupted by another, and a scans file without sessions, are refused.
    write_file(work("split.tsv"), "scan\tfile\tsession\na\tscan_a.ply\t1\nb\tscan_b.ply\t2\nc\tscan_c.ply\t1\n");
    expect_usage_error(
        {"align", work("split.tsv"), "--voxel", kVoxel, "--out", work("split_out.tsv"), "--pairs", "sessions"},
        "line 4: session '1' began at line 2");
    expect_usage_error({"align", scans, "--voxel", kVoxel, "--out", work("nosession.tsv"), "--pairs", "sessions"},
                       "needs a session column");

    // A pairs file (a star on c, one pair the other way round), its own --results.
    write_file(work("star.tsv"), "# star\nsource\ttarget\na\tc\nb\tc\nd\tc\n");
    const Run star = run({"align", scans, "--voxel", kVoxel, "--out", work("star.tsv.out"), "--pairs", work("star.tsv"),
                          "--results", work("star.jsonl")});
    CHECK_MSG(star.code == 0, "pairs file: exit %d: %s", star.code, star.err.c_str());
    check_placed(read_file(work("star.tsv.out")), scene, "--pairs FILE");
    CHECK(contains(read_file(work("star.jsonl")), "\"source\": \"a\", \"target\": \"c\""));

    // A scan that matches nothing (uniform noise) is not placed: exit 1, nan pose, the others still written.
    std::vector<double> noise;
    uint64_t state = 34;
    for (int i = 0; i < 3 * 3000; ++i) noise.push_back(20.0 * splitmix64_uniform(&state) - 10.0);
    std::string error;
    CHECK(kissm_cli::write_ply_xyz(work("noise.ply"), noise.data(), 3000, nullptr, {"noise"}, &error));
    write_file(work("five.tsv"), scans_tsv_text() + "z\t\tnoise.ply\tply\n");
    const Run five = run({"align", work("five.tsv"), "--voxel", kVoxel, "--out", work("five.tsv.out"), "--kitti",
                          work("five.kitti"), "--tum", work("five.tum")});
    CHECK_MSG(five.code == 1, "noise scan: exit %d: %s", five.code, five.err.c_str());
    CHECK_MSG(contains(five.err, "kissm align: 5 scans: 4 placed, 2 components; 10 pairs: 6 valid"), "%s",
              five.err.c_str());
    const std::vector<std::string> five_lines = lines_of(read_file(work("five.tsv.out")));
    REQUIRE(five_lines.size() == 6);
    CHECK_MSG(starts_with(five_lines[5], "z\t0\t4\tnan\tnan\t"), "%s", five_lines[5].c_str());
    CHECK(lines_of(read_file(work("five.tsv.out"))).size() == 6);
    CHECK(lines_of(read_file(work("five.kitti")))[4] == "nan nan nan nan nan nan nan nan nan nan nan nan");
    CHECK_EQ_INT(lines_of(read_file(work("five.tum"))).size(), 4);
    std::fprintf(stderr, "first run (6 pairs, all outputs): %.2f s\n", one_s);
}

void test_align_resume() {
    Scene scene;
    need_scene(&scene);
    const std::string scans = work("scans.tsv");
    const std::string ref = work("ref.tsv"), out = work("out.tsv");
    const Run reference = run({"align", scans, "--voxel", kVoxel, "--out", ref, "--g2o", work("ref.g2o"), "-q"});
    CHECK_EQ_INT(reference.code, 0);
    const std::string poses = read_file(ref), results = read_file(ref + ".pairs.jsonl");
    const std::vector<std::string> lines = lines_of(results);
    REQUIRE(lines.size() == 6);

    // A killed run: two pairs done and part of a third written. --resume drops the part and runs 4.
    write_file(out + ".pairs.jsonl", lines[0] + "\n" + lines[1] + "\n" + lines[2].substr(0, 50));
    const Run resumed = run({"align", scans, "--voxel", kVoxel, "--out", out, "--g2o", work("out.g2o"), "--resume"});
    CHECK_MSG(resumed.code == 0, "resume: exit %d: %s", resumed.code, resumed.err.c_str());
    CHECK_MSG(contains(resumed.err, "dropped the partial last line"), "%s", resumed.err.c_str());
    CHECK_MSG(contains(resumed.err, "; ran 4 in "), "%s", resumed.err.c_str());
    CHECK(read_file(out) == poses);
    CHECK(read_file(work("out.g2o")) == read_file(work("ref.g2o")));
    CHECK(sorted_lines(read_file(out + ".pairs.jsonl")) == sorted_lines(results));

    // Resumed at 2 jobs from one pair, its lines in another order: the same bytes again.
    write_file(out + ".pairs.jsonl", lines[4] + "\n");
    const Run two = run({"align", scans, "--voxel", kVoxel, "--out", out, "--resume", "--jobs", "2", "-q"});
    CHECK_EQ_INT(two.code, 0);
    CHECK(read_file(out) == poses);

    // A complete file runs nothing; without --resume it is refused, untouched.
    const std::string complete = read_file(out + ".pairs.jsonl");
    const Run again = run({"align", scans, "--voxel", kVoxel, "--out", out, "--resume"});
    CHECK_EQ_INT(again.code, 0);
    CHECK_MSG(contains(again.err, "; ran 0 in "), "%s", again.err.c_str());
    CHECK(read_file(out) == poses && read_file(out + ".pairs.jsonl") == complete);
    expect_usage_error({"align", scans, "--voxel", kVoxel, "--out", out}, "exists and is not empty");
    CHECK(read_file(out + ".pairs.jsonl") == complete);

    // --pairs sequence with loop candidates (3 consecutive pairs, then 3 loops): killed in round 2 (pairs 1-4
    // done, part of 5), after round 1 (1-3), and in round 1 (1-2, part of 3): the same bytes each time.
    const std::vector<std::string> loop_args = {"align",    scans,        "--voxel", kVoxel, "--pairs",
                                                "sequence", "--loop-gap", "2",       "--g2o"};
    const auto loop_run = [&](const std::string &poses_file, const std::vector<std::string> &extra) {
        std::vector<std::string> args = loop_args;
        args.push_back(poses_file + ".g2o");
        args.insert(args.end(), {"--out", poses_file});
        args.insert(args.end(), extra.begin(), extra.end());
        return run(args);
    };
    const std::string lref = work("lref.tsv"), lout = work("lout.tsv");
    CHECK_EQ_INT(loop_run(lref, {"-q"}).code, 0);
    const std::string loop_poses = read_file(lref), loop_results = read_file(lref + ".pairs.jsonl");
    const std::vector<std::string> ll = lines_of(loop_results);
    REQUIRE(ll.size() == 6);
    for (size_t k = 0; k < 6; ++k) REQUIRE(starts_with(ll[k], "{\"pair\": " + std::to_string(k + 1) + ","));
    const struct {
        std::string file;
        const char *ran;
    } kills[] = {{ll[0] + "\n" + ll[1] + "\n" + ll[2] + "\n" + ll[3] + "\n" + ll[4].substr(0, 40), "; ran 2 in "},
                 {ll[0] + "\n" + ll[1] + "\n" + ll[2] + "\n", "; ran 3 in "},
                 {ll[2] + "\n" + ll[0] + "\n" + ll[5].substr(0, 60), "; ran 4 in "},
                 {ll[5] + "\n" + ll[1] + "\n" + ll[0] + "\n" + ll[2] + "\n", "; ran 2 in "}};
    for (const auto &kill : kills) {
        write_file(lout + ".pairs.jsonl", kill.file);
        const Run r = loop_run(lout, {"--resume"});
        CHECK_MSG(r.code == 0, "loop resume: exit %d: %s", r.code, r.err.c_str());
        CHECK_MSG(contains(r.err, kill.ran), "expected '%s': %s", kill.ran, r.err.c_str());
        CHECK(read_file(lout) == loop_poses);
        CHECK(read_file(lout + ".g2o") == read_file(lref + ".g2o"));
        CHECK(sorted_lines(read_file(lout + ".pairs.jsonl")) == sorted_lines(loop_results));
    }
    // Round 2's records without all of round 1's, or beyond round 2's list: another pair list's results.
    write_file(lout + ".pairs.jsonl", ll[0] + "\n" + ll[4] + "\n");
    expect_usage_error(
        {"align", scans, "--voxel", kVoxel, "--pairs", "sequence", "--loop-gap", "2", "--out", lout, "--resume"},
        "results of another pair list?");
    write_file(lout + ".pairs.jsonl", loop_results);
    expect_usage_error({"align", scans, "--voxel", kVoxel, "--pairs", "sequence", "--loop-gap", "2", "--loops-per-scan",
                        "1", "--out", lout, "--resume"},
                       "results of another pair list?");
}

// The five KITTI 07 keyframes of ../shared/data: every one placed within 2 degrees and 2 voxels of the ground
// truth, both anchored on the first.
void test_align_realdata() {
    const char *root = std::getenv("KISSM_DATA_DIR");
    const fs::path set = fs::path(root ? root : "") / "kitti07_keyframes_gtsam_points" / "multiway";
    const std::vector<double> gt_numbers = [&] {
        std::vector<double> v;
        for (const std::string &line : lines_of(read_file((set / "gt_poses.txt").string()))) {
            const std::vector<std::string> f = split(line, ' ');
            for (size_t i = 1; i < f.size(); ++i) v.push_back(std::strtod(f[i].c_str(), nullptr));
        }
        return v;
    }();
    if (!root || !*root || !fs::exists(set / "scans.tsv") || gt_numbers.size() != 5 * 12) {
        std::fprintf(stderr, "skipped: KISSM_DATA_DIR (../shared/data) with kitti07_keyframes_gtsam_points/multiway "
                             "is not available\n");
        std::exit(77);
    }
    using namespace kissm_pose;
    std::vector<Pose> world(5);
    for (size_t k = 0; k < 5; ++k) {
        double T[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
        for (size_t i = 0; i < 12; ++i) T[i] = gt_numbers[12 * k + i];
        world[k] = pose_from_matrix(T);
    }
    std::vector<std::array<double, 16>> truth(5);
    for (size_t k = 0; k < 5; ++k) pose_to_matrix(pose_compose(pose_inverse(world[0]), world[k]), truth[k].data());
    const Run r =
        run({"align", (set / "scans.tsv").string(), "--voxel", "0.5", "--out", work("kitti.tsv"), "--jobs", "2"});
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err.c_str());
    std::vector<PoseRow> rows;
    parse_poses(read_file(work("kitti.tsv")), 5, &rows);
    REQUIRE(rows.size() == 5);
    for (const PoseRow &row : rows) CHECK_MSG(row.placed, "scan %s not placed", row.scan.c_str());
    double deg = 0.0, m = 0.0;
    worst_error(rows, truth, &deg, &m);
    CHECK_MSG(deg < 2.0 && m < 2 * 0.5, "worst error %g deg, %g m", deg, m);
    std::fprintf(stderr, "kitti07 multiway: worst error %.3f deg, %.3f m; %s", deg, m, r.err.c_str());

    // A sequence with loop candidates 2 apart: the 4 consecutive pairs and 2 loops, all 5 placed.
    const Run loops = run({"align", (set / "scans.tsv").string(), "--voxel", "0.5", "--out", work("kitti_loops.tsv"),
                           "--pairs", "sequence", "--loop-gap", "2", "--jobs", "2"});
    CHECK_MSG(loops.code == 0, "loops: exit %d: %s", loops.code, loops.err.c_str());
    CHECK_MSG(contains(loops.err, "5 scans: 5 placed, 1 component; 6 pairs: 6 valid"), "%s", loops.err.c_str());
    parse_poses(read_file(work("kitti_loops.tsv")), 5, &rows);
    REQUIRE(rows.size() == 5);
    for (const PoseRow &row : rows) CHECK_MSG(row.placed, "loops: scan %s not placed", row.scan.c_str());
    worst_error(rows, truth, &deg, &m);
    CHECK_MSG(deg < 2.0 && m < 2 * 0.5, "loops: worst error %g deg, %g m", deg, m);
    std::fprintf(stderr, "kitti07 sequence, loop gap 2: worst error %.3f deg, %.3f m; %s", deg, m, loops.err.c_str());
}

} // namespace

int main(int argc, char **argv) {
    std::string which;
    if (!prepare_case(argc, argv, &g_kissm, &g_work, &which)) return 2;
    g_work = fs::absolute(g_work).string(); // an absolute path in a scans file
    const CliCase cases[] = {{"align_usage", test_align_usage},
                             {"align_run", test_align_run},
                             {"align_resume", test_align_resume},
                             {"align_realdata", test_align_realdata}};
    return run_named_case(which, cases);
}
#endif
