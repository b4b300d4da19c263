// SPDX-License-Identifier: MIT
// Point file readers. Every reader bounds-checks every byte it reads and throws Failure(Io | Parse |
// UnsupportedFormat) with a message naming the file and the problem; none allocates more than the file
// could justify (counts in headers are checked against the file size before allocating).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/detail_namespace.hpp"

KISSM_DETAIL_BEGIN

// The readers (src/capi/files.cpp maps the KISSM_FORMAT_* constants of kissm.h to these).
enum class FileFormat { Auto = 0, Ply = 1, Pcd = 2, KittiBin = 3, Npy = 4, Xyz = 5, BinXyz = 6, Las = 7 };

// Reads the file's points as packed x y z doubles (3 * N values). Non-finite values are returned as-is.
// Auto chooses by extension (any case): .ply, .pcd, .bin (KittiBin), .npy, .xyz / .txt / .pts / .asc (Xyz),
// .las / .laz (Las; LAZ is refused as UnsupportedFormat when not built in); for any other extension by content
// (a "ply" line, a PCD header, the \x93NUMPY magic, the "LASF" signature); else it throws
// Failure(UnsupportedFormat). Missing or unreadable files throw Failure(Io); empty, malformed or truncated
// ones Failure(Parse). A well-formed file with no points gives an empty vector. *withheld (when given) is set
// to the number of points the reader left out on purpose: LAS/LAZ points flagged withheld; 0 otherwise.
std::vector<double> read_points_file(const std::string &path, FileFormat format, std::uint64_t *withheld = nullptr);

KISSM_DETAIL_END
