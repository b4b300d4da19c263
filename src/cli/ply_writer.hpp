// SPDX-License-Identifier: MIT
// Writes point clouds as binary little-endian PLY with float64 ("double") x y z properties, whatever the
// host's byte order. float64 keeps every coordinate exactly, so a cloud written here and read back with
// kissm_read_points() registers to the same result as the in-memory cloud.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace kissm_cli {

// xyz: count packed x y z doubles. transform (optional, row-major 4x4): each point p is written as R p + t.
// comments: header comment lines (no newlines). Returns false and sets *error on failure.
bool write_ply_xyz(const std::string &path, const double *xyz, size_t count, const double *transform,
                   const std::vector<std::string> &comments, std::string *error);

} // namespace kissm_cli
