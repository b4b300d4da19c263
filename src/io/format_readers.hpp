// SPDX-License-Identifier: MIT
// One parser per file format, each over a whole file already in memory. `path` is used for messages only.
// All return packed x y z doubles and throw Failure(Parse) for malformed or truncated content.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/detail_namespace.hpp"

KISSM_DETAIL_BEGIN

std::vector<double> parse_ply(const std::string &path, std::string_view bytes);
std::vector<double> parse_pcd(const std::string &path, std::string_view bytes);
std::vector<double> parse_kitti_bin(const std::string &path, std::string_view bytes); // float32 x y z i
std::vector<double> parse_bin_xyz(const std::string &path, std::string_view bytes);   // float32 x y z
std::vector<double> parse_npy(const std::string &path, std::string_view bytes);
std::vector<double> parse_xyz_text(const std::string &path, std::string_view bytes);
// LAS 1.0-1.4 (and LAZ when built in): points flagged withheld are left out, and counted in *withheld if given.
std::vector<double> parse_las(const std::string &path, std::string_view bytes, std::uint64_t *withheld = nullptr);

KISSM_DETAIL_END
