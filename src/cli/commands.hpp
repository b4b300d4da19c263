// SPDX-License-Identifier: MIT
// The kissm commands, and owning wrappers for the library's handles. The tool uses only the public C API
// of kissm.h.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <kissm.h>

namespace kissm_cli {

struct CloudDeleter {
    void operator()(kissm_cloud *cloud) const { kissm_cloud_destroy(cloud); }
};
struct MatcherDeleter {
    void operator()(kissm_matcher *matcher) const { kissm_destroy(matcher); }
};
using CloudPtr = std::unique_ptr<kissm_cloud, CloudDeleter>;
using MatcherPtr = std::unique_ptr<kissm_matcher, MatcherDeleter>;

// Each returns the process exit status (see cli_args.hpp) or throws UsageError.
int run_register(const std::vector<std::string> &args);
int run_refine(const std::vector<std::string> &args);
int run_demo(const std::vector<std::string> &args);
int run_ground(const std::vector<std::string> &args);
int run_batch(const std::vector<std::string> &args);
int run_simulate(const std::vector<std::string> &args);
int run_align(const std::vector<std::string> &args);

void print_register_help(std::FILE *out);
void print_refine_help(std::FILE *out);
void print_demo_help(std::FILE *out);
void print_ground_help(std::FILE *out);
void print_batch_help(std::FILE *out);
void print_simulate_help(std::FILE *out);
void print_align_help(std::FILE *out);

// A log callback printing the library's messages to stderr (for --verbose).
void log_to_stderr(void *user_data, int32_t level, const char *message);

} // namespace kissm_cli
