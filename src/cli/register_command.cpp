// SPDX-License-Identifier: MIT
// kissm register SOURCE TARGET --voxel V [options]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <kissm.h>

#include "cli_args.hpp"
#include "commands.hpp"
#include "json_writer.hpp"
#include "ply_writer.hpp"
#include "png_writer.hpp"
#include "pose_math.hpp"
#include "report.hpp"
#include "top_view.hpp"

namespace kissm_cli {
namespace {

struct RegisterOptions {
    std::vector<std::string> files;
    int32_t source_format = KISSM_FORMAT_AUTO;
    int32_t target_format = KISSM_FORMAT_AUTO;
    bool have_voxel = false;
    double voxel = 0.0;
    int32_t threads = 0;
    int32_t min_inliers = -1;         // -1: library default
    int32_t max_correspondences = -1; // -1: library default
    bool drop_nonfinite = false;
    bool viewpoint_center = false;
    bool json = false;
    bool verbose = false;
    std::string out_transform;
    std::string out_aligned;
    std::string out_topview;
};

double elapsed_ms(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

CloudPtr read_cloud(const char *role, const std::string &path, int32_t format) {
    kissm_cloud *cloud = nullptr;
    const int32_t status = kissm_read_points(path.c_str(), format, &cloud);
    if (status != KISSM_OK) {
        throw UsageError(std::string("cannot read ") + role + " '" + one_line(path) +
                         "': " + library_error(status, path));
    }
    return CloudPtr(cloud);
}

kissm_points points_of(const kissm_cloud *cloud, const char *role) {
    kissm_points points{};
    const int32_t status = kissm_cloud_points(cloud, &points);
    if (status != KISSM_OK)
        throw UsageError(std::string("cannot use the ") + role + " cloud: " + library_error(status));
    return points;
}

} // namespace

void log_to_stderr(void *, int32_t level, const char *message) {
    const char *name = level == KISSM_LOG_ERROR  ? "error"
                       : level == KISSM_LOG_WARN ? "warning"
                       : level == KISSM_LOG_INFO ? "info"
                                                 : "debug";
    std::fprintf(stderr, "kissm: [%s] %s\n", name, message ? message : "");
}

void print_register_help(std::FILE *out) {
    kissm_config defaults{};
    if (kissm_config_init(&defaults, sizeof defaults) != KISSM_OK) {
        defaults.min_inliers = 10;
        defaults.max_correspondences = 5000;
    }
    std::fprintf(out,
                 "usage: kissm register SOURCE TARGET --voxel V [options]\n"
                 "\n"
                 "Globally registers SOURCE against TARGET (no initial guess needed) and prints the rigid\n"
                 "transform that maps SOURCE points into TARGET's frame: p_target = R p_source + t.\n"
                 "\n"
                 "Input files (the format is picked by extension, then by content):\n"
                 "  .ply (ascii/binary)  .pcd (ascii/binary)  .bin (KITTI float32 x y z intensity)\n"
                 "  .npy (float32/float64, N x 3 or more)  .xyz .txt .pts .asc (whitespace-separated x y z)\n"
                 "  --format-src FMT        force SOURCE's format: %s\n"
                 "  --format-tgt FMT        force TARGET's format (bin_xyz = raw float32 x y z triples)\n"
                 "  --format FMT            force both\n"
                 "  --drop-nonfinite        skip NaN/Inf points (default: such points are an error)\n"
                 "\n"
                 "Registration:\n"
                 "  --voxel V               voxel size in the clouds' unit, > 0 (required); every radius and\n"
                 "                          noise bound scales with it. Try 0.3-0.5 for outdoor LiDAR in metres,\n"
                 "                          0.05 for indoor RGB-D fragments\n"
                 "  --threads N             worker threads, 0 = all hardware threads (default 0); the result\n"
                 "                          does not depend on N\n"
                 "  --min-inliers N         final inliers needed for a valid pose (default %d)\n"
                 "  --max-correspondences N cap on the matches kept, best first (default %d)\n"
                 "  --viewpoint-center      orient normals toward each cloud's centre (maps, merged clouds)\n"
                 "                          instead of the sensor at the frame origin (single scans)\n"
                 "\n"
                 "Output:\n"
                 "  --json                  print one JSON object instead of the summary: valid, reason,\n"
                 "                          transform (4x4 row-major), final_inliers, counts, inlier_ratio,\n"
                 "                          residual_rms, time_ms; numbers read back to the exact doubles,\n"
                 "                          NaN is written as null\n"
                 "  --out-transform FILE    write the 4x4 transform as 4 lines of 4 numbers (%%.17g); NaN when\n"
                 "                          no pose was estimated\n"
                 "  --out-aligned FILE.ply  write SOURCE moved into TARGET's frame (binary little-endian PLY,\n"
                 "                          float64 x y z); skipped when no pose was estimated\n"
                 "  --out-topview FILE.png  top-down picture: before (both clouds in their own frames) and\n"
                 "                          after (SOURCE aligned); source orange, target blue\n"
                 "  -v, --verbose           print the library's log messages on stderr\n"
                 "  -h, --help              this text\n"
                 "\n"
                 "Exit status: 0 valid pose, 1 registration ran but the pose is not valid (see the reason),\n"
                 "2 usage or input error (one \"kissm: ...\" line on stderr).\n",
                 format_names(), defaults.min_inliers, defaults.max_correspondences);
}

int run_register(const std::vector<std::string> &args) {
    RegisterOptions opt;
    ArgCursor cur("register", args);
    while (cur.next()) {
        const std::string name = cur.current();
        if (!cur.is_option()) {
            opt.files.push_back(name);
        } else if (name == "-h" || name == "--help") {
            print_register_help(stdout);
            return kExitOk;
        } else if (name == "--voxel") {
            opt.voxel = parse_positive(name, cur.value());
            opt.have_voxel = true;
        } else if (name == "--threads") {
            opt.threads = parse_int32(name, cur.value(), 0, 4096);
        } else if (name == "--min-inliers") {
            opt.min_inliers = parse_int32(name, cur.value(), 3, 1 << 30);
        } else if (name == "--max-correspondences") {
            opt.max_correspondences = parse_int32(name, cur.value(), 3, 1 << 30);
        } else if (name == "--format-src") {
            opt.source_format = parse_format(name, cur.value());
        } else if (name == "--format-tgt") {
            opt.target_format = parse_format(name, cur.value());
        } else if (name == "--format") {
            opt.source_format = opt.target_format = parse_format(name, cur.value());
        } else if (name == "--drop-nonfinite") {
            cur.expect_no_value();
            opt.drop_nonfinite = true;
        } else if (name == "--viewpoint-center") {
            cur.expect_no_value();
            opt.viewpoint_center = true;
        } else if (name == "--json") {
            cur.expect_no_value();
            opt.json = true;
        } else if (name == "-v" || name == "--verbose") {
            cur.expect_no_value();
            opt.verbose = true;
        } else if (name == "--out-transform") {
            opt.out_transform = cur.value();
        } else if (name == "--out-aligned") {
            opt.out_aligned = cur.value();
        } else if (name == "--out-topview") {
            opt.out_topview = cur.value();
        } else {
            cur.unknown();
        }
    }
    if (opt.files.size() != 2) {
        throw UsageError("register expects 2 files (SOURCE TARGET), got " + std::to_string(opt.files.size()) +
                         " (see 'kissm register --help')");
    }
    if (!opt.have_voxel) {
        throw UsageError("register needs --voxel V, the voxel size in the clouds' unit (e.g. --voxel 0.3 for "
                         "outdoor LiDAR in metres)");
    }
    kissm_config config{};
    int32_t status = kissm_config_init(&config, sizeof config);
    if (status != KISSM_OK) throw UsageError("cannot initialise the configuration: " + library_error(status));
    config.voxel_size = opt.voxel;
    config.num_threads = opt.threads;
    if (opt.min_inliers >= 0) config.min_inliers = opt.min_inliers;
    if (opt.max_correspondences >= 0) config.max_correspondences = opt.max_correspondences;
    if (opt.drop_nonfinite) config.nonfinite_policy = KISSM_NONFINITE_DROP;
    if (opt.viewpoint_center) config.viewpoint_mode = KISSM_VIEWPOINT_CLOUD_CENTER;
    if (opt.verbose) {
        config.log_fn = log_to_stderr;
        config.log_level = KISSM_LOG_INFO;
    }
    status = kissm_config_validate(&config);
    if (status != KISSM_OK) throw UsageError("invalid settings: " + library_error(status));

    const auto read_start = std::chrono::steady_clock::now();
    const CloudPtr source = read_cloud("source", opt.files[0], opt.source_format);
    const CloudPtr target = read_cloud("target", opt.files[1], opt.target_format);
    const double read_ms = elapsed_ms(read_start);
    const kissm_points source_points = points_of(source.get(), "source");
    const kissm_points target_points = points_of(target.get(), "target");

    kissm_matcher *raw_matcher = nullptr;
    status = kissm_create(&config, &raw_matcher);
    if (status != KISSM_OK) throw UsageError("invalid settings: " + library_error(status));
    const MatcherPtr matcher(raw_matcher);

    kissm_result result{};
    result.struct_size = sizeof result;
    status = kissm_register(matcher.get(), &source_points, &target_points, &result);
    if (status != KISSM_OK) {
        throw UsageError("cannot register '" + one_line(opt.files[0]) + "' against '" + one_line(opt.files[1]) +
                         "': " + library_error(status));
    }
    const bool have_pose = matrix_is_finite(result.transform);

    // Files first, so that a write error is reported before anything is printed.
    std::string error;
    if (!opt.out_transform.empty() && !write_transform_file(opt.out_transform, result.transform, &error)) {
        throw UsageError(error);
    }
    const double *source_xyz = kissm_cloud_data(source.get());
    const size_t source_count = static_cast<size_t>(kissm_cloud_count(source.get()));
    const double *target_xyz = kissm_cloud_data(target.get());
    const size_t target_count = static_cast<size_t>(kissm_cloud_count(target.get()));
    if (!opt.out_aligned.empty()) {
        if (have_pose) {
            const std::vector<std::string> comments = {std::string("kissm ") + kissm_version_string() +
                                                       ": source moved into the target frame"};
            if (!write_ply_xyz(opt.out_aligned, source_xyz, source_count, result.transform, comments, &error)) {
                throw UsageError(error);
            }
        } else {
            std::fprintf(stderr, "kissm: no pose was estimated; '%s' not written\n", opt.out_aligned.c_str());
        }
    }
    if (!opt.out_topview.empty()) {
        const Rgb orange{255, 127, 14}, blue{31, 119, 180};
        const CloudLayer target_layer{target_xyz, target_count, nullptr, blue};
        const CloudLayer source_layer{source_xyz, source_count, nullptr, orange};
        const CloudLayer aligned_layer{source_xyz, source_count, have_pose ? result.transform : nullptr, orange};
        TopViewFigure figure;
        figure.panels.push_back({"BEFORE: EACH CLOUD IN ITS OWN FRAME", {target_layer, source_layer}, {}});
        TopViewPanel after{
            have_pose ? "AFTER: SOURCE ALIGNED BY KISSM" : "AFTER: NO POSE ESTIMATED", {target_layer}, {}};
        if (have_pose) after.layers.push_back(aligned_layer);
        figure.panels.push_back(after);
        figure.legend = {{"SOURCE", orange}, {"TARGET", blue}};
        char note[160];
        std::snprintf(note, sizeof note, "VALID: %s   FINAL INLIERS %llu   VOXEL %g", result.valid ? "YES" : "NO",
                      static_cast<unsigned long long>(result.num_final_inliers), opt.voxel);
        figure.notes.push_back(note);
        const Image image = render_top_view(figure, fit_view(after.layers));
        if (!write_png_rgb(opt.out_topview, image.width(), image.height(), image.data(), &error)) {
            throw UsageError(error);
        }
    }

    if (opt.json) {
        JsonWriter json;
        json.begin_object();
        json.field("version", kissm_version_string());
        json.field("source", opt.files[0]);
        json.field("target", opt.files[1]);
        json.field("voxel_size", opt.voxel);
        json.field("threads", opt.threads);
        add_result_json(json, result);
        json.field("read_ms", read_ms);
        json.end_object();
        std::fputs(json.str().c_str(), stdout);
    } else {
        std::printf("kissm %s register\n", kissm_version_string());
        std::printf("  source: %s (%llu points)\n", opt.files[0].c_str(),
                    static_cast<unsigned long long>(source_count));
        std::printf("  target: %s (%llu points)\n", opt.files[1].c_str(),
                    static_cast<unsigned long long>(target_count));
        std::printf("  voxel %g, threads %d%s, files read in %.1f ms\n", opt.voxel, opt.threads,
                    opt.threads == 0 ? " (all)" : "", read_ms);
        std::printf("transform (maps source into target, row-major):\n");
        print_matrix(stdout, result.transform, "  ");
        if (have_pose) {
            std::printf("  rotation %.3f deg, translation %.3f\n", rotation_angle_deg(result.transform),
                        translation_norm(result.transform));
        }
        print_result_summary(stdout, result);
    }
    std::fflush(stdout);
    return result.valid ? kExitOk : kExitInvalid;
}

} // namespace kissm_cli
