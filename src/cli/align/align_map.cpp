// SPDX-License-Identifier: MIT
#include "align_map.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "cli_args.hpp"
#include "commands.hpp"
#include "json_writer.hpp"
#include "pair_command.hpp"
#include "ply_writer.hpp"

namespace kissm_cli {
namespace {

// One centroid per occupied cell. A stable sort keeps each cell's points in their order, so the sums add up
// in the same order as numpy's add.at over the merged points.
std::vector<double> voxel_centroids(const std::vector<double> &xyz, double voxel) {
    const size_t n = xyz.size() / 3;
    using Cell = std::array<int64_t, 3>;
    std::vector<Cell> cells(n);
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) cells[i][k] = static_cast<int64_t>(std::floor(xyz[3 * i + k] / voxel));
    }
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), size_t{0});
    std::stable_sort(order.begin(), order.end(), [&cells](size_t a, size_t b) { return cells[a] < cells[b]; });
    std::vector<double> out;
    for (size_t begin = 0; begin < n;) {
        size_t end = begin;
        double sum[3] = {0.0, 0.0, 0.0};
        while (end < n && cells[order[end]] == cells[order[begin]]) {
            for (int k = 0; k < 3; ++k) sum[k] += xyz[3 * order[end] + k];
            ++end;
        }
        const double count = static_cast<double>(end - begin);
        for (int k = 0; k < 3; ++k) out.push_back(sum[k] / count);
        begin = end;
    }
    return out;
}

} // namespace

size_t write_merged_map(const std::string &path, const std::vector<Scan> &scans, const Alignment &alignment,
                        double voxel) {
    std::vector<double> xyz;
    size_t placed = 0;
    for (size_t s = 0; s < scans.size(); ++s) {
        if (!alignment.placed[s]) continue;
        ++placed;
        const CloudPtr cloud = read_cloud("scan", scans[s].file, scans[s].format);
        const double *p = kissm_cloud_data(cloud.get());
        const size_t count = static_cast<size_t>(kissm_cloud_count(cloud.get()));
        const double *T = &alignment.poses[16 * s];
        xyz.reserve(xyz.size() + 3 * count);
        for (size_t i = 0; i < count; ++i, p += 3) {
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
            for (int r = 0; r < 3; ++r) {
                xyz.push_back(T[4 * r] * p[0] + T[4 * r + 1] * p[1] + T[4 * r + 2] * p[2] + T[4 * r + 3]);
            }
        }
    }
    if (voxel > 0.0) xyz = voxel_centroids(xyz, voxel);
    std::vector<std::string> comments = {"kissm align: " + std::to_string(placed) + " placed scans in the frame of '" +
                                         one_line(scans[0].name) + "'"};
    if (voxel > 0.0) comments.push_back("one centroid per voxel of " + JsonWriter::number(voxel));
    std::string error;
    const size_t count = xyz.size() / 3;
    if (!write_ply_xyz(path, xyz.data(), count, nullptr, comments, &error)) throw UsageError(one_line(error));
    return count;
}

} // namespace kissm_cli
