// SPDX-License-Identifier: MIT
// kissm ground IN --voxel V [options]: the ground model of --suppression ground (kissm_ground_mask), per point,
// written as two PLY files (ground and the rest) and summarised.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_args.hpp"
#include "commands.hpp"
#include "json_writer.hpp"
#include "pair_command.hpp"
#include "ply_writer.hpp"
#include "report.hpp"

namespace kissm_cli {
namespace {

struct GroundOptions {
    std::string input;
    int32_t format = KISSM_FORMAT_AUTO;
    GroundUpOptions ground_up; // --preset, --up, --sensor-height
    bool have_voxel = false;
    double voxel = 0.0;
    int32_t threads = 0;
    bool have_viewpoint = false;
    double viewpoint[3] = {0.0, 0.0, 0.0};
    bool drop_nonfinite = false;
    bool json = false;
    bool verbose = false;
    std::string out_ground;
    std::string out_rest;
};

// Returns false when it printed the help.
bool parse_ground_options(const std::vector<std::string> &args, GroundOptions *out) {
    GroundOptions opt;
    ArgCursor cur("ground", args);
    size_t positional = 0;
    while (cur.next()) {
        const std::string name = cur.current();
        if (!cur.is_option()) {
            if (positional++ == 0) opt.input = name;
        } else if (cur.is_help()) {
            print_ground_help(stdout);
            return false;
        } else if (name == "--voxel") {
            opt.voxel = parse_positive(name, cur.value());
            opt.have_voxel = true;
        } else if (take_ground_up_option(cur, false, &opt.ground_up)) {
            // --preset, --up, --sensor-height
        } else if (name == "--threads") {
            opt.threads = parse_int32(name, cur.value(), 0, 4096);
        } else if (name == "--format") {
            opt.format = parse_format(name, cur.value());
        } else if (name == "--viewpoint") {
            const std::string text = cur.value();
            if (text.find(',') == std::string::npos) { // register's modes (fixed, center, ...) mean nothing here
                throw UsageError("--viewpoint of 'kissm ground' is the sensor's position X,Y,Z in the cloud's frame, "
                                 "got '" +
                                 one_line(text) + "'");
            }
            parse_vec3(name, text, opt.viewpoint);
            opt.have_viewpoint = true;
        } else if (name == "--out-ground") {
            opt.out_ground = cur.value();
        } else if (name == "--out-rest") {
            opt.out_rest = cur.value();
        } else if (!cur.take_flag("--drop-nonfinite", &opt.drop_nonfinite) && !cur.take_flag("--json", &opt.json) &&
                   !cur.take_flag("--verbose", &opt.verbose, "-v")) {
            cur.unknown();
        }
    }
    if (positional != 1) {
        throw UsageError("ground expects 1 file (IN), got " + std::to_string(positional) +
                         " (see 'kissm ground --help')");
    }
    if (!opt.have_voxel && opt.ground_up.preset == 0) {
        throw UsageError("ground needs --voxel V, the voxel size in the cloud's unit (e.g. --voxel 0.3 for outdoor "
                         "LiDAR in metres), or a --preset that gives one");
    }
    *out = opt;
    return true;
}

// The preset first, then the options given explicitly; checked by the library (messages name the option).
kissm_config ground_config(const GroundOptions &opt) {
    kissm_config config = config_with_preset(opt.ground_up.preset);
    if (opt.have_voxel) config.voxel_size = opt.voxel;
    config.num_threads = opt.threads;
    apply_ground_up(opt.ground_up, &config);
    if (opt.have_viewpoint) {
        for (int i = 0; i < 3; ++i) config.viewpoint[i] = opt.viewpoint[i];
    }
    return validated_config(config, opt.drop_nonfinite, opt.verbose);
}

struct Split {
    std::vector<double> ground, rest; // packed x y z
    uint64_t nonfinite = 0;           // dropped points (--drop-nonfinite): in neither file
};

Split split_points(const double *xyz, size_t count, const std::vector<uint8_t> &mask) {
    Split s;
    for (size_t i = 0; i < count; ++i) {
        const double *p = xyz + 3 * i;
        if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
            ++s.nonfinite;
            continue;
        }
        std::vector<double> &to = mask[i] ? s.ground : s.rest;
        to.insert(to.end(), p, p + 3);
    }
    return s;
}

void write_part(const std::string &path, const std::vector<double> &xyz, const char *what, const std::string &input) {
    if (path.empty()) return;
    const std::vector<std::string> comments = {std::string("kissm ") + kissm_version_string() + ": " + what + " of " +
                                               one_line(input)};
    std::string error;
    if (!write_ply_xyz(path, xyz.data(), xyz.size() / 3, nullptr, comments, &error)) throw UsageError(error);
}

void add_path(JsonWriter &json, const char *key, const std::string &path) {
    json.key(key);
    if (path.empty()) {
        json.null();
    } else {
        json.value(path);
    }
}

} // namespace

void print_ground_help(std::FILE *out) {
    const kissm_config d = config_defaults();
    std::fprintf(out,
                 "usage: kissm ground IN --voxel V [options]\n"
                 "       kissm ground IN --preset NAME [options]\n"
                 "\n"
                 "Labels the ground points of IN (a scan in its sensor's frame) with the ground model of\n"
                 "`kissm register --suppression ground` (kissm_ground_mask: a region-wise plane model around the\n"
                 "sensor, perpendicular to up, on the voxelised cloud; every point gets its voxel's label), writes\n"
                 "the ground and the other points as PLY files and prints how many there are.\n"
                 "\n"
                 "Input:\n"
                 "  IN                      a point file, format by extension then content\n"
                 "  --format FMT            force its format: %s\n"
                 "  --drop-nonfinite        skip NaN/Inf points (default: such points are an error); they go to\n"
                 "                          neither file\n"
                 "\n"
                 "Settings:\n"
                 "  --preset NAME           %s, applied first: the options below\n"
                 "                          override it in any order; it gives a voxel size (--voxel optional)\n"
                 "  --voxel V               voxel size in the cloud's unit, > 0 (required without --preset)\n"
                 "  --up X,Y,Z              the up direction in the cloud's frame (default %g,%g,%g), any length\n"
                 "                          above 1e-9\n"
                 "  --sensor-height H       the sensor's height above the ground along up (default %g), in\n"
                 "                          [0, 1000]; 0 = estimate it from the cloud\n"
                 "  --viewpoint X,Y,Z       the sensor's position in the cloud's frame (default %g,%g,%g); points\n"
                 "                          within 2.7 m of it (horizontally) or beyond 80 m are never ground\n"
                 "  --threads N             worker threads, 0 = all (default 0); the labels do not depend on N\n"
                 "\n"
                 "Output (files are optional: without them only the counts are printed):\n"
                 "  --out-ground FILE.ply   write the ground points (binary little-endian PLY, float64 x y z)\n"
                 "  --out-rest FILE.ply     write the other points\n"
                 "  --json                  print one JSON object instead of the summary (src/cli/README.md)\n"
                 "  -v, --verbose           print the library's log messages on stderr\n"
                 "  -h, --help              this text\n"
                 "\n"
                 "Exit status: 0 done (also when no point is ground), 2 usage or input error (one \"kissm: ...\"\n"
                 "line on stderr).\n",
                 format_names(), preset_names(), d.up[0], d.up[1], d.up[2], d.sensor_height, d.viewpoint[0],
                 d.viewpoint[1], d.viewpoint[2]);
}

int run_ground(const std::vector<std::string> &args) {
    GroundOptions opt;
    if (!parse_ground_options(args, &opt)) return kExitOk;
    const kissm_config config = ground_config(opt);

    const auto read_start = std::chrono::steady_clock::now();
    const CloudPtr cloud = read_cloud("input", opt.input, opt.format);
    const double read_ms = elapsed_ms(read_start);
    const kissm_points points = points_of(cloud.get(), "input");

    kissm_matcher *raw_matcher = nullptr;
    int32_t status = kissm_create(&config, &raw_matcher);
    if (status != KISSM_OK) throw UsageError(settings_error(status));
    const MatcherPtr matcher(raw_matcher);

    const size_t count = static_cast<size_t>(kissm_cloud_count(cloud.get()));
    std::vector<uint8_t> mask(count, 0);
    const auto ground_start = std::chrono::steady_clock::now();
    status = kissm_ground_mask(matcher.get(), &points, mask.data());
    const double ground_ms = elapsed_ms(ground_start);
    if (status != KISSM_OK) {
        throw UsageError("cannot find the ground of '" + one_line(opt.input) + "': " + library_error(status));
    }
    const Split split = split_points(kissm_cloud_data(cloud.get()), count, mask);

    // Files first, so that a write error is reported before anything is printed.
    write_part(opt.out_ground, split.ground, "ground points", opt.input);
    write_part(opt.out_rest, split.rest, "points other than ground", opt.input);

    const uint64_t ground_points = split.ground.size() / 3, rest_points = split.rest.size() / 3;
    if (opt.json) {
        JsonWriter json;
        json.begin_object();
        json.field("version", kissm_version_string());
        json.field("input", opt.input);
        json.field("preset", opt.ground_up.preset ? preset_name(opt.ground_up.preset) : "none");
        json.field("voxel_size", config.voxel_size);
        json.field("threads", opt.threads);
        json.field_vector("up", config.up, 3);
        json.field_vector("viewpoint", config.viewpoint, 3);
        json.field("sensor_height", config.sensor_height);
        json.field("points", static_cast<uint64_t>(count));
        json.field("ground_points", ground_points);
        json.field("rest_points", rest_points);
        json.field("nonfinite_points", split.nonfinite);
        add_path(json, "out_ground", opt.out_ground);
        add_path(json, "out_rest", opt.out_rest);
        json.field("ground_ms", ground_ms);
        json.field("read_ms", read_ms);
        json.end_object();
        std::fputs(json.str().c_str(), stdout);
    } else {
        std::printf("kissm %s ground\n", kissm_version_string());
        std::printf("  input: %s (%llu points)\n", opt.input.c_str(), static_cast<unsigned long long>(count));
        const int32_t preset = opt.ground_up.preset;
        std::printf("  %s%svoxel %g, threads %d%s, up (%g, %g, %g), sensor at (%g, %g, %g), ", preset ? "preset " : "",
                    preset ? (preset_name(preset) + std::string(", ")).c_str() : "", config.voxel_size, opt.threads,
                    opt.threads == 0 ? " (all)" : "", config.up[0], config.up[1], config.up[2], config.viewpoint[0],
                    config.viewpoint[1], config.viewpoint[2]);
        if (config.sensor_height > 0.0) {
            std::printf("sensor height %g\n", config.sensor_height);
        } else {
            std::printf("sensor height estimated\n");
        }
        const double share = count ? 100.0 * static_cast<double>(ground_points) / static_cast<double>(count) : 0.0;
        std::printf("ground points: %llu (%.1f%%)\n", static_cast<unsigned long long>(ground_points), share);
        std::printf("other points:  %llu\n", static_cast<unsigned long long>(rest_points));
        if (split.nonfinite) {
            std::printf("non-finite (dropped, in neither file): %llu\n",
                        static_cast<unsigned long long>(split.nonfinite));
        }
        if (!opt.out_ground.empty()) std::printf("wrote %s (ground)\n", opt.out_ground.c_str());
        if (!opt.out_rest.empty()) std::printf("wrote %s (the rest)\n", opt.out_rest.c_str());
        std::printf("time (ms): ground %.1f, read %.1f\n", ground_ms, read_ms);
    }
    std::fflush(stdout);
    return kExitOk;
}

} // namespace kissm_cli
