// SPDX-License-Identifier: MIT
// An RGB image with a few drawing primitives and a built-in 5x7 bitmap font (upper-case letters, digits
// and some punctuation; lower-case letters are drawn as upper-case, unknown characters as blanks).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace kissm_cli {

struct Rgb {
    uint8_t r, g, b;
};

class Image {
public:
    Image(int width, int height, Rgb fill);

    int width() const { return width_; }
    int height() const { return height_; }
    const uint8_t *data() const { return pixels_.data(); }

    Rgb get(int x, int y) const;
    void set(int x, int y, Rgb color); // ignores pixels outside the image
    void fill_rect(int x, int y, int w, int h, Rgb color);
    void outline_rect(int x, int y, int w, int h, Rgb color);
    void hline(int x0, int x1, int y, Rgb color);
    void vline(int x, int y0, int y1, Rgb color);
    // Text with its top-left corner at (x, y); each font pixel becomes scale x scale pixels.
    void draw_text(int x, int y, const std::string &text, Rgb color, int scale);
    static int text_width(const std::string &text, int scale);
    static int text_height(int scale) { return 7 * scale; }

private:
    int width_, height_;
    std::vector<uint8_t> pixels_;
};

} // namespace kissm_cli
