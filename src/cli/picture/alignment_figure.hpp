// SPDX-License-Identifier: MIT
// The before/after picture of a registration shared by `kissm register --out-topview` and `kissm demo`:
// BEFORE (each cloud in its own frame) and AFTER (the source moved by the final pose) over the whole scene
// and, when refinement ran, a detail of a small region with both clouds' structure (the ground hidden) under
// the coarse pose and under the refined pose side by side: the refinement's centimetres do not show at the
// scale of a street.
#pragma once

#include <cstddef>
#include <string>

#include "top_view.hpp"

namespace kissm_cli {

struct AlignmentInput {
    const double *source_xyz = nullptr;
    size_t source_count = 0;
    const double *target_xyz = nullptr;
    size_t target_count = 0;
    const double *before = nullptr; // the source's pose in the BEFORE panel (null: its own frame)
    const double *pose = nullptr;   // the final pose (row-major 4x4), or null when none was estimated
    const double *coarse = nullptr; // the pose before refinement, or null when refinement did not run
    double voxel = 0.3;             // the registration's voxel size: the ground clearance of the details
    std::string before_title, after_title, coarse_title, refined_title;
};

struct AlignmentPicture {
    TopViewFigure figure; // panels: before, after[, coarse detail, refined detail] (two per row with details)
    ViewBox view;         // the whole scene, shared by the first two panels
    bool has_detail = false;
};

extern const Rgb kSourceColor; // orange
extern const Rgb kTargetColor; // blue

// The figure, with the target's height floor (when there are details) owned by the returned object.
class AlignmentFigure {
public:
    explicit AlignmentFigure(const AlignmentInput &input);
    AlignmentFigure(const AlignmentFigure &) = delete; // the detail layers point at floor_
    AlignmentFigure &operator=(const AlignmentFigure &) = delete;
    AlignmentPicture &picture() { return picture_; }

private:
    HeightFloor floor_;
    AlignmentPicture picture_;
};

// The detail region: the square of side 2 * half inside `view` holding the most structure of both clouds
// (points above their layers' floors): the largest sum over the cells of a grid over `view` of the smaller
// of the two clouds' counts; the first such square in row-major order.
ViewBox detail_view(const CloudLayer &target, const CloudLayer &aligned_source, const ViewBox &view, double half);
// The lowest target point per cell of a cells x cells grid over `view`, with the given clearance.
HeightFloor height_floor(const CloudLayer &target, const ViewBox &view, int cells, double clearance);

} // namespace kissm_cli
