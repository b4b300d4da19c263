// SPDX-License-Identifier: MIT
// `kissm simulate` run as a user would, and the drive simulator behind it (src/sim/drive.hpp) tested directly.
//
//   cli_simulate_test KISSM_BINARY WORK_DIR CASE
//
// CASE: simulate_usage (bad arguments exit 2 with one line, help) | simulate_run (a short drive: the files
// parse, the poses are rigid and spaced along the path, the loop table agrees with the poses, the scans are
// readable and register to the ground truth) | simulate_threads (the same bytes at --threads 1 and 2, and a
// shorter run is the start of a longer one) | simulate_drive (the library: loops of a 1,000-scan drive
// against brute force, a culled scan against a scan of the whole city).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_case_main.hpp"
#include "cli_test_util.hpp"
#include "drive.hpp"
#include "harness.h"
#include "lidar_sim.hpp"
#include "pose_math.hpp"

#if !defined(_WIN32)
#  include <sys/wait.h>
#endif

namespace fs = std::filesystem;
using namespace cli_test;
using namespace kissm_pose;

namespace {

std::string g_kissm, g_work;
int g_runs = 0;

std::string work(const std::string &name) { return (fs::path(g_work) / name).string(); }

std::string quote(const std::string &s) {
#if defined(_WIN32)
    return "\"" + s + "\"";
#else
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
#endif
}

struct Run {
    int code = -1;
    std::string out, err;
};

// args is appended to the command line as is: quote paths with quote().
Run run(const std::string &args) {
    const int n = ++g_runs;
    const std::string out_path = work("run" + std::to_string(n) + ".out");
    const std::string err_path = work("run" + std::to_string(n) + ".err");
    const int status =
        std::system((quote(g_kissm) + " " + args + " >" + quote(out_path) + " 2>" + quote(err_path)).c_str());
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

void expect_usage_error(const std::string &args, const std::string &about) {
    const Run r = run(args);
    size_t lines = 0;
    for (char c : r.err) lines += c == '\n' ? 1u : 0u;
    CHECK_MSG(r.code == 2, "'kissm %s' exited with %d, expected 2 (stderr: %s)", args.c_str(), r.code, r.err.c_str());
    CHECK_MSG(starts_with(r.err, "kissm: ") && lines == 1, "'kissm %s': stderr is not one 'kissm: ' line: [%s]",
              args.c_str(), r.err.c_str());
    CHECK_MSG(contains(r.err, about), "'kissm %s': [%s] does not mention '%s'", args.c_str(), r.err.c_str(),
              about.c_str());
    CHECK_MSG(r.out.empty(), "'kissm %s' printed on stdout: [%s]", args.c_str(), r.out.c_str());
}

std::vector<std::vector<std::string>> split_lines(const std::string &text, char sep) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        std::vector<std::string> fields;
        size_t begin = 0;
        for (;;) {
            const size_t end = line.find(sep, begin);
            fields.push_back(line.substr(begin, end == std::string::npos ? std::string::npos : end - begin));
            if (end == std::string::npos) break;
            begin = end + 1;
        }
        rows.push_back(fields);
    }
    return rows;
}

std::string scan_name(size_t i) {
    char name[24];
    std::snprintf(name, sizeof name, "%06zu", i);
    return name;
}

// gt_poses.txt as 4x4 row-major matrices; checks the names on the way.
std::vector<std::vector<double>> read_poses(const std::string &dir, size_t expected) {
    std::vector<std::vector<double>> poses;
    const auto rows = split_lines(read_file((fs::path(dir) / "gt_poses.txt").string()), ' ');
    CHECK_MSG(rows.size() == expected, "gt_poses.txt has %zu rows, expected %zu", rows.size(), expected);
    for (size_t i = 0; i < rows.size(); ++i) {
        CHECK_MSG(rows[i].size() == 13 && rows[i][0] == scan_name(i), "gt_poses.txt row %zu is malformed", i);
        if (rows[i].size() != 13) return poses;
        std::vector<double> T(16, 0.0);
        for (int k = 0; k < 12; ++k) {
            char *end = nullptr;
            T[static_cast<size_t>(k)] = std::strtod(rows[i][static_cast<size_t>(k) + 1].c_str(), &end);
            CHECK(end && *end == '\0' && std::isfinite(T[static_cast<size_t>(k)]));
        }
        T[15] = 1.0;
        poses.push_back(T);
    }
    return poses;
}

void test_usage() {
    const std::string out = quote(work("out"));
    expect_usage_error("simulate", "output folder");
    expect_usage_error("simulate " + out, "--scans");
    expect_usage_error("simulate " + out + " --scans 0", "--scans");
    expect_usage_error("simulate " + out + " --scans 2000000", "--scans");
    expect_usage_error("simulate " + out + " --scans abc", "--scans");
    expect_usage_error("simulate " + out + " --scans", "--scans");
    expect_usage_error("simulate " + out + " --scans 5 --spacing 0", "--spacing");
    expect_usage_error("simulate " + out + " --scans 5 --spacing -1", "--spacing");
    expect_usage_error("simulate " + out + " --scans 5 --spacing 1000", "--spacing");
    expect_usage_error("simulate " + out + " --scans 5 --spacing nan", "--spacing");
    expect_usage_error("simulate " + out + " --scans 5 --seed -3", "--seed");
    expect_usage_error("simulate " + out + " --scans 5 --threads -1", "--threads");
    expect_usage_error("simulate " + out + " --scans 5 --bogus", "--bogus");
    expect_usage_error("simulate " + out + " " + quote(work("other")) + " --scans 5", "one folder");
    expect_usage_error("simulate " + out + " --scans 5 -q=1", "-q");
    CHECK_MSG(!fs::exists(work("out")), "a refused command created its folder");
    // A file where the folder should be.
    CHECK(write_file(work("file"), "x"));
    expect_usage_error("simulate " + quote(work("file")) + " --scans 1", "cannot create");

    for (const char *help : {"simulate --help", "help simulate", "simulate -h --scans 0"}) {
        const Run r = run(help);
        CHECK_MSG(r.code == 0 && starts_with(r.out, "usage: kissm simulate") && r.err.empty(), "'kissm %s': %d [%s]",
                  help, r.code, r.err.c_str());
    }
    const Run r = run("--help");
    CHECK(r.code == 0 && contains(r.out, "kissm simulate OUTDIR --scans N"));
}

void test_run() {
    const std::string dir = work("drive");
    const size_t n = 30;
    const double spacing = 0.5;
    const Run r = run("simulate " + quote(dir) + " --scans 30 --spacing 0.5 --seed 7 --threads 2");
    CHECK_MSG(r.code == 0, "kissm simulate exited with %d: %s", r.code, r.err.c_str());
    CHECK_MSG(r.out.empty(), "simulate printed on stdout: [%s]", r.out.c_str());
    CHECK_MSG(contains(r.err, "kissm simulate: 30 scans") && contains(r.err, "loop pairs"), "summary: [%s]",
              r.err.c_str());

    // scans.tsv: the shared sets' header, one row per scan, each file a readable PLY in the sensor frame.
    const auto table = split_lines(read_file((fs::path(dir) / "scans.tsv").string()), '\t');
    CHECK_MSG(table.size() == n + 1, "scans.tsv has %zu lines", table.size());
    if (table.size() != n + 1) return;
    CHECK(table[0] == (std::vector<std::string>{"scan", "file", "format"}));
    for (size_t i = 0; i < n; ++i) {
        CHECK_MSG(table[i + 1] == (std::vector<std::string>{scan_name(i), "scans/" + scan_name(i) + ".ply", "ply"}),
                  "scans.tsv row %zu", i);
    }
    for (size_t i : {size_t{0}, n / 2, n - 1}) {
        const std::string path = (fs::path(dir) / table[i + 1][1]).string();
        kissm_cloud *cloud = nullptr;
        CHECK_MSG(kissm_read_points(path.c_str(), KISSM_FORMAT_AUTO, &cloud) == KISSM_OK, "cannot read %s",
                  path.c_str());
        if (!cloud) continue;
        const size_t count = kissm_cloud_count(cloud);
        const double *p = kissm_cloud_data(cloud);
        CHECK_MSG(count > 20000 && count < 70000, "scan %zu has %zu points", i, count);
        double rmin = 1e30, rmax = 0.0;
        for (size_t k = 0; k < count; ++k) {
            const double range =
                std::sqrt(p[3 * k] * p[3 * k] + p[3 * k + 1] * p[3 * k + 1] + p[3 * k + 2] * p[3 * k + 2]);
            rmin = std::fmin(rmin, range);
            rmax = std::fmax(rmax, range);
        }
        CHECK_MSG(rmin > 0.8 && rmax < 60.2, "scan %zu ranges %g..%g m", i, rmin, rmax);
        kissm_cloud_destroy(cloud);
    }

    // gt_poses.txt: rigid, a few degrees of tilt at most, `spacing` apart along the path.
    const auto poses = read_poses(dir, n);
    if (poses.size() != n) return;
    for (size_t i = 0; i < n; ++i) {
        const std::vector<double> &T = poses[i];
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) {
                const double dot =
                    T[4 * 0 + a] * T[4 * 0 + b] + T[4 * 1 + a] * T[4 * 1 + b] + T[4 * 2 + a] * T[4 * 2 + b];
                CHECK_NEAR(dot, a == b ? 1.0 : 0.0, 1e-12);
            }
        }
        const double det = T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) +
                           T[2] * (T[4] * T[9] - T[5] * T[8]);
        CHECK_NEAR(det, 1.0, 1e-12);
        CHECK_MSG(T[10] > std::cos(deg_to_rad(6.0)), "scan %zu tilts by %g degrees", i, rad_to_deg(std::acos(T[10])));
        if (i > 0) {
            const std::vector<double> &P = poses[i - 1];
            const double step = std::hypot(T[3] - P[3], T[7] - P[7]);
            CHECK_MSG(step > 0.99 * spacing && step < spacing + 1e-9, "scans %zu and %zu are %g m apart", i - 1, i,
                      step);
        }
    }

    // loops.tsv: header only here (30 scans of 0.5 m are 15 m: no loop), checked against the poses in
    // simulate_drive on a drive with loops.
    const auto loops = split_lines(read_file((fs::path(dir) / "loops.tsv").string()), '\t');
    CHECK(loops.size() == 1 &&
          loops[0] == (std::vector<std::string>{"scan_i", "scan_j", "distance_m", "along_path_m"}));

    // The data is right: two scans 10 m apart register to the relative pose of the ground truth,
    // T_i_j = inv(T_world_i) T_world_j (scan j into scan i).
    const std::string a = (fs::path(dir) / "scans" / "000000.ply").string();
    const std::string b = (fs::path(dir) / "scans" / "000020.ply").string();
    const Run reg = run("register " + quote(b) + " " + quote(a) + " --voxel 0.5 --refine gicp --json");
    CHECK_MSG(reg.code == 0, "register exited with %d: %s", reg.code, reg.err.c_str());
    try {
        const Json j = json_parse(reg.out);
        const Pose gt =
            pose_compose(pose_inverse(pose_from_matrix(poses[0].data())), pose_from_matrix(poses[20].data()));
        double G[16], T[16];
        pose_to_matrix(gt, G);
        const Json &rows = j.at("transform");
        CHECK(rows.items.size() == 4);
        for (size_t row = 0; row < 4 && row < rows.items.size(); ++row) {
            for (size_t c = 0; c < 4; ++c) T[4 * row + c] = rows.items[row].items.at(c).as_double();
        }
        CHECK_MSG(rotation_error_deg(T, G) < 0.2 && translation_error(T, G) < 0.05, "register: %g deg, %g m off",
                  rotation_error_deg(T, G), translation_error(T, G));
    } catch (const std::exception &e) {
        CHECK_MSG(false, "register --json: %s", e.what());
    }
}

void test_threads() {
    const std::string one = work("one"), two = work("two"), short_run = work("short");
    const std::string args = " --scans 12 --spacing 3 --seed 11 -q";
    const Run r1 = run("simulate " + quote(one) + args + " --threads 1");
    const Run r2 = run("simulate " + quote(two) + args + " --threads 2");
    const Run r3 = run("simulate " + quote(short_run) + " --scans 5 --spacing 3 --seed 11 -q --threads 2");
    for (const Run *r : {&r1, &r2, &r3}) {
        CHECK_MSG(r->code == 0 && r->err.empty() && r->out.empty(), "simulate -q: %d [%s]", r->code, r->err.c_str());
    }
    for (const char *name : {"scans.tsv", "gt_poses.txt", "loops.tsv"}) {
        const std::string a = read_file((fs::path(one) / name).string());
        CHECK_MSG(!a.empty() && a == read_file((fs::path(two) / name).string()), "%s differs between thread counts",
                  name);
    }
    const std::string poses = read_file((fs::path(one) / "gt_poses.txt").string());
    const std::string first = read_file((fs::path(short_run) / "gt_poses.txt").string());
    CHECK_MSG(!first.empty() && poses.compare(0, first.size(), first) == 0, "5 scans are not the start of 12");
    for (size_t i = 0; i < 12; ++i) {
        const fs::path scan = fs::path("scans") / (scan_name(i) + ".ply");
        const std::string a = read_file((fs::path(one) / scan).string());
        CHECK_MSG(a.size() > 100000 && a == read_file((fs::path(two) / scan).string()),
                  "scan %zu differs between thread counts", i);
        if (i < 5) CHECK_MSG(a == read_file((fs::path(short_run) / scan).string()), "scan %zu differs from 5's", i);
    }
    // A seed makes its own city and drive.
    const Run other = run("simulate " + quote(work("other")) + " --scans 1 --spacing 3 --seed 12 -q");
    CHECK(other.code == 0);
    CHECK(read_file(work("other/scans/000000.ply")) != read_file((fs::path(one) / "scans" / "000000.ply").string()));
}

void test_drive() {
    kissm_sim::DriveOptions options;
    options.seed = 3;
    options.scans = 1000;
    const kissm_sim::Drive a = kissm_sim::plan_drive(options);
    const kissm_sim::Drive b = kissm_sim::plan_drive(options);
    CHECK(a.poses.size() == 1000 && a.route == b.route && a.city.scene.prims.size() == b.city.scene.prims.size());
    CHECK(a.city.scene.prims.size() > 2000 && a.city.stats.buildings > 150 && a.city.stats.cars > 100);
    // Real loops: some stretches between crossings are driven again.
    CHECK_MSG(a.legs > a.distinct_legs && a.distinct_legs >= 8, "%zu stretches, %zu different", a.legs,
              a.distinct_legs);

    // The loop pairs are exactly those brute force finds.
    const double gap = 100.0, radius = 10.0;
    const std::vector<kissm_sim::LoopPair> loops = kissm_sim::true_loops(a, gap, radius);
    std::vector<std::pair<size_t, size_t>> brute;
    for (size_t i = 0; i < a.poses.size(); ++i) {
        for (size_t j = i + 1; j < a.poses.size(); ++j) {
            const double *p = a.poses[i].t, *q = a.poses[j].t;
            const double d = std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                       (p[2] - q[2]) * (p[2] - q[2]));
            if (a.distance[j] - a.distance[i] >= gap && d <= radius) brute.emplace_back(i, j);
        }
    }
    CHECK_MSG(loops.size() == brute.size() && loops.size() > 50, "%zu loop pairs, brute force %zu", loops.size(),
              brute.size());
    for (size_t k = 0; k < loops.size() && k < brute.size(); ++k) {
        CHECK(loops[k].i == brute[k].first && loops[k].j == brute[k].second);
    }

    // A scan of the culled scene is the same, bit for bit, as a scan of the whole city.
    const size_t index = 321;
    const kissm_sim::DemoScan culled = kissm_sim::simulate_drive_scan(a, index, options);
    kissm_sim::Rng rng(options.seed, 2 + index); // the scan's stream (drive.hpp)
    kissm_sim::Scene whole = a.city.scene;
    kissm_sim::add_city_movers(whole, rng, a.city, a.poses[index]);
    const kissm_sim::DemoScan full = kissm_sim::cast_scan(whole, a.poses[index], options.sensor, rng);
    CHECK_MSG(culled.xyz.size() > 60000 && culled.xyz == full.xyz, "culled %zu, whole %zu values", culled.xyz.size(),
              full.xyz.size());
}

} // namespace

int main(int argc, char **argv) {
    std::string which;
    if (!prepare_case(argc, argv, &g_kissm, &g_work, &which)) return 2;
    const CliCase cases[] = {{"simulate_usage", test_usage},
                             {"simulate_run", test_run},
                             {"simulate_threads", test_threads},
                             {"simulate_drive", test_drive}};
    return run_named_case(which, cases);
}
