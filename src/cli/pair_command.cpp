// SPDX-License-Identifier: MIT
#include "pair_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "commands.hpp"
#include "json_writer.hpp"
#include "las_writer.hpp"
#include "picture/alignment_figure.hpp"
#include "picture/png_writer.hpp"
#include "picture/top_view.hpp"
#include "ply_writer.hpp"
#include "pose_math.hpp"
#include "report.hpp"
#include "transform_file.hpp"

namespace kissm_cli {
using namespace kissm_pose; // src/common/pose_math.hpp
namespace {

const char *command_name(PairCommand command) { return command == PairCommand::Register ? "register" : "refine"; }

// The option that sets each config field the library may reject, so that its message (which names the
// field) can name the option too.
struct FieldOption {
    const char *field;
    const char *option;
};
constexpr FieldOption kFieldOptions[] = {
    {"config.voxel_size ", "--voxel"},
    {"config.num_threads ", "--threads"},
    {"config.min_inliers ", "--min-inliers"},
    {"config.max_correspondences ", "--max-correspondences"},
    {"config.refine_max_iterations ", "--refine-iterations"},
    {"config.refine_max_distance_gain ", "--refine-distance"},
    {"config.min_overlap ", "--min-overlap"},
    {"config.max_rotation_uncertainty ", "--max-rotation-uncertainty"},
    {"config.max_ambiguity ", "--max-ambiguity"},
    {"config.min_inlier_coverage ", "--min-inlier-coverage"},
    {"config.refine_min_inliers ", "--refine-min-inliers"},
    {"config.min_refine_condition ", "--min-refine-condition"},
    {"config.max_refine_rmse_gain ", "--max-refine-rmse"},
    {"config.refine_normal_radius_gain ", "--refine-normal-radius"},
    {"config.suppression ", "--suppression"},
    {"config.rotation_dof ", "--rotation-dof"},
    {"config.up", "--up"}, // "config.up is (0, 0, 0); ..." and "config.up[1] is not finite"
    {"config.sensor_height ", "--sensor-height"},
    {"config.viewpoint[", "--viewpoint"},
};

void write_outputs(PairCommand command, const PairOptions &opt, const kissm_cloud *source, const kissm_cloud *target,
                   const kissm_result &result) {
    const bool have_pose = matrix_is_finite(result.transform);
    std::string error;
    if (!opt.out_transform.empty() && !write_transform_file(opt.out_transform, result.transform, &error)) {
        throw UsageError(error);
    }
    const double *source_xyz = kissm_cloud_data(source);
    const size_t source_count = static_cast<size_t>(kissm_cloud_count(source));
    if (!opt.out_aligned.empty()) {
        if (have_pose) {
            if (is_las_path(opt.out_aligned)) {
                // The target's scale and offset when it is LAS/LAZ: the aligned points land on its grid.
                LasFrame frame;
                if (!read_las_frame(opt.files[1], &frame))
                    frame = las_frame_for(source_xyz, source_count, result.transform);
                size_t written = 0;
                if (!write_las_xyz(opt.out_aligned, source_xyz, source_count, result.transform, frame, &written,
                                   &error)) {
                    throw UsageError(error);
                }
                if (written < source_count) {
                    std::fprintf(stderr, "kissm: %zu non-finite points left out of '%s' (LAS cannot hold them)\n",
                                 source_count - written, opt.out_aligned.c_str());
                }
            } else {
                const std::vector<std::string> comments = {std::string("kissm ") + kissm_version_string() +
                                                           ": source moved into the target frame"};
                if (!write_ply_xyz(opt.out_aligned, source_xyz, source_count, result.transform, comments, &error)) {
                    throw UsageError(error);
                }
            }
        } else {
            std::fprintf(stderr, "kissm: no pose was estimated; '%s' not written\n", opt.out_aligned.c_str());
        }
    }
    if (opt.out_topview.empty()) return;
    const bool refined = refinement_ran(result) && matrix_is_finite(result.coarse_transform);
    const bool from_initial = command == PairCommand::Refine;
    AlignmentInput in;
    in.source_xyz = source_xyz;
    in.source_count = source_count;
    in.target_xyz = kissm_cloud_data(target);
    in.target_count = static_cast<size_t>(kissm_cloud_count(target));
    in.before = from_initial ? result.coarse_transform : nullptr;
    in.pose = have_pose ? result.transform : nullptr;
    in.coarse = (have_pose && refined) ? result.coarse_transform : nullptr;
    in.voxel = opt.voxel;
    in.before_title = from_initial ? "BEFORE: SOURCE MOVED BY THE INITIAL POSE" : "BEFORE: EACH CLOUD IN ITS OWN FRAME";
    in.after_title = !have_pose ? "AFTER: NO POSE ESTIMATED"
                     : refined  ? "AFTER: SOURCE ALIGNED BY KISSM (REFINED)"
                                : "AFTER: SOURCE ALIGNED BY KISSM";
    in.coarse_title = from_initial ? "DETAIL: INITIAL POSE" : "DETAIL: COARSE POSE (SOLVER)";
    in.refined_title = std::string("DETAIL: REFINED POSE (") + refine_mode_name(opt.refine_mode) + ")";
    AlignmentFigure figure(in);
    AlignmentPicture &pic = figure.picture();
    char note[200];
    if (from_initial) {
        std::snprintf(note, sizeof note, "VALID: %s   VOXEL %g", result.valid ? "YES" : "NO", opt.voxel);
    } else {
        std::snprintf(note, sizeof note, "VALID: %s   FINAL INLIERS %llu   VOXEL %g", result.valid ? "YES" : "NO",
                      static_cast<unsigned long long>(result.num_final_inliers), opt.voxel);
    }
    pic.figure.notes.push_back(note);
    if (refined) {
        std::snprintf(note, sizeof note, "REFINEMENT MOVED THE %s POSE BY %.3f DEG, %.3g. OVERLAP %.3f",
                      from_initial ? "INITIAL" : "COARSE",
                      rotation_error_deg(result.coarse_transform, result.transform),
                      translation_error(result.coarse_transform, result.transform), result.overlap);
        pic.figure.notes.push_back(note);
    }
    const Image image = render_top_view(pic.figure, pic.view);
    if (!write_png_rgb(opt.out_topview, image.width(), image.height(), image.data(), &error)) throw UsageError(error);
}

void print_json(PairCommand command, const PairOptions &opt, const kissm_result &result, const double *initial,
                double read_ms) {
    JsonWriter json;
    json.begin_object();
    json.field("version", kissm_version_string());
    json.field("source", opt.files[0]);
    json.field("target", opt.files[1]);
    json.field("voxel_size", opt.voxel);
    json.field("threads", opt.threads);
    add_result_json(json, result, opt.refine_mode, command == PairCommand::Refine ? initial : nullptr);
    json.field("read_ms", read_ms);
    json.end_object();
    std::fputs(json.str().c_str(), stdout);
}

// The largest side of a cloud's bounding box over its finite points (0 when it has none).
double largest_side(const kissm_points &points) {
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    const auto *xyz = static_cast<const double *>(points.data);
    for (uint64_t i = 0; i < points.count; ++i) {
        const double *p = xyz + 3 * i;
        if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) continue;
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    double side = 0.0;
    for (int k = 0; k < 3; ++k) side = std::max(side, hi[k] - lo[k]);
    return side;
}

// "Too few voxels" says what the voxel should be (issue 36): the clouds' size, and the voxel --voxel auto would
// choose for them. On stderr, one line, so the JSON on stdout stays as it is.
void print_voxel_hint(const kissm_points &source, const kissm_points &target, double voxel) {
    const kissm_points both[2] = {source, target};
    double suggested = 0.0;
    if (kissm_suggest_voxel_size(both, 2, &suggested) != KISSM_OK) return; // nothing sensible to say
    std::fprintf(stderr,
                 "kissm: hint: the clouds span %.4g and %.4g (their bounding boxes' largest sides), too few voxels "
                 "of %g to describe; --voxel auto would use %.4g\n",
                 largest_side(source), largest_side(target), voxel, suggested);
}

void print_human(PairCommand command, const PairOptions &opt, const kissm_config &config, const kissm_result &result,
                 double read_ms) {
    std::printf("kissm %s %s\n", kissm_version_string(), command_name(command));
    std::printf("  source: %s (%llu points)\n", opt.files[0].c_str(),
                static_cast<unsigned long long>(result.num_source_points));
    std::printf("  target: %s (%llu points)\n", opt.files[1].c_str(),
                static_cast<unsigned long long>(result.num_target_points));
    std::printf("  voxel %g%s, threads %d%s, refinement %s, files read in %.1f ms\n", opt.voxel,
                opt.voxel_auto ? " (auto)" : "", opt.threads, opt.threads == 0 ? " (all)" : "",
                refine_mode_name(opt.refine_mode), read_ms);
    if (command == PairCommand::Register &&
        (opt.ground_up.preset != 0 || config.suppression != KISSM_SUPPRESS_NONE || config.rotation_dof != 3)) {
        const int32_t preset = opt.ground_up.preset;
        std::printf("  %s%ssuppression %s, rotation dof %d, up (%g, %g, %g)\n", preset ? "preset " : "",
                    preset ? (preset_name(preset) + std::string(", ")).c_str() : "",
                    config.suppression == KISSM_SUPPRESS_GROUND ? "ground" : "none", config.rotation_dof, config.up[0],
                    config.up[1], config.up[2]);
    }
    if (command == PairCommand::Refine) {
        std::printf("initial transform (from %s):\n", opt.initial.c_str());
        print_matrix(stdout, result.coarse_transform, "  ");
    }
    const bool refined = refinement_ran(result);
    std::printf("%stransform (maps source into target, row-major):\n", refined ? "refined " : "");
    print_matrix(stdout, result.transform, "  ");
    if (matrix_is_finite(result.transform)) {
        std::printf("  rotation %.3f deg, translation %.3f\n", rotation_angle_deg(result.transform),
                    translation_norm(result.transform));
    }
    if (command == PairCommand::Register && refined) {
        std::printf("coarse transform (the solver's, before refinement):\n");
        print_matrix(stdout, result.coarse_transform, "  ");
    }
    print_result_summary(stdout, result, command == PairCommand::Register ? ResultKind::Global : ResultKind::Refine);
}

} // namespace

double elapsed_ms(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

bool take_ground_up_option(ArgCursor &cur, bool solver, GroundUpOptions *opt) {
    if (!cur.is_option()) return false;
    const std::string &name = cur.current();
    if (name == "--preset") {
        opt->preset = parse_preset(name, cur.value());
    } else if (name == "--up") {
        parse_vec3(name, cur.value(), opt->up);
        opt->have_up = true;
    } else if (name == "--sensor-height") {
        opt->sensor_height = parse_double(name, cur.value());
        opt->have_sensor_height = true;
    } else if (solver && name == "--suppression") {
        opt->suppression = parse_suppression(name, cur.value());
    } else if (solver && name == "--rotation-dof") {
        constexpr int32_t kAnyInt = std::numeric_limits<int32_t>::max(); // the library checks the range
        opt->rotation_dof = parse_int32(name, cur.value(), -kAnyInt - 1, kAnyInt);
        opt->have_rotation_dof = true;
    } else {
        return false;
    }
    return true;
}

void apply_ground_up(const GroundUpOptions &opt, kissm_config *config) {
    if (opt.suppression >= 0) config->suppression = opt.suppression;
    if (opt.have_rotation_dof) config->rotation_dof = opt.rotation_dof;
    if (opt.have_up) {
        for (int i = 0; i < 3; ++i) config->up[i] = opt.up[i];
    }
    if (opt.have_sensor_height) config->sensor_height = opt.sensor_height;
}

kissm_config validated_config(kissm_config config, bool drop_nonfinite, bool verbose) {
    if (drop_nonfinite) config.nonfinite_policy = KISSM_NONFINITE_DROP;
    if (verbose) {
        config.log_fn = log_to_stderr;
        config.log_level = KISSM_LOG_INFO;
    }
    const int32_t status = kissm_config_validate(&config);
    if (status != KISSM_OK) throw UsageError(settings_error(status));
    return config;
}

CloudPtr read_cloud(const char *role, const std::string &path, int32_t format) {
    kissm_cloud *cloud = nullptr;
    const int32_t status = kissm_read_points(path.c_str(), format, &cloud);
    if (status != KISSM_OK) {
        throw UsageError(std::string("cannot read ") + role + " '" + one_line(path) +
                         "': " + library_error(status, path));
    }
    // A LAS/LAZ file's withheld points are not registered; say how many, since the file's own count differs.
    const uint64_t withheld = kissm_cloud_num_withheld(cloud);
    if (withheld > 0) {
        std::fprintf(stderr, "kissm: %s '%s': %llu points flagged withheld left out\n", role, one_line(path).c_str(),
                     static_cast<unsigned long long>(withheld));
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

std::string settings_error(int32_t status) {
    const std::string message = library_error(status);
    for (const FieldOption &f : kFieldOptions) {
        if (message.find(f.field) != std::string::npos) return std::string("invalid ") + f.option + ": " + message;
    }
    return "invalid settings: " + message;
}

void require_voxel(const char *command, const PairOptions &opt) {
    if (!opt.have_voxel && opt.ground_up.preset == 0) { // every preset gives a voxel size
        throw UsageError(std::string(command) +
                         " needs --voxel V, the voxel size in the clouds' unit (e.g. --voxel 0.3 for outdoor LiDAR "
                         "in metres), --voxel auto (suggested from the clouds), or a --preset that gives one");
    }
}

int run_pair_command(PairCommand command, const std::vector<std::string> &args) {
    PairOptions opt;
    if (!parse_pair_options(command, args, &opt)) return kExitOk;
    return run_pair(command, opt);
}

bool take_pair_option(PairCommand command, ArgCursor &cur, bool with_outputs, PairOptions *out) {
    if (!cur.is_option()) return false;
    const bool is_register = command == PairCommand::Register;
    PairOptions &opt = *out;
    constexpr int32_t kAnyInt = std::numeric_limits<int32_t>::max(); // the library checks the range
    const std::string name = cur.current();
    if (name == "--voxel") {
        const std::string value = cur.value();
        opt.voxel_auto = value == "auto";
        opt.voxel = opt.voxel_auto ? 0.0 : parse_positive(name, value); // 0: the library suggests one per pair
        opt.have_voxel = true;
    } else if (name == "--threads") {
        opt.threads = parse_int32(name, cur.value(), 0, 4096);
        opt.have_threads = true;
    } else if (is_register && name == "--min-inliers") {
        opt.min_inliers = parse_int32(name, cur.value(), 3, 1 << 30);
    } else if (is_register && name == "--max-correspondences") {
        opt.max_correspondences = parse_int32(name, cur.value(), 0, 1 << 30); // 0: automatic
    } else if (is_register && name == "--max-rotation-uncertainty") {
        opt.max_rotation_uncertainty = parse_double(name, cur.value());
        opt.have_max_rotation_uncertainty = true;
    } else if (is_register && name == "--max-ambiguity") {
        opt.max_ambiguity = parse_double(name, cur.value());
        opt.have_max_ambiguity = true;
    } else if (is_register && name == "--min-inlier-coverage") {
        opt.min_inlier_coverage = parse_double(name, cur.value());
        opt.have_min_inlier_coverage = true;
    } else if (is_register && name == "--refine-min-inliers") {
        opt.refine_min_inliers = parse_int32(name, cur.value(), -kAnyInt - 1, kAnyInt);
        opt.have_refine_min_inliers = true;
    } else if (is_register && take_ground_up_option(cur, true, &opt.ground_up)) {
        // --preset, --suppression, --rotation-dof, --up, --sensor-height
    } else if (!is_register && name == "--initial") {
        opt.initial = cur.value();
    } else if (name == "--viewpoint") {
        opt.viewpoint_mode = parse_viewpoint_mode(name, cur.value());
    } else if (name == "--refine") {
        opt.refine_mode = parse_refine_mode(name, cur.value());
        if (!is_register && opt.refine_mode == KISSM_REFINE_NONE) {
            throw UsageError("refine: --refine none leaves nothing to do (expected gicp or point-to-plane)");
        }
    } else if (name == "--refine-iterations") {
        opt.refine_iterations = parse_int32(name, cur.value(), -kAnyInt - 1, kAnyInt);
        opt.have_refine_iterations = true;
    } else if (name == "--refine-distance") {
        opt.refine_distance = parse_double(name, cur.value());
        opt.have_refine_distance = true;
    } else if (name == "--min-overlap") {
        opt.min_overlap = parse_double(name, cur.value());
        opt.have_min_overlap = true;
    } else if (name == "--min-refine-condition") {
        opt.min_refine_condition = parse_double(name, cur.value());
        opt.have_min_refine_condition = true;
    } else if (name == "--max-refine-rmse") {
        opt.max_refine_rmse_gain = parse_double(name, cur.value());
        opt.have_max_refine_rmse = true;
    } else if (name == "--refine-normal-radius") {
        opt.refine_normal_radius_gain = parse_double(name, cur.value());
        opt.have_refine_normal_radius = true;
    } else if (name == "--format-src") {
        opt.source_format = parse_format(name, cur.value());
    } else if (name == "--format-tgt") {
        opt.target_format = parse_format(name, cur.value());
    } else if (name == "--format") {
        opt.source_format = opt.target_format = parse_format(name, cur.value());
    } else if (with_outputs && name == "--out-transform") {
        opt.out_transform = cur.value();
    } else if (with_outputs && name == "--out-aligned") {
        opt.out_aligned = cur.value();
        if (is_laz_path(opt.out_aligned))
            throw UsageError("--out-aligned: kissm does not write LAZ ('" + opt.out_aligned +
                             "'); name a .las or .ply file");
    } else if (with_outputs && name == "--out-topview") {
        opt.out_topview = cur.value();
    } else if (!cur.take_flag("--drop-nonfinite", &opt.drop_nonfinite) &&
               !cur.take_flag("--viewpoint-center", &opt.viewpoint_center) &&
               !cur.take_flag("--allow-degenerate", &opt.allow_degenerate) &&
               !(with_outputs && cur.take_flag("--json", &opt.json)) &&
               !cur.take_flag("--verbose", &opt.verbose, "-v")) {
        return false;
    }
    return true;
}

bool parse_pair_options(PairCommand command, const std::vector<std::string> &args, PairOptions *out) {
    const bool is_register = command == PairCommand::Register;
    PairOptions opt;
    opt.refine_mode = is_register ? KISSM_REFINE_NONE : KISSM_REFINE_GICP;
    ArgCursor cur(command_name(command), args);
    while (cur.next()) {
        const std::string name = cur.current();
        if (!cur.is_option()) {
            opt.files.push_back(name);
        } else if (cur.is_help()) {
            if (is_register) {
                print_register_help(stdout);
            } else {
                print_refine_help(stdout);
            }
            return false;
        } else if (!take_pair_option(command, cur, true, &opt)) {
            cur.unknown();
        }
    }
    const std::string see = std::string(" (see 'kissm ") + command_name(command) + " --help')";
    if (opt.files.size() != 2) {
        throw UsageError(std::string(command_name(command)) + " expects 2 files (SOURCE TARGET), got " +
                         std::to_string(opt.files.size()) + see);
    }
    require_voxel(command_name(command), opt);
    if (!is_register && opt.initial.empty()) {
        throw UsageError("refine needs --initial FILE, the starting transform (4 rows of 4 numbers, as "
                         "--out-transform writes)" +
                         see);
    }
    *out = opt;
    return true;
}

kissm_config config_defaults() {
    kissm_config config{};
    const int32_t status = kissm_config_init(&config, sizeof config);
    if (status != KISSM_OK) throw UsageError("cannot initialise the configuration: " + library_error(status));
    return config;
}

kissm_config config_with_preset(int32_t preset) {
    kissm_config config = config_defaults();
    if (preset == 0) return config;
    const int32_t status = kissm_config_preset(&config, preset);
    if (status != KISSM_OK) throw UsageError("invalid --preset: " + library_error(status));
    return config;
}

kissm_config pair_config(PairCommand command, const PairOptions &opt) {
    // The preset first, so that every option given explicitly overrides it, whatever their order.
    kissm_config config = config_with_preset(command == PairCommand::Register ? opt.ground_up.preset : 0);
    if (opt.have_voxel) config.voxel_size = opt.voxel;
    config.num_threads = opt.threads;
    if (command == PairCommand::Register) {
        apply_ground_up(opt.ground_up, &config);
        if (opt.min_inliers >= 0) config.min_inliers = opt.min_inliers;
        if (opt.max_correspondences >= 0) config.max_correspondences = opt.max_correspondences;
        if (opt.have_max_rotation_uncertainty) config.max_rotation_uncertainty = opt.max_rotation_uncertainty;
        if (opt.have_max_ambiguity) config.max_ambiguity = opt.max_ambiguity;
        if (opt.have_min_inlier_coverage) config.min_inlier_coverage = opt.min_inlier_coverage;
        if (opt.have_refine_min_inliers) config.refine_min_inliers = opt.refine_min_inliers;
    }
    config.refine_mode = opt.refine_mode;
    if (opt.have_refine_iterations) config.refine_max_iterations = opt.refine_iterations;
    if (opt.have_refine_distance) config.refine_max_distance_gain = opt.refine_distance;
    if (opt.have_min_overlap) config.min_overlap = opt.min_overlap;
    if (opt.have_min_refine_condition) config.min_refine_condition = opt.min_refine_condition;
    if (opt.have_max_refine_rmse) config.max_refine_rmse_gain = opt.max_refine_rmse_gain;
    if (opt.allow_degenerate) config.allow_degenerate = 1;
    if (opt.have_refine_normal_radius) config.refine_normal_radius_gain = opt.refine_normal_radius_gain;
    if (opt.viewpoint_mode >= 0) config.viewpoint_mode = opt.viewpoint_mode;
    if (opt.viewpoint_center) config.viewpoint_mode = KISSM_VIEWPOINT_CLOUD_CENTER;
    return validated_config(config, opt.drop_nonfinite, opt.verbose);
}

int run_pair(PairCommand command, const PairOptions &given) {
    const kissm_config config = pair_config(command, given);
    PairOptions opt = given;
    opt.voxel = config.voxel_size; // --voxel, or the preset's
    double initial[16] = {};
    if (command == PairCommand::Refine) {
        std::string error;
        if (!read_transform_file(opt.initial, initial, &error)) throw UsageError("--initial: " + error);
    }

    const auto read_start = std::chrono::steady_clock::now();
    const CloudPtr source = read_cloud("source", opt.files[0], opt.source_format);
    const CloudPtr target = read_cloud("target", opt.files[1], opt.target_format);
    const double read_ms = elapsed_ms(read_start);
    const kissm_points source_points = points_of(source.get(), "source");
    const kissm_points target_points = points_of(target.get(), "target");

    kissm_matcher *raw_matcher = nullptr;
    int32_t status = kissm_create(&config, &raw_matcher);
    if (status != KISSM_OK) throw UsageError(settings_error(status));
    const MatcherPtr matcher(raw_matcher);

    kissm_result result{};
    result.struct_size = sizeof result;
    const std::string pair = "'" + one_line(opt.files[0]) + "' against '" + one_line(opt.files[1]) + "'";
    if (command == PairCommand::Register) {
        status = kissm_register(matcher.get(), &source_points, &target_points, &result);
        if (status != KISSM_OK) throw UsageError("cannot register " + pair + ": " + library_error(status));
    } else {
        status = kissm_refine(matcher.get(), &source_points, &target_points, initial, &result);
        const std::string message = status == KISSM_OK ? std::string() : library_error(status);
        if (status == KISSM_ERR_INVALID_ARGUMENT && message.find("initial_transform") != std::string::npos) {
            throw UsageError("--initial: '" + one_line(opt.initial) + "' is not a rigid transform: " + message);
        }
        if (status != KISSM_OK) throw UsageError("cannot refine " + pair + ": " + message);
    }

    if (opt.voxel_auto) opt.voxel = result.voxel_size_used; // what the pictures and reports show
    // Files first, so that a write error is reported before anything is printed.
    write_outputs(command, opt, source.get(), target.get(), result);
    if (opt.json) {
        print_json(command, opt, result, initial, read_ms);
    } else {
        print_human(command, opt, config, result, read_ms);
    }
    std::fflush(stdout);
    if (result.reason == KISSM_REASON_TOO_FEW_VOXELS) print_voxel_hint(source_points, target_points, opt.voxel);
    return result.valid ? kExitOk : kExitInvalid;
}

namespace {

void print_pair_input_help(std::FILE *out) {
    std::fprintf(out,
                 "Input files (the format is picked by extension, then by content):\n"
                 "  .ply (ascii/binary)  .pcd (ascii/binary)  .bin (KITTI float32 x y z intensity)\n"
                 "  .npy (float32/float64, N x 3 or more)  .xyz .txt .pts .asc (whitespace-separated x y z)\n"
                 "  --format-src FMT        force SOURCE's format: %s\n"
                 "  --format-tgt FMT        force TARGET's format (bin_xyz = raw float32 x y z triples)\n"
                 "  --format FMT            force both\n"
                 "  --drop-nonfinite        skip NaN/Inf points (default: such points are an error)\n"
                 "\n",
                 format_names());
}

void print_refinement_help(std::FILE *out, PairCommand command, const kissm_config &d) {
    if (command == PairCommand::Register) {
        std::fprintf(out, "Refinement (after the global solver, on the voxelised clouds):\n"
                          "  --refine MODE           gicp, point-to-plane or none (default none); the JSON's\n"
                          "                          transform is then the refined pose, coarse_transform the\n"
                          "                          solver's\n");
    } else {
        std::fprintf(out, "Refinement:\n"
                          "  --refine MODE           gicp or point-to-plane (default gicp)\n");
    }
    std::fprintf(out,
                 "  --refine-iterations N   iteration cap, 1..1000 (default %d)\n"
                 "  --refine-distance GAIN  correspondence distance = GAIN * voxel, in (0, 100] (default %g); also\n"
                 "                          the distance within which a source voxel counts as overlapping\n"
                 "  --min-overlap X         least overlap of a valid refined pose, in [0, 1] (default %g): the\n"
                 "                          share of the source's voxels within that distance of the target\n"
                 "  --min-refine-condition X (default %g)\n"
                 "                          least condition of a valid refined pose, in [0, 1]: the weakest\n"
                 "                          direction's share of the strongest one's information; below it the\n"
                 "                          pose slides (a corridor, a plane)\n"
                 "  --max-refine-rmse GAIN (default %g)\n"
                 "                          largest residual of a valid refined pose = GAIN * voxel, in (0, 100]:\n"
                 "                          right alignments stay within a fraction of a voxel, the wrong optima\n"
                 "                          a far initial pose leads to do not\n"
                 "  --allow-degenerate      a refined pose that leaves directions free (a corridor, a tunnel, a\n"
                 "                          plane) may be valid, flagged (JSON degenerate, weak_directions);\n"
                 "                          without it such a pose is not valid (reason_code 8)\n"
                 "  --refine-normal-radius GAIN (default %g)\n"
                 "                          refinement aligns planes fitted to the neighbours within GAIN * voxel\n"
                 "                          (at least 5 of them; at most the normals' radius), in (0, 50]\n",
                 d.refine_max_iterations, d.refine_max_distance_gain, d.min_overlap, d.min_refine_condition,
                 d.max_refine_rmse_gain, d.refine_normal_radius_gain);
    if (command == PairCommand::Register) {
        std::fprintf(out,
                     "  --refine-min-inliers N  final inliers a valid refined pose needs, 3..100000 (default %d);\n"
                     "                          --min-inliers applies without refinement\n"
                     "  --min-inlier-coverage X least inlier coverage of a valid refined pose (default %g), in\n"
                     "                          [0, 1]: the spread of the solver's inliers over that of the aligned\n"
                     "                          overlap (inliers on one object cover little of it)\n",
                     d.refine_min_inliers, d.min_inlier_coverage);
    }
    std::fprintf(out, "\n");
}

void print_pair_output_help(std::FILE *out) {
    std::fprintf(out,
                 "Output:\n"
                 "  --json                  print one JSON object instead of the summary (see src/cli/README.md):\n"
                 "                          valid, reason, transform (4x4 row-major), coarse_transform, refine,\n"
                 "                          information (6x6, null without refinement), overlap, refine_rmse,\n"
                 "                          counts, time_ms, ...; numbers read back to the exact doubles, NaN\n"
                 "                          is written as null\n"
                 "  --out-transform FILE    write the 4x4 transform as 4 lines of 4 numbers (%%.17g); NaN when\n"
                 "                          no pose was estimated. `kissm refine --initial FILE` reads it\n"
                 "  --out-aligned FILE      write SOURCE moved into TARGET's frame; skipped when no pose was\n"
                 "                          estimated. FILE.las: LAS 1.2 point format 0, with TARGET's scale and\n"
                 "                          offset when TARGET is LAS/LAZ (else 0.0001 around the cloud's centre);\n"
                 "                          non-finite points left out. Any other name: binary little-endian PLY,\n"
                 "                          float64 x y z\n"
                 "  --out-topview FILE.png  top-down picture: before and after (source orange, target blue);\n"
                 "                          with refinement also a detail under the coarse and refined poses\n"
                 "  -v, --verbose           print the library's log messages on stderr\n"
                 "  -h, --help              this text\n"
                 "\n");
}

} // namespace

void print_pair_help(std::FILE *out, PairCommand command, const char *intro,
                     void (*settings)(std::FILE *out, const kissm_config &defaults), const char *exit_status) {
    const kissm_config defaults = config_defaults();
    std::fputs(intro, out);
    print_pair_input_help(out);
    settings(out, defaults);
    print_refinement_help(out, command, defaults);
    print_pair_output_help(out);
    std::fputs(exit_status, out);
}

} // namespace kissm_cli
