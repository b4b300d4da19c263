// SPDX-License-Identifier: MIT
// kissm simulate OUTDIR --scans N [--seed S] [--spacing M] [--threads T] [-q]
//
// A long simulated drive with loops (src/sim/drive.hpp) written as a multi-scan set in the layout of the
// shared data's sets (scans.tsv, gt_poses.txt), plus the loop closures the ground truth knows (loops.tsv),
// for multiway registration and pose-graph work at the scale of thousands of scans.
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include <kissm.h>

#include "cli_args.hpp"
#include "commands.hpp"
#include "drive.hpp"
#include "json_writer.hpp"
#include "ply_writer.hpp"
#include "pose_math.hpp"

namespace kissm_cli {
using namespace kissm_pose; // src/common/pose_math.hpp
namespace {

constexpr int32_t kMaxScans = 1000000; // scan names have six digits
constexpr double kMaxSpacing = 100.0;  // metres
constexpr double kLoopGap = 100.0;     // metres along the path between the scans of a loop pair, at least
constexpr double kLoopRadius = 10.0;   // metres between their sensors, at most
constexpr double kProgressEvery = 5.0; // seconds between progress lines

struct SimulateOptions {
    std::string out_dir;
    int32_t scans = 0;
    uint64_t seed = 1;
    double spacing = 2.0;
    int32_t threads = 0;
    bool quiet = false;
};

struct FileCloser {
    void operator()(std::FILE *f) const { std::fclose(f); }
};

std::string scan_name(size_t i) {
    char name[24];
    std::snprintf(name, sizeof name, "%06zu", i);
    return name;
}

// Writes `text` to `path` whole, or throws UsageError naming the file.
void write_text(const std::string &path, const std::string &text) {
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
    if (!file || std::fwrite(text.data(), 1, text.size(), file.get()) != text.size() ||
        std::fclose(file.release()) != 0) {
        throw UsageError("cannot write '" + path + "': " + std::strerror(errno));
    }
}

SimulateOptions parse_options(const std::vector<std::string> &args, bool *help) {
    SimulateOptions opt;
    bool have_scans = false;
    ArgCursor cur("simulate", args);
    while (cur.next()) {
        const std::string name = cur.current();
        if (!cur.is_option()) {
            if (!opt.out_dir.empty()) {
                throw UsageError("simulate takes one folder, got '" + one_line(opt.out_dir) + "' and '" +
                                 one_line(name) + "' (see 'kissm simulate --help')");
            }
            opt.out_dir = name;
        } else if (cur.is_help()) {
            *help = true;
            return opt;
        } else if (name == "--scans") {
            opt.scans = parse_int32(name, cur.value(), 1, kMaxScans);
            have_scans = true;
        } else if (name == "--seed") {
            opt.seed = parse_uint64(name, cur.value());
        } else if (name == "--spacing") {
            opt.spacing = parse_positive(name, cur.value());
            if (opt.spacing > kMaxSpacing) {
                throw UsageError("--spacing must be at most " + JsonWriter::number(kMaxSpacing) + " m, got '" +
                                 one_line(JsonWriter::number(opt.spacing)) + "'");
            }
        } else if (name == "--threads") {
            opt.threads = parse_int32(name, cur.value(), 0, 4096);
        } else if (!cur.take_flag("--quiet", &opt.quiet, "-q")) {
            cur.unknown();
        }
    }
    if (opt.out_dir.empty()) throw UsageError("simulate needs an output folder (see 'kissm simulate --help')");
    if (!have_scans) throw UsageError("simulate needs --scans N (see 'kissm simulate --help')");
    return opt;
}

// The scans.tsv, gt_poses.txt and loops.tsv texts.
std::string scans_table(size_t scans) {
    std::string out = "scan\tfile\tformat\n";
    for (size_t i = 0; i < scans; ++i) out += scan_name(i) + "\tscans/" + scan_name(i) + ".ply\tply\n";
    return out;
}

std::string gt_poses_text(const kissm_sim::Drive &drive) {
    std::string out;
    for (size_t i = 0; i < drive.poses.size(); ++i) {
        const Pose &p = drive.poses[i];
        out += scan_name(i);
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) out += " " + JsonWriter::number(p.R[3 * r + c]);
            out += " " + JsonWriter::number(p.t[r]);
        }
        out += "\n";
    }
    return out;
}

std::string loops_text(const kissm_sim::Drive &drive, const std::vector<kissm_sim::LoopPair> &loops) {
    std::string out = "scan_i\tscan_j\tdistance_m\talong_path_m\n";
    char numbers[64];
    for (const kissm_sim::LoopPair &l : loops) {
        std::snprintf(numbers, sizeof numbers, "\t%.3f\t%.3f\n", l.distance, drive.distance[l.j] - drive.distance[l.i]);
        out += scan_name(l.i) + "\t" + scan_name(l.j) + numbers;
    }
    return out;
}

// Casts and writes the scans on `threads` threads, each taking the next scan not yet taken; prints a progress
// line on stderr at most every kProgressEvery seconds. Returns the number of points written.
uint64_t write_scans(const kissm_sim::Drive &drive, const kissm_sim::DriveOptions &drive_options,
                     const SimulateOptions &opt, const std::string &scan_dir, int threads) {
    const size_t total = drive.poses.size();
    std::atomic<size_t> next{0}, done{0};
    std::atomic<uint64_t> points{0};
    std::atomic<bool> failed{false};
    std::mutex mutex;
    std::condition_variable changed;
    std::string error;
    const std::string tag = std::string("kissm ") + kissm_version_string() + " simulate, seed " +
                            std::to_string(opt.seed) + ", spacing " + JsonWriter::number(opt.spacing) + " m";

    const auto work = [&]() {
        try {
            for (size_t i = next++; i < total && !failed; i = next++) {
                const kissm_sim::DemoScan scan = kissm_sim::simulate_drive_scan(drive, i, drive_options);
                const size_t n = scan.xyz.size() / 3;
                std::string message;
                const std::string path = (std::filesystem::path(scan_dir) / (scan_name(i) + ".ply")).string();
                if (!write_ply_xyz(path, scan.xyz.data(), n, nullptr,
                                   {tag + ": scan " + scan_name(i) + ", sensor frame"}, &message)) {
                    throw std::runtime_error(message);
                }
                points += n;
                {
                    // Under the lock, so that the reporting thread cannot miss the last scan between its
                    // check and its wait.
                    const std::lock_guard<std::mutex> lock(mutex);
                    ++done;
                }
                changed.notify_all();
            }
        } catch (const std::exception &e) {
            const std::lock_guard<std::mutex> lock(mutex);
            if (!failed.exchange(true)) error = e.what();
            changed.notify_all();
        }
    };
    // The workers cast; this thread reports progress.
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back(work);
    {
        const auto start = std::chrono::steady_clock::now();
        double last = 0.0; // seconds at the last line
        std::unique_lock<std::mutex> lock(mutex);
        while (done < total && !failed) {
            changed.wait_for(lock, std::chrono::duration<double>(kProgressEvery));
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (opt.quiet || done >= total || failed || elapsed - last < kProgressEvery) continue;
            last = elapsed;
            const size_t d = done;
            const double rate = static_cast<double>(d) / elapsed;
            std::fprintf(stderr, "kissm simulate: %zu/%zu scans (%.0f%%), %.1f scans/s, ETA %.0f s\n", d, total,
                         100.0 * static_cast<double>(d) / static_cast<double>(total), rate,
                         rate > 0.0 ? static_cast<double>(total - d) / rate : 0.0);
        }
    }
    for (std::thread &t : pool) t.join();
    if (failed) throw UsageError(error);
    return points;
}

} // namespace

void print_simulate_help(std::FILE *out) {
    std::fprintf(out,
                 "usage: kissm simulate OUTDIR --scans N [--seed S] [--spacing M] [--threads T] [-q]\n"
                 "\n"
                 "Simulates a long drive through a synthetic city (a grid of 3x3 blocks of 80-120 m whose\n"
                 "streets are built like the demo's: buildings with details, walls, hedges, street lights,\n"
                 "trees, parked cars, clutter, kerbs, rough undulating ground) and scans it with the demo's\n"
                 "64-beam spinning LiDAR every M metres along the way. The route keeps to the right lane,\n"
                 "turns at crossings and comes back over crossings and streets it has driven (real loops);\n"
                 "vehicles and pedestrians differ from scan to scan. Writes into OUTDIR:\n"
                 "  scans/000000.ply ...  the scans (binary little-endian PLY, float64 x y z, sensor frames)\n"
                 "  scans.tsv             scan<TAB>file<TAB>format, one row per scan\n"
                 "  gt_poses.txt          per scan: its name, then the first 3 rows of the exact 4x4\n"
                 "                        T_world_scan (p_world = R p_scan + t), row-major\n"
                 "  loops.tsv             scan_i<TAB>scan_j<TAB>distance_m<TAB>along_path_m: the true loop\n"
                 "                        closures, pairs at least %g m apart along the path whose sensors are\n"
                 "                        within %g m of each other\n"
                 "(the layout of the shared data's multi-scan sets: T_i_j = inv(T_world_i) T_world_j maps\n"
                 "scan j into scan i's frame).\n"
                 "\n"
                 "  --scans N     number of scans, 1..%d (required)\n"
                 "  --seed S      city, route and sensor-noise seed (default 1)\n"
                 "  --spacing M   metres along the path between scans, in (0, %g] (default 2)\n"
                 "  --threads T   scans cast in parallel, 0 = all hardware threads (default 0); the files\n"
                 "                are the same bytes at any thread count\n"
                 "  -q, --quiet   no progress line and no summary on stderr\n"
                 "  -h, --help    this text\n"
                 "\n"
                 "The same seed and spacing give the same scans whatever N: a shorter run is the start of a\n"
                 "longer one. Files already in OUTDIR are overwritten; others are left alone.\n"
                 "Exit status: 0 done, 2 usage or output error.\n",
                 kLoopGap, kLoopRadius, kMaxScans, kMaxSpacing);
}

int run_simulate(const std::vector<std::string> &args) {
    bool help = false;
    const SimulateOptions opt = parse_options(args, &help);
    if (help) {
        print_simulate_help(stdout);
        return kExitOk;
    }
    const auto start = std::chrono::steady_clock::now();
    kissm_sim::DriveOptions drive_options;
    drive_options.seed = opt.seed;
    drive_options.scans = static_cast<size_t>(opt.scans);
    drive_options.spacing = opt.spacing;
    kissm_sim::Drive drive;
    try {
        drive = kissm_sim::plan_drive(drive_options);
    } catch (const std::invalid_argument &e) {
        throw UsageError(e.what());
    }
    const std::vector<kissm_sim::LoopPair> loops = kissm_sim::true_loops(drive, kLoopGap, kLoopRadius);

    std::error_code ec;
    const std::string scan_dir = (std::filesystem::path(opt.out_dir) / "scans").string();
    std::filesystem::create_directories(scan_dir, ec);
    if (ec) throw UsageError("cannot create the folder '" + one_line(scan_dir) + "': " + ec.message());

    int threads = opt.threads;
    if (threads == 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    threads = std::min(threads, opt.scans);
    if (!opt.quiet) {
        std::fprintf(stderr, "kissm simulate: %d scan%s every %g m along %.0f m through %zu primitives, %d thread%s\n",
                     opt.scans, opt.scans == 1 ? "" : "s", opt.spacing, drive.distance.back(),
                     drive.city.scene.prims.size(), threads, threads == 1 ? "" : "s");
    }
    const uint64_t points = write_scans(drive, drive_options, opt, scan_dir, threads);

    // The tables last: a run that stops early leaves no table naming scans it did not write.
    const std::filesystem::path dir(opt.out_dir);
    write_text((dir / "scans.tsv").string(), scans_table(drive.poses.size()));
    write_text((dir / "gt_poses.txt").string(), gt_poses_text(drive));
    write_text((dir / "loops.tsv").string(), loops_text(drive, loops));
    if (!opt.quiet) {
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        size_t looped = 0; // scans with a loop partner
        std::vector<bool> in_loop(drive.poses.size(), false);
        for (const kissm_sim::LoopPair &l : loops) in_loop[l.i] = in_loop[l.j] = true;
        for (bool b : in_loop) looped += b ? 1 : 0;
        std::fprintf(stderr,
                     "kissm simulate: %d scan%s (%llu points) along %.0f m, %zu stretches between crossings (%zu "
                     "different); %zu loop pairs (%zu scans in one); %.1f s; wrote %s\n",
                     opt.scans, opt.scans == 1 ? "" : "s", static_cast<unsigned long long>(points),
                     drive.distance.back(), drive.legs, drive.distinct_legs, loops.size(), looped, seconds,
                     opt.out_dir.c_str());
    }
    return kExitOk;
}

} // namespace kissm_cli
