// SPDX-License-Identifier: MIT
// kissm demo [--out DIR] [--threads N] [--seed S] [--voxel V] [--refine MODE] [--json]
//
// Simulates two LiDAR scans of a synthetic street (demo_scene.hpp), registers and refines them through the
// public C API exactly as an application would, compares the coarse and the refined pose with the ground
// truth and writes the clouds and a before/after top view with a detail of the coarse and refined alignment.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <kissm.h>

#include "cli_args.hpp"
#include "commands.hpp"
#include "demo_scene.hpp"
#include "json_writer.hpp"
#include "picture/alignment_figure.hpp"
#include "picture/png_writer.hpp"
#include "picture/top_view.hpp"
#include "ply_writer.hpp"
#include "pose_math.hpp"
#include "report.hpp"

namespace kissm_cli {
using namespace kissm_pose; // src/common/pose_math.hpp
namespace {

constexpr double kMaxRotationErrorDeg = 5.0;
constexpr double kMaxTranslationErrorM = 2.0;

struct DemoCommandOptions {
    std::string out_dir = "kissm_demo_out";
    int32_t threads = 0;
    uint64_t seed = 1;
    double voxel = 0.3;
    int32_t refine_mode = KISSM_REFINE_GICP;
    bool json = false;
    bool verbose = false;
};

double elapsed_ms(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

kissm_points view_of(const std::vector<double> &xyz) {
    kissm_points points{};
    points.data = xyz.data();
    points.count = xyz.size() / 3;
    points.stride_bytes = 0;
    points.scalar_type = KISSM_SCALAR_FLOAT64;
    points.reserved = 0;
    return points;
}

void print_two_matrices(const double A[16], const double B[16]) {
    std::printf("  %-46s  %s\n", "ground truth (maps source into target)", "recovered by kissm");
    for (int r = 0; r < 4; ++r) {
        std::printf("  [ %9.5f %9.5f %9.5f %9.4f ]    [ %9.5f %9.5f %9.5f %9.4f ]\n", A[4 * r], A[4 * r + 1],
                    A[4 * r + 2], A[4 * r + 3], B[4 * r], B[4 * r + 1], B[4 * r + 2], B[4 * r + 3]);
    }
}

std::string join_path(const std::string &dir, const char *name) { return (std::filesystem::path(dir) / name).string(); }

} // namespace

void print_demo_help(std::FILE *out) {
    std::fprintf(out,
                 "usage: kissm demo [--out DIR] [--threads N] [--seed S] [--voxel V] [--refine MODE] [--json]\n"
                 "\n"
                 "Builds a synthetic outdoor scene (an asymmetric street closed at one end, a cross street,\n"
                 "buildings with balconies and columns, walls, hedges, street lights, trees, parked cars, a lorry,\n"
                 "clutter, vehicles and pedestrians that move between the scans, kerbs, rough undulating ground),\n"
                 "simulates two scans by a 64-beam spinning LiDAR (60 m range, 1.5 cm range noise, real\n"
                 "occlusion) from two poses 10-15 m apart with a 120-165 degree relative yaw and a few degrees of\n"
                 "roll and pitch, and registers the scans (each in its own sensor frame) with kissm, refining\n"
                 "the global pose by GICP. Prints the true and recovered poses, the rotation and translation\n"
                 "errors of the coarse (solver) and the refined pose, the counts and the per-stage times, and\n"
                 "writes into DIR:\n"
                 "  source.ply, target.ply   the scans (binary little-endian PLY, float64 x y z, sensor frames)\n"
                 "  aligned_source.ply       the source moved into the target frame by the recovered pose\n"
                 "  demo_topview.png         top view before / after registration (source orange, target blue),\n"
                 "                           and a detail of the coarse and the refined alignment\n"
                 "\n"
                 "  --out DIR     output folder, created if needed (default kissm_demo_out)\n"
                 "  --threads N   worker threads, 0 = all hardware threads (default 0)\n"
                 "  --seed S      scene and sensor-noise seed (default 1); the same seed gives the same scans\n"
                 "  --voxel V     voxel size in metres (default 0.3)\n"
                 "  --refine MODE gicp, point-to-plane or none (default gicp)\n"
                 "  --json        print one JSON object (the register fields plus ground_truth,\n"
                 "                rotation_error_deg, translation_error_m (the final pose's),\n"
                 "                coarse_rotation_error_deg, coarse_translation_error_m, success) instead of\n"
                 "                the report\n"
                 "  -v, --verbose print the library's log messages on stderr\n"
                 "  -h, --help    this text\n"
                 "\n"
                 "`kissm register DIR/source.ply DIR/target.ply --voxel 0.3 --refine gicp` reproduces the demo's\n"
                 "pose exactly.\n"
                 "Exit status: 0 when the final pose is valid and within %g deg / %g m of the truth, 1 otherwise,\n"
                 "2 on usage or output errors.\n",
                 kMaxRotationErrorDeg, kMaxTranslationErrorM);
}

int run_demo(const std::vector<std::string> &args) {
    DemoCommandOptions opt;
    ArgCursor cur("demo", args);
    while (cur.next()) {
        const std::string name = cur.current();
        if (!cur.is_option()) {
            throw UsageError("demo takes no positional arguments, got '" + one_line(name) +
                             "' (see 'kissm demo --help')");
        } else if (cur.is_help()) {
            print_demo_help(stdout);
            return kExitOk;
        } else if (name == "--out") {
            opt.out_dir = cur.value();
        } else if (name == "--threads") {
            opt.threads = parse_int32(name, cur.value(), 0, 4096);
        } else if (name == "--seed") {
            opt.seed = parse_uint64(name, cur.value());
        } else if (name == "--voxel") {
            opt.voxel = parse_positive(name, cur.value());
        } else if (name == "--refine") {
            opt.refine_mode = parse_refine_mode(name, cur.value());
        } else if (!cur.take_flag("--json", &opt.json) && !cur.take_flag("--verbose", &opt.verbose, "-v")) {
            cur.unknown();
        }
    }

    // 1. The scans.
    kissm_sim::DemoOptions scene_options;
    scene_options.seed = opt.seed;
    const auto generate_start = std::chrono::steady_clock::now();
    const kissm_sim::DemoData demo = kissm_sim::generate_demo(scene_options);
    const double generate_ms = elapsed_ms(generate_start);
    const double *gt = demo.gt_target_from_source;

    // 2. Registration through the public API.
    kissm_config config{};
    int32_t status = kissm_config_init(&config, sizeof config);
    if (status != KISSM_OK) throw UsageError("cannot initialise the configuration: " + library_error(status));
    config.voxel_size = opt.voxel;
    config.num_threads = opt.threads;
    config.refine_mode = opt.refine_mode;
    if (opt.verbose) {
        config.log_fn = log_to_stderr;
        config.log_level = KISSM_LOG_INFO;
    }
    kissm_matcher *raw_matcher = nullptr;
    status = kissm_create(&config, &raw_matcher);
    if (status != KISSM_OK) throw UsageError("invalid settings: " + library_error(status));
    const MatcherPtr matcher(raw_matcher);
    const kissm_points source_points = view_of(demo.source.xyz);
    const kissm_points target_points = view_of(demo.target.xyz);
    kissm_result result{};
    result.struct_size = sizeof result;
    status = kissm_register(matcher.get(), &source_points, &target_points, &result);
    if (status != KISSM_OK) throw UsageError("registration failed: " + library_error(status));

    const bool have_pose = matrix_is_finite(result.transform);
    const bool refined = have_pose && refinement_ran(result);
    const double rot_err = have_pose ? rotation_error_deg(result.transform, gt) : std::nan("");
    const double trans_err = have_pose ? translation_error(result.transform, gt) : std::nan("");
    const double coarse_rot_err = have_pose ? rotation_error_deg(result.coarse_transform, gt) : std::nan("");
    const double coarse_trans_err = have_pose ? translation_error(result.coarse_transform, gt) : std::nan("");
    const bool success = result.valid && rot_err < kMaxRotationErrorDeg && trans_err < kMaxTranslationErrorM;

    // 3. Files.
    const auto write_start = std::chrono::steady_clock::now();
    std::error_code ec;
    std::filesystem::create_directories(opt.out_dir, ec);
    if (ec) throw UsageError("cannot create the folder '" + one_line(opt.out_dir) + "': " + ec.message());
    const std::string source_path = join_path(opt.out_dir, "source.ply");
    const std::string target_path = join_path(opt.out_dir, "target.ply");
    const std::string aligned_path = join_path(opt.out_dir, "aligned_source.ply");
    const std::string png_path = join_path(opt.out_dir, "demo_topview.png");
    const std::string tag = std::string("kissm ") + kissm_version_string() + " demo, seed " + std::to_string(opt.seed);
    std::string error;
    const size_t ns = demo.source.xyz.size() / 3, nt = demo.target.xyz.size() / 3;
    if (!write_ply_xyz(source_path, demo.source.xyz.data(), ns, nullptr, {tag + ": source scan, sensor frame"},
                       &error) ||
        !write_ply_xyz(target_path, demo.target.xyz.data(), nt, nullptr, {tag + ": target scan, sensor frame"},
                       &error)) {
        throw UsageError(error);
    }
    if (have_pose) {
        if (!write_ply_xyz(aligned_path, demo.source.xyz.data(), ns, result.transform,
                           {tag + ": source scan moved into the target frame by the recovered pose"}, &error)) {
            throw UsageError(error);
        }
    } else {
        std::error_code ignored;
        std::filesystem::remove(aligned_path, ignored); // never leave a stale file from an earlier run
    }

    AlignmentInput in;
    in.source_xyz = demo.source.xyz.data();
    in.source_count = ns;
    in.target_xyz = demo.target.xyz.data();
    in.target_count = nt;
    in.pose = have_pose ? result.transform : nullptr;
    in.coarse = refined ? result.coarse_transform : nullptr;
    in.voxel = opt.voxel;
    in.before_title = "BEFORE: EACH SCAN IN ITS OWN SENSOR FRAME";
    in.after_title = !have_pose ? "AFTER: NO POSE ESTIMATED"
                     : refined  ? "AFTER: SOURCE MOVED BY THE REFINED POSE"
                                : "AFTER: SOURCE MOVED BY THE POSE FROM KISSM";
    in.coarse_title = "DETAIL: COARSE POSE (SOLVER)";
    in.refined_title = std::string("DETAIL: REFINED POSE (") + refine_mode_name(opt.refine_mode) + ")";
    AlignmentFigure alignment(in);
    TopViewFigure &figure = alignment.picture().figure;
    figure.legend = {{"SOURCE SCAN", kSourceColor}, {"TARGET SCAN", kTargetColor}, {"+ SENSORS", {90, 90, 90}}};
    figure.panels[0].markers = {{0.0, 0.0, kTargetColor}, {0.0, 0.0, kSourceColor}};
    figure.panels[1].markers = {{0.0, 0.0, kTargetColor}};
    if (have_pose) figure.panels[1].markers.push_back({result.transform[3], result.transform[7], kSourceColor});
    char line[200];
    std::snprintf(line, sizeof line, "SEED %llu: TRUE MOTION %.1f M, %.1f DEG.  KISSM: %s, %llu FINAL INLIERS",
                  static_cast<unsigned long long>(opt.seed), translation_norm(gt), rotation_angle_deg(gt),
                  result.valid ? "VALID" : "NOT VALID", static_cast<unsigned long long>(result.num_final_inliers));
    figure.notes.push_back(line);
    if (refined) {
        std::snprintf(line, sizeof line, "COARSE ERROR: ROTATION %.3f DEG, TRANSLATION %.3f M", coarse_rot_err,
                      coarse_trans_err);
        figure.notes.push_back(line);
        std::snprintf(line, sizeof line, "REFINED ERROR: ROTATION %.3f DEG, TRANSLATION %.3f M (OVERLAP %.3f).  %s",
                      rot_err, trans_err, result.overlap, success ? "SUCCESS" : "FAILURE");
        figure.notes.push_back(line);
    } else if (have_pose) {
        std::snprintf(line, sizeof line, "ERROR: ROTATION %.3f DEG, TRANSLATION %.3f M.  %s", rot_err, trans_err,
                      success ? "SUCCESS" : "FAILURE");
        figure.notes.push_back(line);
    }
    const Image image = render_top_view(figure, alignment.picture().view);
    if (!write_png_rgb(png_path, image.width(), image.height(), image.data(), &error)) throw UsageError(error);
    const double write_ms = elapsed_ms(write_start);

    // 4. Report.
    if (opt.json) {
        JsonWriter json;
        json.begin_object();
        json.field("version", kissm_version_string());
        json.field("seed", opt.seed);
        json.field("voxel_size", opt.voxel);
        json.field("threads", opt.threads);
        json.field("success", success);
        json.field("rotation_error_deg", rot_err);
        json.field("translation_error_m", trans_err);
        json.field("coarse_rotation_error_deg", coarse_rot_err);
        json.field("coarse_translation_error_m", coarse_trans_err);
        json.field_matrix("ground_truth", gt, 4, 4);
        add_result_json(json, result, opt.refine_mode);
        json.key("scene");
        json.begin_object();
        json.field("primitives", static_cast<uint64_t>(demo.stats.primitives));
        json.field("source_points", static_cast<uint64_t>(ns));
        json.field("target_points", static_cast<uint64_t>(nt));
        json.field("generate_ms", generate_ms);
        json.end_object();
        json.key("files");
        json.begin_object();
        json.field("source", source_path);
        json.field("target", target_path);
        if (have_pose) json.field("aligned_source", aligned_path);
        json.field("topview", png_path);
        json.end_object();
        json.end_object();
        std::fputs(json.str().c_str(), stdout);
    } else {
        const kissm_sim::DemoSceneStats &s = demo.stats;
        double yaw = 0, pitch = 0, roll = 0;
        yaw_pitch_roll_deg(gt, &yaw, &pitch, &roll);
        std::printf("kissm %s demo: synthetic street scene, seed %llu\n", kissm_version_string(),
                    static_cast<unsigned long long>(opt.seed));
        std::printf(
            "  scene: %zu primitives on rough, undulating ground: %d building blocks (%d facade details),\n"
            "         %d walls and hedges, %d street lights, %d trees, %d parked vehicles, %d clutter objects,\n"
            "         %d vehicles and pedestrians seen in one scan only\n",
            s.primitives, s.buildings, s.details, s.walls, s.poles, s.trees, s.cars, s.clutter, s.movers);
        std::printf(
            "  sensor: %d-beam spinning LiDAR (%+.1f to %+.1f deg), %d columns, %.0f m range, %.1f cm range noise\n",
            scene_options.beams, scene_options.fov_up_deg, scene_options.fov_down_deg, scene_options.azimuth_steps,
            scene_options.max_range, 100.0 * scene_options.range_noise);
        std::printf("  scans: source %zu points, target %zu points, each in its own sensor frame (%.0f ms)\n", ns, nt,
                    generate_ms);
        std::printf("  true motion: %.2f m, %.2f deg (yaw %.1f, pitch %.1f, roll %.1f deg)\n", translation_norm(gt),
                    rotation_angle_deg(gt), yaw, pitch, roll);
        std::printf("\nregistration: voxel %g m, threads %d%s, refinement %s\n", opt.voxel, opt.threads,
                    opt.threads == 0 ? " (all)" : "", refine_mode_name(opt.refine_mode));
        print_two_matrices(gt, result.transform);
        if (refined) {
            std::printf("error against the ground truth:\n");
            std::printf("  coarse pose (solver): rotation error %.4f deg, translation error %.4f m\n", coarse_rot_err,
                        coarse_trans_err);
            const std::string label = std::string("refined pose (") + refine_mode_name(opt.refine_mode) + "):";
            std::printf("  %-21s rotation error %.4f deg, translation error %.4f m\n", label.c_str(), rot_err,
                        trans_err);
        } else if (have_pose) {
            std::printf("rotation error: %.4f deg\ntranslation error: %.4f m\n", rot_err, trans_err);
        } else {
            std::printf("rotation error: -\ntranslation error: - (no pose estimated)\n");
        }
        print_result_summary(stdout, result, ResultKind::Global);
        std::printf("\nwrote (%.0f ms): %s, %s, %s%s%s\n", write_ms, source_path.c_str(), target_path.c_str(),
                    have_pose ? aligned_path.c_str() : "", have_pose ? ", " : "", png_path.c_str());
        std::printf("result: %s (needs a valid pose within %g deg and %g m of the truth)\n",
                    success ? "SUCCESS" : "FAILURE", kMaxRotationErrorDeg, kMaxTranslationErrorM);
    }
    std::fflush(stdout);
    return success ? kExitOk : kExitInvalid;
}

} // namespace kissm_cli
