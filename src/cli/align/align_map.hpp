// SPDX-License-Identifier: MIT
// `kissm align --map`: the placed scans' points in the world (the first scan's) frame, as one PLY.
#pragma once

#include <string>
#include <vector>

#include "align/align_graph.hpp"
#include "align/align_scans.hpp"

namespace kissm_cli {

// Reads every placed scan again, moves its finite points into the world frame (p_world = R p + t) and writes
// them, scan after scan, as binary little-endian PLY (ply_writer). voxel > 0: instead, the centroid of each
// occupied voxel of that size (cells floor(p / voxel), in increasing (x, y, z) cell order, each summed in
// point order, as Python's Alignment.merged). Returns the points written; a UsageError when a scan cannot be
// read or the file cannot be written.
size_t write_merged_map(const std::string &path, const std::vector<Scan> &scans, const Alignment &alignment,
                        double voxel);

} // namespace kissm_cli
