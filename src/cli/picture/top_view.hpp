// SPDX-License-Identifier: MIT
// Top-down (x-y) pictures of point clouds: square panels in rows, each overlaying several clouds in their
// own colours, with a metric grid, a scale bar, sensor markers, outlined regions, titles and a legend.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "raster.hpp"

namespace kissm_cli {

struct ViewBox { // a square region, metres
    double cx = 0, cy = 0, half = 10;
};

// The lowest point of a reference cloud per square cell of a region: drawing only what stands `clearance`
// above it hides the ground, so that walls, poles and cars (what shows a misalignment) stand out.
struct HeightFloor {
    double x0 = 0, y0 = 0, cell = 1; // the region's lower-left corner and the cell size
    int cells = 0;                   // per side
    std::vector<double> min_z;       // row-major from (x0, y0); +infinity where the reference has no point
    double clearance = 0;
    // True when z is at least `clearance` above the floor of the cell holding (x, y) (false outside).
    bool above(double x, double y, double z) const;
};

struct CloudLayer {
    const double *xyz = nullptr; // packed x y z
    size_t count = 0;
    const double *transform = nullptr; // optional row-major 4x4 applied before projecting
    Rgb color{0, 0, 0};
    const HeightFloor *floor = nullptr; // optional: only points above it (after the transform) are drawn
};

struct Marker { // drawn as a cross, e.g. a sensor origin
    double x = 0, y = 0;
    Rgb color{0, 0, 0};
};

struct TopViewPanel {
    std::string title;
    std::vector<CloudLayer> layers; // drawn in order: later layers on top
    std::vector<Marker> markers;
    bool has_view = false; // otherwise the figure's view
    ViewBox view;
    std::vector<std::pair<ViewBox, Rgb>> outlines; // regions drawn as rectangles (e.g. another panel's)
    int dot = 1; // pixels per side of a point: more for sparse points in a magnified view
};

struct TopViewFigure {
    std::vector<TopViewPanel> panels;
    std::vector<std::pair<std::string, Rgb>> legend;
    std::vector<std::string> notes; // text lines under the panels
    int panel_size = 640;           // pixels
    int columns = 0;                // panels per row; 0 = all in one row
};

// A square box holding about 98% of the layers' points (robust to far outliers).
ViewBox fit_view(const std::vector<CloudLayer> &layers);
// The layer's point i projected as drawn (transform applied): false when it is not drawn (not finite,
// or under the layer's floor).
bool project_point(const CloudLayer &layer, size_t i, double *x, double *y);
Image render_top_view(const TopViewFigure &figure, const ViewBox &view);

} // namespace kissm_cli
