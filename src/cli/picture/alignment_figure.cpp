// SPDX-License-Identifier: MIT
#include "alignment_figure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace kissm_cli {

const Rgb kSourceColor{255, 127, 14};
const Rgb kTargetColor{31, 119, 180};

namespace {

constexpr int kFloorCells = 128;        // per side of the whole view: about a metre for a street scan
constexpr double kDetailFraction = 8.0; // the detail square is 1/8 of the whole view's side
constexpr int kDetailDot = 2;           // pixels: the details magnify 8 times, so their points are sparse
constexpr Rgb kOutline{60, 60, 60};

// Points of the layer (as drawn) per cell of a cells x cells grid over `view`.
std::vector<uint32_t> cell_counts(const CloudLayer &layer, const ViewBox &view, int cells) {
    std::vector<uint32_t> counts(static_cast<size_t>(cells) * static_cast<size_t>(cells), 0u);
    const double cell = 2.0 * view.half / cells, x0 = view.cx - view.half, y0 = view.cy - view.half;
    for (size_t i = 0; i < layer.count; ++i) {
        double x = 0, y = 0;
        if (!project_point(layer, i, &x, &y)) continue;
        const double fx = (x - x0) / cell, fy = (y - y0) / cell;
        if (!(fx >= 0.0 && fy >= 0.0 && fx < cells && fy < cells)) continue;
        ++counts[static_cast<size_t>(fy) * static_cast<size_t>(cells) + static_cast<size_t>(fx)];
    }
    return counts;
}

} // namespace

HeightFloor height_floor(const CloudLayer &target, const ViewBox &view, int cells, double clearance) {
    HeightFloor floor;
    floor.x0 = view.cx - view.half;
    floor.y0 = view.cy - view.half;
    floor.cells = cells;
    floor.cell = 2.0 * view.half / cells;
    floor.clearance = clearance;
    floor.min_z.assign(static_cast<size_t>(cells) * static_cast<size_t>(cells),
                       std::numeric_limits<double>::infinity());
    const double *T = target.transform;
    CloudLayer all = target;
    all.floor = nullptr;
    for (size_t i = 0; i < target.count; ++i) {
        const double *p = target.xyz + 3 * i;
        double x = 0, y = 0;
        if (!project_point(all, i, &x, &y)) continue;
        const double z = T ? T[8] * p[0] + T[9] * p[1] + T[10] * p[2] + T[11] : p[2];
        const double fx = (x - floor.x0) / floor.cell, fy = (y - floor.y0) / floor.cell;
        if (!(fx >= 0.0 && fy >= 0.0 && fx < cells && fy < cells) || !std::isfinite(z)) continue;
        double &m = floor.min_z[static_cast<size_t>(fy) * static_cast<size_t>(cells) + static_cast<size_t>(fx)];
        m = std::min(m, z);
    }
    return floor;
}

ViewBox detail_view(const CloudLayer &target, const CloudLayer &aligned_source, const ViewBox &view, double half) {
    const int cells = kFloorCells;
    const std::vector<uint32_t> t = cell_counts(target, view, cells), s = cell_counts(aligned_source, view, cells);
    // Summed-area table of the structure both clouds show: per cell, the smaller of their point counts
    // (dense walls seen from both sensors score high; one cloud's clutter or a far, sparse wall low).
    const size_t stride = static_cast<size_t>(cells) + 1;
    std::vector<uint64_t> sum(stride * stride, 0u);
    for (int y = 0; y < cells; ++y) {
        for (int x = 0; x < cells; ++x) {
            const size_t k = static_cast<size_t>(y) * static_cast<size_t>(cells) + static_cast<size_t>(x);
            const uint64_t both = std::min(t[k], s[k]);
            sum[(y + 1) * stride + (x + 1)] =
                both + sum[y * stride + (x + 1)] + sum[(y + 1) * stride + x] - sum[y * stride + x];
        }
    }
    const double cell = 2.0 * view.half / cells;
    const int side = std::max(1, std::min(cells, static_cast<int>(std::lround(2.0 * half / cell))));
    int best_x = (cells - side) / 2, best_y = (cells - side) / 2;
    uint64_t best = 0;
    for (int y = 0; y + side <= cells; ++y) {
        for (int x = 0; x + side <= cells; ++x) {
            const uint64_t v = sum[(y + side) * stride + (x + side)] - sum[y * stride + (x + side)] -
                               sum[(y + side) * stride + x] + sum[y * stride + x];
            if (v > best) {
                best = v;
                best_x = x;
                best_y = y;
            }
        }
    }
    ViewBox box;
    box.half = 0.5 * side * cell;
    box.cx = view.cx - view.half + (best_x + 0.5 * side) * cell;
    box.cy = view.cy - view.half + (best_y + 0.5 * side) * cell;
    return box;
}

AlignmentFigure::AlignmentFigure(const AlignmentInput &in) {
    const CloudLayer target{in.target_xyz, in.target_count, nullptr, kTargetColor, nullptr};
    const CloudLayer source{in.source_xyz, in.source_count, in.before, kSourceColor, nullptr};
    const CloudLayer aligned{in.source_xyz, in.source_count, in.pose, kSourceColor, nullptr};
    AlignmentPicture &pic = picture_;
    pic.view = fit_view({target, in.pose ? aligned : source});
    pic.figure.panels.push_back({in.before_title, {target, source}, {}, false, {}, {}, 1});
    TopViewPanel after{in.after_title, {target}, {}, false, {}, {}, 1};
    if (in.pose) after.layers.push_back(aligned);
    pic.figure.panels.push_back(after);
    pic.figure.legend = {{"SOURCE", kSourceColor}, {"TARGET", kTargetColor}};
    if (!in.pose || !in.coarse) return;

    // The details: structure only (the ground would cover the whole square), in a region both clouds share.
    floor_ = height_floor(target, pic.view, kFloorCells, 2.0 * in.voxel);
    CloudLayer target_above = target, refined_above = aligned, coarse_above = aligned;
    target_above.floor = refined_above.floor = coarse_above.floor = &floor_;
    coarse_above.transform = in.coarse;
    const ViewBox detail = detail_view(target_above, refined_above, pic.view, pic.view.half / kDetailFraction);
    pic.figure.panels[1].outlines.push_back({detail, kOutline});
    pic.figure.panels.push_back({in.coarse_title, {target_above, coarse_above}, {}, true, detail, {}, kDetailDot});
    pic.figure.panels.push_back({in.refined_title, {target_above, refined_above}, {}, true, detail, {}, kDetailDot});
    pic.figure.columns = 2;
    pic.has_detail = true;
}

} // namespace kissm_cli
