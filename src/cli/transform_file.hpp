// SPDX-License-Identifier: MIT
// The tool's transform file: 4 lines of 4 whitespace-separated numbers (a 4x4 row-major matrix that maps
// source points into the target frame), as --out-transform writes it and `kissm refine --initial` reads it.
// Lines whose first non-blank character is '#', and blank lines, are ignored when reading.
#pragma once

#include <string>

namespace kissm_cli {

// Four lines of four "%.17g" numbers (exact doubles). Returns false and sets *error on failure.
bool write_transform_file(const std::string &path, const double T[16], std::string *error);

// Reads exactly 16 finite numbers in 4 rows of 4 into T. Returns false and sets *error (a one-line message
// naming the file and, where there is one, the line) when the file cannot be read, a row does not hold 4
// numbers, there are not 4 rows, or a number is not finite. Whether the matrix is rigid is the library's to
// judge (kissm_refine checks it and names initial_transform).
bool read_transform_file(const std::string &path, double T[16], std::string *error);

} // namespace kissm_cli
