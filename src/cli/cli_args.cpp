// SPDX-License-Identifier: MIT
#include "cli_args.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <utility>

#include <kissm.h>

#include "commands.hpp"
#include "near_match.hpp"

namespace kissm_cli {

namespace {

// The command's --help printer, whose text lists every option it takes (nullptr for an unknown command).
void (*help_of(const std::string &command))(std::FILE *) {
    for (const auto &[name, print] : command_helps())
        if (command == name) return print;
    return nullptr;
}

} // namespace

const std::vector<std::pair<std::string, void (*)(std::FILE *)>> &command_helps() {
    static const std::vector<std::pair<std::string, void (*)(std::FILE *)>> helps = {
        {"register", print_register_help}, {"refine", print_refine_help}, {"demo", print_demo_help},
        {"ground", print_ground_help},     {"batch", print_batch_help},   {"simulate", print_simulate_help},
        {"align", print_align_help}};
    return helps;
}

ArgCursor::ArgCursor(std::string command, std::vector<std::string> args)
    : command_(std::move(command)), args_(std::move(args)) {}

bool ArgCursor::next() {
    if (index_ >= args_.size()) return false;
    const std::string &arg = args_[index_++];
    has_inline_value_ = false;
    inline_value_.clear();
    if (!options_done_ && arg == "--") {
        options_done_ = true;
        return next();
    }
    is_option_ = !options_done_ && arg.size() > 1 && arg[0] == '-';
    name_ = arg;
    if (is_option_ && arg.compare(0, 2, "--") == 0) {
        const size_t eq = arg.find('=');
        if (eq != std::string::npos) {
            name_ = arg.substr(0, eq);
            inline_value_ = arg.substr(eq + 1);
            has_inline_value_ = true;
        }
    }
    return true;
}

std::string ArgCursor::value() {
    std::string v;
    if (has_inline_value_) {
        v = inline_value_;
    } else if (index_ < args_.size()) {
        v = args_[index_++];
    }
    if (v.empty()) throw UsageError(name_ + " needs a value (see 'kissm " + command_ + " --help')");
    return v;
}

void ArgCursor::expect_no_value() const {
    if (has_inline_value_) throw UsageError(name_ + " takes no value");
}

bool ArgCursor::take_flag(const char *name, bool *flag, const char *alias) const {
    if (!is_option_ || (name_ != name && (alias == nullptr || name_ != alias))) return false;
    expect_no_value();
    *flag = true;
    return true;
}

void ArgCursor::unknown() const {
    std::string hint;
    if (is_option_ && name_.compare(0, 2, "--") == 0) {
        if (auto *print = help_of(command_)) hint = did_you_mean(name_, options_in_help(print));
    }
    throw UsageError("unknown option '" + one_line(name_) + "' for 'kissm " + command_ + "'" + hint + " (see 'kissm " +
                     command_ + " --help')");
}

double parse_double(const std::string &option, const std::string &text) {
    const char *begin = text.c_str();
    char *end = nullptr;
    errno = 0;
    const double v = std::strtod(begin, &end);
    if (text.empty() || end != begin + text.size() || std::isspace(static_cast<unsigned char>(text[0]))) {
        throw UsageError(option + " expects a number, got '" + one_line(text) + "'");
    }
    if (!std::isfinite(v) || errno == ERANGE) {
        throw UsageError(option + " expects a finite number, got '" + one_line(text) + "'");
    }
    return v;
}

double parse_positive(const std::string &option, const std::string &text) {
    const double v = parse_double(option, text);
    if (!(v > 0.0)) throw UsageError(option + " must be greater than 0, got '" + one_line(text) + "'");
    return v;
}

int32_t parse_int32(const std::string &option, const std::string &text, int32_t min_value, int32_t max_value) {
    const char *begin = text.c_str();
    char *end = nullptr;
    errno = 0;
    const long long v = std::strtoll(begin, &end, 10);
    if (text.empty() || end != begin + text.size() || std::isspace(static_cast<unsigned char>(text[0]))) {
        throw UsageError(option + " expects an integer, got '" + one_line(text) + "'");
    }
    if (errno == ERANGE || v < min_value || v > max_value) {
        throw UsageError(option + " must be between " + std::to_string(min_value) + " and " +
                         std::to_string(max_value) + ", got '" + one_line(text) + "'");
    }
    return static_cast<int32_t>(v);
}

uint64_t parse_uint64(const std::string &option, const std::string &text) {
    const char *begin = text.c_str();
    char *end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(begin, &end, 0);
    if (text.empty() || end != begin + text.size() || text[0] == '-' || text[0] == '+' ||
        std::isspace(static_cast<unsigned char>(text[0]))) {
        throw UsageError(option + " expects a non-negative integer, got '" + one_line(text) + "'");
    }
    if (errno == ERANGE) throw UsageError(option + " is out of range: '" + one_line(text) + "'");
    return static_cast<uint64_t>(v);
}

int32_t parse_format(const std::string &option, const std::string &text) {
    struct Name {
        const char *name;
        int32_t format;
    };
    static const Name kNames[] = {
        {"auto", KISSM_FORMAT_AUTO},       {"ply", KISSM_FORMAT_PLY},
        {"pcd", KISSM_FORMAT_PCD},         {"kitti_bin", KISSM_FORMAT_KITTI_BIN},
        {"kitti", KISSM_FORMAT_KITTI_BIN}, {"kitti_bin_xyzi_f32", KISSM_FORMAT_KITTI_BIN},
        {"bin_xyz", KISSM_FORMAT_BIN_XYZ}, {"bin_xyz_f32", KISSM_FORMAT_BIN_XYZ},
        {"npy", KISSM_FORMAT_NPY},         {"npy_xyz", KISSM_FORMAT_NPY},
        {"xyz", KISSM_FORMAT_XYZ},         {"txt", KISSM_FORMAT_XYZ},
        {"las", KISSM_FORMAT_LAS},
    };
    for (const Name &n : kNames) {
        if (text == n.name) return n.format;
    }
    throw UsageError(option + ": unknown format '" + one_line(text) + "' (expected " + format_names() + ")");
}

const char *format_names() { return "auto, ply, pcd, kitti_bin, bin_xyz, npy, xyz or las"; }

int32_t parse_refine_mode(const std::string &option, const std::string &text) {
    if (text == "none") return KISSM_REFINE_NONE;
    if (text == "gicp") return KISSM_REFINE_GICP;
    if (text == "point-to-plane" || text == "point_to_plane") return KISSM_REFINE_POINT_TO_PLANE;
    throw UsageError(option + ": unknown refinement '" + one_line(text) + "' (expected gicp, point-to-plane or none)");
}

int32_t parse_viewpoint_mode(const std::string &option, const std::string &text) {
    if (text == "fixed") return KISSM_VIEWPOINT_FIXED;
    if (text == "center" || text == "cloud-center" || text == "cloud_center") return KISSM_VIEWPOINT_CLOUD_CENTER;
    if (text == "sign-free" || text == "sign_free") return KISSM_VIEWPOINT_SIGN_FREE;
    if (text == "local") return KISSM_VIEWPOINT_LOCAL;
    throw UsageError(option + ": unknown viewpoint mode '" + one_line(text) +
                     "' (expected fixed, center, sign-free or local)");
}

const char *refine_mode_name(int32_t mode) {
    switch (mode) {
    case KISSM_REFINE_NONE: return "none";
    case KISSM_REFINE_GICP: return "gicp";
    case KISSM_REFINE_POINT_TO_PLANE: return "point-to-plane";
    default: return "unknown";
    }
}

void parse_vec3(const std::string &option, const std::string &text, double out[3]) {
    double v[3] = {0.0, 0.0, 0.0};
    size_t begin = 0;
    for (int i = 0; i < 3; ++i) {
        const size_t comma = text.find(',', begin);
        const bool last = i == 2;
        if (last != (comma == std::string::npos)) {
            throw UsageError(option + " expects three numbers X,Y,Z separated by commas, got '" + one_line(text) + "'");
        }
        const std::string part = text.substr(begin, last ? std::string::npos : comma - begin);
        v[i] = parse_double(option, part);
        begin = comma + 1;
    }
    for (int i = 0; i < 3; ++i) out[i] = v[i];
}

int32_t parse_suppression(const std::string &option, const std::string &text) {
    if (text == "none") return KISSM_SUPPRESS_NONE;
    if (text == "ground") return KISSM_SUPPRESS_GROUND;
    throw UsageError(option + ": unknown suppression '" + one_line(text) + "' (expected none or ground)");
}

int32_t parse_preset(const std::string &option, const std::string &text) {
    std::string name = text;
    for (char &c : name) {
        if (c == '_') c = '-';
    }
    if (name == "lidar-vehicle") return KISSM_PRESET_LIDAR_VEHICLE;
    if (name == "lidar-handheld") return KISSM_PRESET_LIDAR_HANDHELD;
    if (name == "indoor-rgbd") return KISSM_PRESET_INDOOR_RGBD;
    if (name == "object") return KISSM_PRESET_OBJECT;
    throw UsageError(option + ": unknown preset '" + one_line(text) + "' (expected " + preset_names() + ")");
}

const char *preset_name(int32_t preset) {
    switch (preset) {
    case KISSM_PRESET_LIDAR_VEHICLE: return "lidar-vehicle";
    case KISSM_PRESET_LIDAR_HANDHELD: return "lidar-handheld";
    case KISSM_PRESET_INDOOR_RGBD: return "indoor-rgbd";
    case KISSM_PRESET_OBJECT: return "object";
    default: return "unknown";
    }
}

const char *preset_names() { return "lidar-vehicle, lidar-handheld, indoor-rgbd or object"; }

std::string one_line(const std::string &text) {
    std::string out = text;
    for (char &c : out) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    return out;
}

} // namespace kissm_cli
