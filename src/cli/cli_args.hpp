// SPDX-License-Identifier: MIT
// Command-line parsing helpers shared by the kissm commands. Every problem with the command line or the
// inputs is reported by throwing UsageError; main() prints it as one "kissm: ..." line and exits with 2.
#pragma once

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace kissm_cli {

// Exit status of the tool.
constexpr int kExitOk = 0;      // success (a valid, trustworthy pose)
constexpr int kExitInvalid = 1; // ran, but the result is not valid (or the demo missed its accuracy bound)
constexpr int kExitUsage = 2;   // usage or input error

class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Walks over a command's arguments. Options are "--name value", "--name=value" or flags; "--" ends the
// options; everything else is positional.
// Every command's name with its --help printer, in `kissm --help` order (for suggestions).
const std::vector<std::pair<std::string, void (*)(std::FILE *)>> &command_helps();

class ArgCursor {
public:
    ArgCursor(std::string command, std::vector<std::string> args);

    // Advances to the next argument; false at the end.
    bool next();
    bool is_option() const { return is_option_; }
    // -h or --help: every command prints its help and stops there.
    bool is_help() const { return is_option_ && (name_ == "-h" || name_ == "--help"); }
    // The option's name ("--voxel", without any "=value") or the positional argument.
    const std::string &current() const { return name_; }
    // The current option's value: its "=value" part or the next argument.
    std::string value();
    // For flags: rejects "--flag=value".
    void expect_no_value() const;
    // When the current option is the flag `name` (or its short form `alias`): rejects a value, sets *flag
    // and returns true.
    bool take_flag(const char *name, bool *flag, const char *alias = nullptr) const;
    [[noreturn]] void unknown() const;

private:
    std::string command_;
    std::vector<std::string> args_;
    size_t index_ = 0;
    bool options_done_ = false;
    bool is_option_ = false;
    bool has_inline_value_ = false;
    std::string name_;
    std::string inline_value_;
};

double parse_double(const std::string &option, const std::string &text);   // finite
double parse_positive(const std::string &option, const std::string &text); // finite and > 0
int32_t parse_int32(const std::string &option, const std::string &text, int32_t min_value, int32_t max_value);
uint64_t parse_uint64(const std::string &option, const std::string &text);
// A point file format name (auto, ply, pcd, kitti_bin, bin_xyz, npy, xyz, las, and the names used by the test
// data's pair.txt files) to its KISSM_FORMAT_* value.
int32_t parse_format(const std::string &option, const std::string &text);
const char *format_names();
// A refinement mode name (none, gicp, point-to-plane; point_to_plane as golden.json spells it) to its
// KISSM_REFINE_* value, and back (the names the JSON prints; "unknown" for other values).
int32_t parse_refine_mode(const std::string &option, const std::string &text);
// --viewpoint: fixed, center (cloud-center), sign-free or local.
int32_t parse_viewpoint_mode(const std::string &option, const std::string &text);
const char *refine_mode_name(int32_t mode);
// --up, --viewpoint X,Y,Z: three finite numbers separated by commas ("0,0,1"), into out[0..2].
void parse_vec3(const std::string &option, const std::string &text, double out[3]);
// --suppression: none or ground, to its KISSM_SUPPRESS_* value.
int32_t parse_suppression(const std::string &option, const std::string &text);
// --preset: lidar-vehicle, lidar-handheld, indoor-rgbd or object (or with underscores), to its
// KISSM_PRESET_* value.
int32_t parse_preset(const std::string &option, const std::string &text);
const char *preset_names();
const char *preset_name(int32_t preset); // "lidar-vehicle", ...; "unknown" for other values

// The text with line breaks replaced by spaces, so that an error message stays on one line.
std::string one_line(const std::string &text);

} // namespace kissm_cli
