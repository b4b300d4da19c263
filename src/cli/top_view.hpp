// SPDX-License-Identifier: MIT
// Top-down (x-y) pictures of point clouds: one or more square panels side by side, each overlaying several
// clouds in their own colours, with a metric grid, a scale bar, sensor markers, titles and a legend.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "raster.hpp"

namespace kissm_cli {

struct CloudLayer {
    const double *xyz = nullptr; // packed x y z
    size_t count = 0;
    const double *transform = nullptr; // optional row-major 4x4 applied before projecting
    Rgb color{0, 0, 0};
};

struct Marker { // drawn as a cross, e.g. a sensor origin
    double x = 0, y = 0;
    Rgb color{0, 0, 0};
};

struct TopViewPanel {
    std::string title;
    std::vector<CloudLayer> layers; // drawn in order: later layers on top
    std::vector<Marker> markers;
};

struct ViewBox { // the square region shown by every panel, metres
    double cx = 0, cy = 0, half = 10;
};

struct TopViewFigure {
    std::vector<TopViewPanel> panels;
    std::vector<std::pair<std::string, Rgb>> legend;
    std::vector<std::string> notes; // text lines under the panels
    int panel_size = 640;           // pixels
};

// A square box holding about 98% of the layers' points (robust to far outliers).
ViewBox fit_view(const std::vector<CloudLayer> &layers);
Image render_top_view(const TopViewFigure &figure, const ViewBox &view);

} // namespace kissm_cli
