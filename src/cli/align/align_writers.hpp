// SPDX-License-Identifier: MIT
// `kissm align`'s text outputs: the poses table (--out), and the TUM, KITTI and g2o files, which are byte for
// byte what Python's kissm.multiway Alignment.write_tum / write_kitti / write_g2o write for the same numbers.
#pragma once

#include <string>
#include <vector>

#include "align/align_graph.hpp"
#include "align/align_scans.hpp"

namespace kissm_cli {

// Python's repr() of a float: the shortest digits that read back to the same double, in fixed notation
// from 1e-4 up to 1e16 (with ".0" when whole: "1.0", "-0.0"), else as "1.5e-05"; "nan", "inf", "-inf".
std::string python_float_text(double v);

// (qx, qy, qz, qw) of the rotation block of a row-major 4x4, w >= 0: the same operations, in the same order,
// as multiway._quaternion, so that the same matrix gives the same bits.
void rotation_quaternion(const double T[16], double q[4]);

// The poses table: a header line "scan placed component T00 T01 T02 T03 T10 ... T23" (tab-separated), then one
// line per scan in the scans file's order: its name, 1 or 0, its component (a scan position), and the first
// three rows of T_world_scan, each number the shortest text that reads back to the same double ("nan" for a
// scan that is not placed).
std::string poses_table(const std::vector<Scan> &scans, const Alignment &alignment);
// TUM: "timestamp tx ty tz qx qy qz qw" per placed scan, its position as the timestamp.
std::string tum_text(const Alignment &alignment);
// KITTI odometry: the first three rows of every scan's pose, one line per scan ("nan" where not placed).
std::string kitti_text(const Alignment &alignment);
// g2o: a VERTEX_SE3:QUAT per placed scan, an EDGE_SE3:QUAT from target to source per accepted edge, with the
// information reordered to g2o's (translation first) and its rotation rows and columns doubled (g2o's error is
// a quaternion's vector part, half the angle; docs/pose-graph.md).
std::string g2o_text(const Alignment &alignment);

// Writes the text to a file; a UsageError naming `what` (--out, --g2o, ...) when it cannot.
void write_text_file(const std::string &path, const std::string &text, const char *what);

} // namespace kissm_cli
