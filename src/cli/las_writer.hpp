// SPDX-License-Identifier: MIT
// Writes point clouds as ASPRS LAS 1.2, point data record format 0: x y z stored as int32 counts of a
// scale around an offset (the file's "frame"), every point a first and only return, unclassified. The
// frame is the target's when the target is a LAS/LAZ file, so that the aligned cloud lands on the same
// grid as the georeferenced data it was aligned to; otherwise las_frame_for() picks one (see there).
#pragma once

#include <cstddef>
#include <string>

namespace kissm_cli {

struct LasFrame {
    double scale[3] = {1, 1, 1};
    double offset[3] = {0, 0, 0};
};

// True when `path` names a LAS output (extension .las, any case).
bool is_las_path(const std::string &path);
// True when `path` names a LAZ file (extension .laz): kissm does not write those.
bool is_laz_path(const std::string &path);

// The scale and offset of a LAS or LAZ file's public header. False when the file does not start with a LAS
// header (not an error: the caller picks a frame itself) or its scale or offset is unusable.
bool read_las_frame(const std::string &path, LasFrame *frame);

// A frame for a cloud without one: scale 0.0001 (0.1 mm for metres: rounding moves a point by at most
// 0.05 mm, far below a scanner's noise) on every axis, coarser by powers of ten only when the cloud spans
// more than int32 counts hold (about +-214 km around the offset at 0.1 mm); offset the centre of the
// cloud's bounding box rounded to a whole unit. Points are taken after `transform` (row-major 4x4, or
// null); non-finite points are ignored.
LasFrame las_frame_for(const double *xyz, size_t count, const double *transform);

// Writes the finite points of `xyz` (count packed x y z doubles), each moved by `transform` (row-major 4x4,
// or null), in `frame`. Non-finite points are left out (LAS cannot hold them); *written says how many were
// written. Returns false and sets *error when the file cannot be written, a point does not fit the
// frame's int32 range, or there are more than 2^32 - 1 points.
bool write_las_xyz(const std::string &path, const double *xyz, size_t count, const double *transform,
                   const LasFrame &frame, size_t *written, std::string *error);

} // namespace kissm_cli
