// SPDX-License-Identifier: MIT
// Runs `kissm batch` as a user would and checks exit codes, messages and the results file byte for byte.
//
//   cli_batch_test KISSM_BINARY WORK_DIR CASE
//
// CASE: batch_usage | batch_run | batch_resume. The clouds are the committed pair of tests/data
// (KISSM_TEST_DATA) and rigid copies of its source, so every pair has an exact ground truth. batch_resume
// kills a run with SIGKILL at a known point: one cloud of its pairs file is a named pipe, on whose open the
// run blocks after the pairs before it are written. POSIX only (77 elsewhere).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_case_main.hpp"
#include "cli_test_util.hpp"
#include "harness.h"
#include "ply_writer.hpp"
#include "pose_math.hpp"
#include "transform_file.hpp"

#if defined(_WIN32)
int main() {
    std::fprintf(stderr, "cli_batch_test: POSIX only (named pipes, SIGKILL); skipped\n");
    return 77;
}
#else
#  include <chrono>
#  include <csignal>
#  include <fcntl.h>
#  include <spawn.h>
#  include <sys/stat.h>
#  include <sys/wait.h>
#  include <thread>
#  include <unistd.h>

extern char **environ;

namespace fs = std::filesystem;
using namespace cli_test;

namespace {

std::string g_kissm, g_work;
int g_runs = 0;

std::string work(const std::string &name) { return (fs::path(g_work) / name).string(); }

struct Child {
    pid_t pid = -1;
    std::string out_path, err_path;
};

// Starts the binary with `args` (no shell), stdout and stderr into files of the work folder.
Child start(const std::vector<std::string> &args) {
    Child c;
    const int n = ++g_runs;
    c.out_path = work("run" + std::to_string(n) + ".out");
    c.err_path = work("run" + std::to_string(n) + ".err");
    std::vector<std::string> all = {g_kissm};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char *> argv;
    for (std::string &a : all) argv.push_back(&a[0]);
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, c.out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, c.err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (posix_spawn(&c.pid, g_kissm.c_str(), &actions, nullptr, argv.data(), environ) != 0) c.pid = -1;
    posix_spawn_file_actions_destroy(&actions);
    if (c.pid <= 0) {
        std::fprintf(stderr, "cannot start %s\n", g_kissm.c_str());
        std::exit(1);
    }
    return c;
}

struct Run {
    int code = -1; // exit status; -1 when killed by a signal
    std::string out, err;
};

Run finish(const Child &c) {
    int status = 0;
    Run r;
    if (waitpid(c.pid, &status, 0) == c.pid && WIFEXITED(status)) r.code = WEXITSTATUS(status);
    r.out = read_file(c.out_path);
    r.err = read_file(c.err_path);
    return r;
}

Run run(const std::vector<std::string> &args) { return finish(start(args)); }

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

std::vector<std::string> sorted_lines(const std::string &text) {
    std::vector<std::string> lines = lines_of(text);
    std::sort(lines.begin(), lines.end());
    return lines;
}

// ---------------------------------------------------------------------------------------------------
// The clouds: the committed source (c0), target and rigid copies of the source (c2 = T2 c0, c3 = T3 c0).

constexpr const char *kVoxel = "0.25"; // golden.json's for the committed pair

struct Scene {
    double truth[16]; // committed target from source
    double T2[16], T3[16];
};

void write_transform(const std::string &name, const double T[16]) {
    std::string error;
    CHECK_MSG(kissm_cli::write_transform_file(work(name), T, &error), "%s", error.c_str());
}

// Writes into the work folder: src.ply, tgt.ply (the committed pair), c2.ply, c3.ply and the ground-truth
// files gt_*.txt of the pairs the cases use. False (77) when tests/data is not reachable.
bool make_scene(Scene *s) {
    const char *dir = std::getenv("KISSM_TEST_DATA");
    if (!dir || !*dir) return false;
    const fs::path data(dir);
    std::error_code ec;
    fs::copy_file(data / "roundtrip_source.ply", work("src.ply"), fs::copy_options::overwrite_existing, ec);
    fs::copy_file(data / "roundtrip_target.ply", work("tgt.ply"), fs::copy_options::overwrite_existing, ec);
    if (ec) return false;
    std::string error;
    if (!kissm_cli::read_transform_file((data / "roundtrip_ground_truth.txt").string(), s->truth, &error)) return false;
    kissm_cloud *cloud = nullptr;
    if (kissm_read_points(work("src.ply").c_str(), KISSM_FORMAT_AUTO, &cloud) != KISSM_OK) return false;
    const double *xyz = kissm_cloud_data(cloud);
    const size_t n = static_cast<size_t>(kissm_cloud_count(cloud));
    using namespace kissm_cli;
    using namespace kissm_pose;
    pose_to_matrix(pose_from_ypr(deg_to_rad(70.0), deg_to_rad(5.0), deg_to_rad(-3.0), 4.0, -2.0, 0.5), s->T2);
    pose_to_matrix(pose_from_ypr(deg_to_rad(-120.0), 0.0, deg_to_rad(8.0), -3.0, 6.0, 1.0), s->T3);
    CHECK(write_ply_xyz(work("c2.ply"), xyz, n, s->T2, {"cli_batch_test"}, &error));
    CHECK(write_ply_xyz(work("c3.ply"), xyz, n, s->T3, {"cli_batch_test"}, &error));
    kissm_cloud_destroy(cloud);
    const Pose p2 = pose_from_matrix(s->T2), p3 = pose_from_matrix(s->T3), g = pose_from_matrix(s->truth);
    double T[16];
    write_transform("gt_src_tgt.txt", s->truth);
    pose_to_matrix(pose_inverse(p2), T);
    write_transform("gt_c2_src.txt", T);
    write_transform("gt_src_c3.txt", s->T3);
    pose_to_matrix(pose_compose(p3, pose_inverse(p2)), T);
    write_transform("gt_c2_c3.txt", T);
    pose_to_matrix(pose_compose(g, pose_inverse(p3)), T);
    write_transform("gt_c3_tgt.txt", T);
    return true;
}

// ---------------------------------------------------------------------------------------------------

void test_batch_usage() {
    const std::string pairs = work("pairs.tsv");
    write_file(pairs, "source\ttarget\na.ply\tb.ply\n");
    const std::string out = work("out.jsonl");
    expect_usage_error({"batch"}, "batch expects 1 pairs file, got 0");
    expect_usage_error({"batch", pairs, pairs, "--voxel", "1", "--out", out}, "batch expects 1 pairs file, got 2");
    expect_usage_error({"batch", pairs, "--out", out}, "batch needs --voxel V");
    expect_usage_error({"batch", pairs, "--voxel", "1"}, "batch needs --out FILE");
    for (const char *bad : {"0", "-1", "x", "1025"}) {
        expect_usage_error({"batch", pairs, "--voxel", "1", "--out", out, "--jobs", bad}, "--jobs");
    }
    // register's per-run outputs mean nothing for a batch
    for (const char *option : {"--json", "--out-transform=t.txt", "--out-aligned=a.ply", "--out-topview=t.png"}) {
        expect_usage_error({"batch", pairs, "--voxel", "1", "--out", out, option}, "unknown option");
    }
    expect_usage_error({"batch", pairs, "--voxel", "1", "--out", out, "--resume=yes"}, "--resume takes no value");
    // register's settings are checked as there
    expect_usage_error({"batch", pairs, "--voxel", "1", "--out", out, "--rotation-dof", "2"},
                       "invalid --rotation-dof: config.rotation_dof is 2");
    expect_usage_error({"batch", pairs, "--preset", "nope", "--out", out}, "--preset");

    const auto bad_pairs = [&](const std::string &text, const std::string &about) {
        write_file(pairs, text);
        expect_usage_error({"batch", pairs, "--voxel", "1", "--out", out}, about);
    };
    expect_usage_error({"batch", work("nope.tsv"), "--voxel", "1", "--out", out}, "cannot read the pairs file");
    bad_pairs("", "no header line");
    bad_pairs("# only a comment\n\n", "no header line");
    bad_pairs("source target\na.ply b.ply\n", "line 1: the header has no 'source' column");
    bad_pairs("source\tgt\na.ply\tb.txt\n", "line 1: the header has no 'target' column");
    bad_pairs("source\ttarget\tsource\na\tb\tc\n", "the header names the column 'source' twice");
    bad_pairs("# pairs\nsource\ttarget\na.ply\tb.ply\n\na.ply\n", "line 5: 1 tab-separated fields, the header has 2");
    bad_pairs("source\ttarget\n\tb.ply\n", "line 2: empty source path");
    CHECK_MSG(!fs::exists(out), "a usage error created %s", out.c_str());

    // Help, in both spellings, and in the overview.
    const Run help = run({"batch", "--help"});
    CHECK_EQ_INT(help.code, 0);
    CHECK(starts_with(help.out, "usage: kissm batch PAIRS.tsv"));
    CHECK(contains(help.out, "--resume") && contains(help.out, "--jobs N") && contains(help.out, "Exit status: 0"));
    CHECK(help.err.empty());
    const Run help2 = run({"help", "batch"});
    CHECK_EQ_INT(help2.code, 0);
    CHECK(help2.out == help.out);
    CHECK(contains(run({"--help"}).out, "kissm batch PAIRS.tsv"));
}

// The fields every line has, in order, then the status's.
void check_line_shape(const Json &j, const char *what) {
    const std::vector<std::string> keys = j.keys();
    CHECK_MSG(keys.size() > 7 && keys[0] == "pair" && keys[1] == "source" && keys[2] == "target" && keys[3] == "gt" &&
                  keys[4] == "status",
              "%s: keys start %s", what, keys.empty() ? "(none)" : keys[0].c_str());
    CHECK_MSG(!j.find("time_ms"), "%s: a line holds timings", what);
    const std::string status = j.at("status").text;
    if (status == "ok") {
        CHECK_MSG(keys[5] == "valid" && keys[6] == "reason", "%s: ok line without valid, reason", what);
        CHECK_MSG(j.at("transform").is(Json::Type::Array), "%s: no transform", what);
    } else {
        CHECK_MSG(status == "error", "%s: status '%s'", what, status.c_str());
        CHECK_MSG(keys.size() == 8 && keys[5] == "message" && keys[6] == "valid" && keys[7] == "transform", "%s: %s",
                  what, "error line fields");
        CHECK(j.at("valid").is(Json::Type::Bool) && !j.at("valid").boolean);
        CHECK(j.at("transform").is(Json::Type::Null));
    }
}

struct Expected {
    const char *source, *target, *gt; // as written; gt "" = none (null in the line)
    bool error;
};

// pairs.tsv of batch_run: relative and absolute paths, a gt per pair but the last, and a missing cloud.
std::vector<Expected> run_pairs(std::string *tsv) {
    static const std::string abs_tgt = work("tgt.ply");
    const std::vector<Expected> rows = {{"src.ply", "tgt.ply", "gt_src_tgt.txt", false},
                                        {"c2.ply", "src.ply", "gt_c2_src.txt", false},
                                        {"src.ply", "c3.ply", "gt_src_c3.txt", false},
                                        {"c2.ply", "c3.ply", "gt_c2_c3.txt", false},
                                        {"missing.ply", "src.ply", "gt_c2_src.txt", true},
                                        {"c3.ply", abs_tgt.c_str(), "gt_c3_tgt.txt", false},
                                        {"src.ply", "c2.ply", "", false}};
    *tsv = "# kissm batch test pairs\r\nsource\ttarget\tid\tgt\r\n";
    int id = 0;
    for (const Expected &e : rows) {
        *tsv += std::string(e.source) + "\t" + e.target + "\tp" + std::to_string(++id) + "\t" + e.gt + "\r\n";
    }
    return rows;
}

void test_batch_run() {
    Scene scene;
    if (!make_scene(&scene)) {
        std::fprintf(stderr, "cli_batch_test: KISSM_TEST_DATA (tests/data) is not available\n");
        std::exit(77);
    }
    std::string tsv;
    const std::vector<Expected> rows = run_pairs(&tsv);
    const std::string pairs = work("pairs.tsv");
    write_file(pairs, tsv);
    const auto t0 = std::chrono::steady_clock::now();
    const Run one = run({"batch", pairs, "--voxel", kVoxel, "--out", work("one.jsonl")});
    const double one_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    CHECK_MSG(one.code == 1, "exit %d, expected 1 (a missing cloud); stderr: %s", one.code, one.err.c_str());
    CHECK(one.out.empty());
    CHECK_MSG(contains(one.err, "kissm batch: 7 pairs: 6 valid, 0 not valid, 1 error; ran 7 in "), "summary: %s",
              one.err.c_str());
    const std::string text = read_file(work("one.jsonl"));
    const std::vector<std::string> lines = lines_of(text);
    CHECK_EQ_INT(lines.size(), rows.size());
    CHECK(!text.empty() && text.back() == '\n');
    std::vector<int> seen(rows.size() + 1, 0);
    for (const std::string &line : lines) {
        std::string error;
        const Json j = json_parse(line, &error);
        CHECK_MSG(error.empty(), "not JSON (%s): %s", error.c_str(), line.c_str());
        const double pair = j.at("pair").as_double();
        REQUIRE(pair >= 1 && pair <= static_cast<double>(rows.size()) && pair == std::floor(pair));
        const size_t k = static_cast<size_t>(pair);
        ++seen[k];
        const Expected &e = rows[k - 1];
        check_line_shape(j, line.c_str());
        CHECK_MSG(j.at("source").text == e.source && j.at("target").text == e.target, "pair %zu: %s", k, line.c_str());
        if (*e.gt) {
            CHECK_MSG(j.at("gt").text == e.gt, "pair %zu gt", k);
        } else {
            CHECK_MSG(j.at("gt").is(Json::Type::Null) && !j.find("rotation_error_deg"), "pair %zu: gt null", k);
        }
        if (e.error) {
            CHECK_MSG(j.at("message").text.find("source 'missing.ply': cannot read it: ") == 0, "pair %zu: %s", k,
                      j.at("message").text.c_str());
            continue;
        }
        CHECK_MSG(j.at("status").text == "ok" && j.at("valid").boolean, "pair %zu not valid: %s", k, line.c_str());
        if (!*e.gt) continue;
        const double deg = j.at("rotation_error_deg").as_double(), m = j.at("translation_error_m").as_double();
        CHECK_MSG(deg < 1.0 && m < 0.1, "pair %zu: error %g deg, %g m", k, deg, m);
        // The line's error is the tool's measure of its own transform against the gt file.
        const std::vector<double> T = j.at("transform").flat();
        double gt[16];
        std::string gt_error;
        REQUIRE(kissm_cli::read_transform_file(work(e.gt), gt, &gt_error));
        REQUIRE(T.size() == 16);
        CHECK_NEAR(deg, kissm_pose::rotation_error_deg(T.data(), gt), 1e-9);
        CHECK_NEAR(m, kissm_pose::translation_error(T.data(), gt), 1e-12);
    }
    for (size_t k = 1; k <= rows.size(); ++k) CHECK_MSG(seen[k] == 1, "pair %zu has %d lines", k, seen[k]);

    // Two jobs (and 2 threads each): the same lines, byte for byte.
    const Run two =
        run({"batch", pairs, "--voxel", kVoxel, "--out", work("two.jsonl"), "--jobs", "2", "--threads=2", "--quiet"});
    CHECK_EQ_INT(two.code, 1);
    CHECK_MSG(two.err.empty(), "--quiet printed: %s", two.err.c_str());
    CHECK(sorted_lines(read_file(work("two.jsonl"))) == sorted_lines(text));

    // register's settings apply: --refine gicp makes refined lines (one pair: refinement is slow under ASan).
    write_file(work("one.tsv"), "source\ttarget\nsrc.ply\ttgt.ply\n");
    const Run refined =
        run({"batch", work("one.tsv"), "--voxel", kVoxel, "--out", work("gicp.jsonl"), "--refine", "gicp", "-q"});
    CHECK_EQ_INT(refined.code, 0);
    const Json first = json_parse(lines_of(read_file(work("gicp.jsonl")))[0]);
    CHECK(first.at("refine").text == "gicp" && first.at("information").is(Json::Type::Array));
    std::fprintf(stderr, "first run of 7 pairs: %.2f s\n", one_s);

    // A `format` column reads a row's clouds in its format (issue 35): src.ply's points as bare float32 triples
    // under a name no reader knows, read as bin_xyz on the rows that say so; an empty field keeps the run's
    // (auto: the same file is then an error); a name that is no format is a usage error naming the line.
    {
        kissm_cloud *cloud = nullptr;
        REQUIRE(kissm_read_points(work("src.ply").c_str(), KISSM_FORMAT_AUTO, &cloud) == KISSM_OK);
        std::vector<float> xyz(3 * kissm_cloud_count(cloud));
        for (size_t i = 0; i < xyz.size(); ++i) xyz[i] = static_cast<float>(kissm_cloud_data(cloud)[i]);
        kissm_cloud_destroy(cloud);
        write_file(work("src.points"), std::string(reinterpret_cast<const char *>(xyz.data()), 4 * xyz.size()));
    }
    write_file(work("formats.tsv"), "source\ttarget\tformat\tgt\nsrc.points\ttgt.ply\t\tgt_src_tgt.txt\n"
                                    "src.points\tsrc.points\tbin_xyz\t\nsrc.points\tsrc.points\t bin_xyz_f32 \t\n");
    const Run formats = run({"batch", work("formats.tsv"), "--voxel", kVoxel, "--out", work("formats.jsonl"), "-q"});
    CHECK_MSG(formats.code == 1, "format column: exit %d (%s)", formats.code, formats.err.c_str());
    const std::vector<std::string> format_lines = lines_of(read_file(work("formats.jsonl")));
    REQUIRE(format_lines.size() == 3);
    for (const std::string &line : format_lines) {
        const Json j = json_parse(line);
        const double pair = j.at("pair").as_double();
        if (pair == 1) {
            CHECK_MSG(j.at("status").text == "error", "the run's format (auto) cannot read src.points: %s",
                      line.c_str());
        } else {
            CHECK_MSG(j.at("status").text == "ok" && j.at("valid").boolean, "pair %g: %s", pair, line.c_str());
            const std::vector<double> T = j.at("transform").flat();
            REQUIRE(T.size() == 16);
            for (int i = 0; i < 16; ++i) CHECK_NEAR(T[static_cast<size_t>(i)], (i % 5 == 0) ? 1.0 : 0.0, 1e-6);
        }
    }
    write_file(work("badformat.tsv"), "source\ttarget\tformat\nsrc.ply\ttgt.ply\tplyy\n");
    expect_usage_error({"batch", work("badformat.tsv"), "--voxel", kVoxel, "--out", work("bad.jsonl")},
                       "line 2: format");
}

void test_batch_resume() {
    Scene scene;
    if (!make_scene(&scene)) {
        std::fprintf(stderr, "cli_batch_test: KISSM_TEST_DATA (tests/data) is not available\n");
        std::exit(77);
    }
    // late.ply is c3 for the reference run and a named pipe for the run that is killed: with one job the run
    // writes pairs 1 and 2, then blocks opening it.
    const std::string pairs = work("pairs.tsv");
    write_file(pairs, "source\ttarget\n"
                      "src.ply\tc2.ply\n"
                      "c2.ply\tc3.ply\n"
                      "late.ply\tsrc.ply\n"
                      "c3.ply\tsrc.ply\n"
                      "late.ply\tc2.ply\n"
                      "tgt.ply\tsrc.ply\n");
    std::error_code ec;
    fs::copy_file(work("c3.ply"), work("late.ply"), ec);
    const std::string ref = work("ref.jsonl"), out = work("out.jsonl");
    const Run reference = run({"batch", pairs, "--voxel", kVoxel, "--out", ref, "-q"});
    CHECK_EQ_INT(reference.code, 0);
    const std::string expected = read_file(ref);
    CHECK_EQ_INT(lines_of(expected).size(), 6);

    fs::remove(work("late.ply"));
    REQUIRE(mkfifo(work("late.ply").c_str(), 0600) == 0);
    const Child child = start({"batch", pairs, "--voxel", kVoxel, "--out", out, "--jobs", "1"});
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    for (;;) {
        const std::string so_far = read_file(out);
        if (std::count(so_far.begin(), so_far.end(), '\n') >= 2 || std::chrono::steady_clock::now() > deadline) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    REQUIRE(kill(child.pid, SIGKILL) == 0);
    const Run killed = finish(child);
    CHECK_EQ_INT(killed.code, -1);
    const std::string partial = read_file(out);
    CHECK_MSG(lines_of(partial).size() == 2 && partial.back() == '\n', "killed run left [%s]", partial.c_str());
    const std::vector<std::string> ref_lines = lines_of(expected);
    CHECK(lines_of(partial) == std::vector<std::string>(ref_lines.begin(), ref_lines.begin() + 2));

    // Without --resume the finished work is not touched.
    const Run refused = run({"batch", pairs, "--voxel", kVoxel, "--out", out});
    CHECK_EQ_INT(refused.code, 2);
    CHECK(contains(refused.err, "exists and is not empty: --resume completes it"));
    CHECK(read_file(out) == partial);

    // A kill while a line was being written leaves part of it: --resume drops it, runs pairs 3 to 6 once.
    write_file(out, partial + ref_lines[2].substr(0, 40));
    fs::remove(work("late.ply"));
    fs::copy_file(work("c3.ply"), work("late.ply"), ec);
    const Run resumed = run({"batch", pairs, "--voxel", kVoxel, "--out", out, "--resume", "--jobs", "2"});
    CHECK_MSG(resumed.code == 0, "resume exited %d: %s", resumed.code, resumed.err.c_str());
    CHECK_MSG(contains(resumed.err, "dropped the partial last line"), "%s", resumed.err.c_str());
    CHECK_MSG(contains(resumed.err, "6 pairs: 6 valid, 0 not valid, 0 errors (2 done by an earlier run); ran 4 in"),
              "%s", resumed.err.c_str());
    const std::string completed = read_file(out);
    CHECK(completed.compare(0, partial.size(), partial) == 0); // appended, not rewritten
    CHECK(sorted_lines(completed) == sorted_lines(expected));

    // Resuming a complete file runs nothing and changes nothing.
    const Run again = run({"batch", pairs, "--voxel", kVoxel, "--out", out, "--resume"});
    CHECK_EQ_INT(again.code, 0);
    CHECK(contains(again.err, "(6 done by an earlier run); ran 0 in"));
    CHECK(read_file(out) == completed);

    // --resume without the file just runs.
    const Run fresh = run({"batch", pairs, "--voxel", kVoxel, "--out", work("fresh.jsonl"), "--resume", "-q"});
    CHECK_EQ_INT(fresh.code, 0);
    CHECK(read_file(work("fresh.jsonl")) == expected);

    // A file that is not this pairs file's results is refused, untouched: another pair at that number, a
    // repeated pair, a line that is not a record (but for the last).
    const auto refuse = [&](const std::string &content, const std::string &about) {
        write_file(out, content);
        expect_usage_error({"batch", pairs, "--voxel", kVoxel, "--out", out, "--resume"}, about);
        CHECK(read_file(out) == content);
    };
    std::string other = ref_lines[0] + "\n";
    other.replace(other.find("\"c2.ply\""), 8, "\"c3.ply\"");
    refuse(other, "results of another pairs file?");
    refuse(ref_lines[0] + "\n" + ref_lines[0] + "\n", "line 2 repeats pair 1");
    refuse("not json\n" + ref_lines[0] + "\n", "line 1 is not a kissm batch record");
    refuse("{\"pair\": 9, \"source\": \"a\", \"target\": \"b\", \"status\": \"ok\", \"valid\": true}\n",
           "is pair 9, but the pairs file has 6");
}

} // namespace

int main(int argc, char **argv) {
    std::string which;
    if (!prepare_case(argc, argv, &g_kissm, &g_work, &which)) return 2;
    g_work = fs::absolute(g_work).string(); // the absolute path in a pairs file
    const CliCase cases[] = {
        {"batch_usage", test_batch_usage}, {"batch_run", test_batch_run}, {"batch_resume", test_batch_resume}};
    return run_named_case(which, cases);
}
#endif
