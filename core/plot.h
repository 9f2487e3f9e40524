#pragma once
// Small plotting for `mesolab sweep`: error against time as an RGB image (written as PNG by the
// caller), with axes, ticks, tick labels, axis titles, a title, a legend and point labels, drawn
// with a built-in bitmap font (no third-party code).
#include "core/image.h"
#include <string>
#include <vector>

namespace mesolab {

struct PlotSeries {
    std::string label;
    std::vector<double> x, y;
    std::vector<std::string> point_labels;  // optional, one per point (e.g. the knob value)
};

struct PlotSpec {
    std::string title, xlabel, ylabel;
    bool log_x = true, log_y = true;  // non-positive values are dropped on log axes
    std::vector<PlotSeries> series;
};

// Render to a linear RGB image (white background) of the given size (an empty image if either is
// <= 0). Text and marks scale with min(width, height) / 300. NaN/Inf values (and non-positive
// ones on log axes) are dropped; a series' line joins its remaining points in the given order.
Image render_plot(const PlotSpec& spec, int width = 900, int height = 600);

// Draw ASCII text (5x7 glyphs scaled by `scale`) into a 3- or 4-channel image; (x, y) is the
// top-left corner in pixels; glyphs are 7*scale pixels tall and advance 6*scale pixels. Characters
// outside printable ASCII draw as '?' (one per UTF-8 character). Pixels outside the image are
// clipped; on a 4-channel image drawn pixels get alpha 1. text_width is the inked width,
// (6 * characters - 1) * scale.
void draw_text(Image& img, int x, int y, const std::string& text, float r, float g, float b, int scale = 1);
int text_width(const std::string& text, int scale = 1);
}  // namespace mesolab
