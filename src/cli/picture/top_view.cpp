// SPDX-License-Identifier: MIT
#include "top_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace kissm_cli {
namespace {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kGrid{232, 232, 232};
constexpr Rgb kAxis{200, 200, 200};
constexpr Rgb kBorder{120, 120, 120};
constexpr Rgb kText{40, 40, 40};
constexpr int kMargin = 20;
constexpr int kGap = 24;
constexpr int kTextScale = 2;

// Grid spacing of 1, 2 or 5 times a power of ten giving 4 to 10 lines across the panel.
double grid_spacing(double extent) {
    double step = std::pow(10.0, std::floor(std::log10(extent / 4.0)));
    for (double m : {1.0, 2.0, 5.0, 10.0}) {
        if (extent / (step * m) <= 8.0) return step * m;
    }
    return step * 10.0;
}

std::string format_length(double metres) {
    char buf[32];
    if (metres >= 1.0) {
        std::snprintf(buf, sizeof buf, "%g M", metres);
    } else {
        std::snprintf(buf, sizeof buf, "%g CM", metres * 100.0);
    }
    return buf;
}

uint8_t mix(uint8_t from, uint8_t to, double alpha) {
    return static_cast<uint8_t>(std::lround(from + (to - from) * alpha));
}

void draw_panel(Image &img, int x0, int y0, int size, const TopViewPanel &panel, const ViewBox &view) {
    const double scale = size / (2.0 * view.half); // pixels per metre
    const double left = view.cx - view.half, top = view.cy + view.half;
    const auto to_px = [&](double x) { return static_cast<int>(std::floor((x - left) * scale)); };
    const auto to_py = [&](double y) { return static_cast<int>(std::floor((top - y) * scale)); };

    // Grid and axes through the origin.
    const double spacing = grid_spacing(2.0 * view.half);
    for (double g = std::ceil(left / spacing) * spacing; g <= left + 2.0 * view.half; g += spacing) {
        const int px = to_px(g);
        if (px >= 0 && px < size) img.vline(x0 + px, y0, y0 + size - 1, std::fabs(g) < 1e-9 ? kAxis : kGrid);
    }
    for (double g = std::ceil((top - 2.0 * view.half) / spacing) * spacing; g <= top; g += spacing) {
        const int py = to_py(g);
        if (py >= 0 && py < size) img.hline(x0, x0 + size - 1, y0 + py, std::fabs(g) < 1e-9 ? kAxis : kGrid);
    }

    // Points: per-pixel hit counts per layer, blended so that single hits are light and dense
    // structures (walls, poles) saturate.
    const int dot = std::max(1, panel.dot);
    const size_t npix = static_cast<size_t>(size) * static_cast<size_t>(size);
    std::vector<uint16_t> counts(npix);
    for (const CloudLayer &layer : panel.layers) {
        std::fill(counts.begin(), counts.end(), uint16_t{0});
        for (size_t i = 0; i < layer.count; ++i) {
            double x = 0, y = 0;
            if (!project_point(layer, i, &x, &y)) continue;
            const double fx = (x - left) * scale, fy = (top - y) * scale;
            if (fx < 0.0 || fy < 0.0 || fx >= size || fy >= size) continue;
            const int px = static_cast<int>(fx), py = static_cast<int>(fy);
            for (int dy = 0; dy < dot && py + dy < size; ++dy) {
                for (int dx = 0; dx < dot && px + dx < size; ++dx) {
                    uint16_t &c =
                        counts[static_cast<size_t>(py + dy) * static_cast<size_t>(size) + static_cast<size_t>(px + dx)];
                    if (c < UINT16_MAX) ++c;
                }
            }
        }
        for (int py = 0; py < size; ++py) {
            for (int px = 0; px < size; ++px) {
                const uint16_t c =
                    counts[static_cast<size_t>(py) * static_cast<size_t>(size) + static_cast<size_t>(px)];
                if (c == 0) continue;
                const double alpha = 0.92 * (1.0 - std::exp(-c / 1.5));
                const Rgb old = img.get(x0 + px, y0 + py);
                img.set(x0 + px, y0 + py,
                        {mix(old.r, layer.color.r, alpha), mix(old.g, layer.color.g, alpha),
                         mix(old.b, layer.color.b, alpha)});
            }
        }
    }

    // Markers: a cross with a white outline so that it stays visible on top of the points.
    for (const Marker &m : panel.markers) {
        const int px = x0 + to_px(m.x), py = y0 + to_py(m.y);
        if (px < x0 || py < y0 || px >= x0 + size || py >= y0 + size) continue;
        const Rgb dark{static_cast<uint8_t>(m.color.r * 3 / 5), static_cast<uint8_t>(m.color.g * 3 / 5),
                       static_cast<uint8_t>(m.color.b * 3 / 5)};
        for (int pass = 0; pass < 2; ++pass) {
            const int w = pass == 0 ? 2 : 1, len = pass == 0 ? 9 : 8;
            const Rgb c = pass == 0 ? kWhite : dark;
            for (int d = -w; d <= w; ++d) {
                img.hline(std::max(px - len, x0), std::min(px + len, x0 + size - 1), py + d, c);
                img.vline(px + d, std::max(py - len, y0), std::min(py + len, y0 + size - 1), c);
            }
        }
    }

    // Outlined regions, 2 pixels wide, clipped to the panel.
    for (const auto &outline : panel.outlines) {
        const ViewBox &b = outline.first;
        const int l = std::max(to_px(b.cx - b.half), 0), r = std::min(to_px(b.cx + b.half), size - 1);
        const int t = std::max(to_py(b.cy + b.half), 0), d = std::min(to_py(b.cy - b.half), size - 1);
        if (l > r || t > d) continue;
        for (int w = 0; w < 2; ++w) {
            img.hline(x0 + l, x0 + r, y0 + std::min(t + w, d), outline.second);
            img.hline(x0 + l, x0 + r, y0 + std::max(d - w, t), outline.second);
            img.vline(x0 + std::min(l + w, r), y0 + t, y0 + d, outline.second);
            img.vline(x0 + std::max(r - w, l), y0 + t, y0 + d, outline.second);
        }
    }

    // Scale bar (one grid spacing) in the bottom-left corner.
    const int bar = static_cast<int>(std::lround(spacing * scale));
    const int bx = x0 + 14, by = y0 + size - 16;
    img.fill_rect(bx - 6, by - 22, std::max(bar, Image::text_width(format_length(spacing), kTextScale)) + 12, 32,
                  kWhite);
    img.fill_rect(bx, by, bar, 3, kText);
    img.fill_rect(bx, by - 5, 2, 8, kText);
    img.fill_rect(bx + bar - 2, by - 5, 2, 8, kText);
    img.draw_text(bx, by - 19, format_length(spacing), kText, kTextScale);

    img.outline_rect(x0 - 1, y0 - 1, size + 2, size + 2, kBorder);
    img.draw_text(x0, y0 - Image::text_height(kTextScale) - 8, panel.title, kText, kTextScale);
}

} // namespace

bool HeightFloor::above(double x, double y, double z) const {
    const double fx = (x - x0) / cell, fy = (y - y0) / cell;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < cells && fy < cells)) return false;
    const size_t k = static_cast<size_t>(fy) * static_cast<size_t>(cells) + static_cast<size_t>(fx);
    return z >= min_z[k] + clearance;
}

bool project_point(const CloudLayer &layer, size_t i, double *x, double *y) {
    const double *p = layer.xyz + 3 * i;
    double z = p[2];
    if (layer.transform) {
        const double *T = layer.transform;
        *x = T[0] * p[0] + T[1] * p[1] + T[2] * p[2] + T[3];
        *y = T[4] * p[0] + T[5] * p[1] + T[6] * p[2] + T[7];
        if (layer.floor) z = T[8] * p[0] + T[9] * p[1] + T[10] * p[2] + T[11];
    } else {
        *x = p[0];
        *y = p[1];
    }
    if (!std::isfinite(*x) || !std::isfinite(*y)) return false;
    return !layer.floor || layer.floor->above(*x, *y, z);
}

ViewBox fit_view(const std::vector<CloudLayer> &layers) {
    size_t total = 0;
    for (const CloudLayer &layer : layers) total += layer.count;
    const size_t stride = std::max<size_t>(1, total / 50000);
    std::vector<double> xs, ys;
    for (const CloudLayer &layer : layers) {
        for (size_t i = 0; i < layer.count; i += stride) {
            double x = 0, y = 0;
            if (!project_point(layer, i, &x, &y)) continue;
            xs.push_back(x);
            ys.push_back(y);
        }
    }
    ViewBox box;
    if (xs.empty()) return box;
    const auto quantile = [](std::vector<double> &v, double q) {
        const size_t k = static_cast<size_t>(q * static_cast<double>(v.size() - 1));
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
        return v[k];
    };
    const double x0 = quantile(xs, 0.01), x1 = quantile(xs, 0.99);
    const double y0 = quantile(ys, 0.01), y1 = quantile(ys, 0.99);
    box.cx = 0.5 * (x0 + x1);
    box.cy = 0.5 * (y0 + y1);
    box.half = std::max(0.55 * std::max(x1 - x0, y1 - y0), 1e-3);
    return box;
}

Image render_top_view(const TopViewFigure &figure, const ViewBox &view) {
    const int n = std::max<int>(1, static_cast<int>(figure.panels.size()));
    const int columns = figure.columns > 0 ? std::min(figure.columns, n) : n;
    const int rows = (n + columns - 1) / columns;
    const int size = std::max(figure.panel_size, 64);
    const int line = Image::text_height(kTextScale) + 10;
    const int row_height = size + kGap + line + 4; // a row of panels, then the next row's titles
    const int panels_top = kMargin + line + 4;
    const int legend_top = panels_top + (rows - 1) * row_height + size + 16;
    const int width = 2 * kMargin + columns * size + (columns - 1) * kGap;
    const int height = legend_top + line + static_cast<int>(figure.notes.size()) * line + kMargin;
    Image img(width, height, kWhite);

    for (size_t i = 0; i < figure.panels.size(); ++i) {
        const int column = static_cast<int>(i) % columns, row = static_cast<int>(i) / columns;
        const TopViewPanel &panel = figure.panels[i];
        draw_panel(img, kMargin + column * (size + kGap), panels_top + row * row_height, size, panel,
                   panel.has_view ? panel.view : view);
    }
    int x = kMargin;
    for (const auto &entry : figure.legend) {
        img.fill_rect(x, legend_top, 14, 14, entry.second);
        img.draw_text(x + 22, legend_top, entry.first, kText, kTextScale);
        x += 22 + Image::text_width(entry.first, kTextScale) + 30;
    }
    int y = legend_top + line;
    for (const std::string &note : figure.notes) {
        img.draw_text(kMargin, y, note, kText, kTextScale);
        y += line;
    }
    return img;
}

} // namespace kissm_cli
