#pragma once
// Small plotting for `mesolab sweep`: error against time as an RGB image (written as PNG by the
// caller) or as SVG, with axes, ticks, tick labels, axis titles, a title, a legend and point
// labels. Text is UTF-8 (Greek letters, units such as µs, m², °) in the plot font, DejaVu Sans
// through FreeType (app/plot_text.h). Without the font file (Debian package fonts-dejavu-core),
// rendering a plot throws std::runtime_error naming the file and the package: there is no
// fallback font, since one without these glyphs would put placeholders in the labels.
#include "core/image.h"
#include <string>
#include <vector>

namespace mesolab {

struct PlotSeries {
    std::string label;
    std::vector<double> x, y;
    std::vector<std::string> point_labels;  // optional, one per point (e.g. the knob value)
    bool line = true;                       // false: markers only (a scatter)
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
// The same chart as SVG (UTF-8): the same layout in pixel units, lines as vector paths, text as
// <text> in DejaVu Sans (drawn with the viewer's copy of the font and its hinting, so widths may
// differ from the PNG's by a pixel or so).
std::string render_plot_svg(const PlotSpec& spec, int width = 900, int height = 600);

// Draw UTF-8 text, anti-aliased, into a 1- to 4-channel image; (x, y) is the top-left corner of
// the text's box, text_width(text, scale) x text_height(scale) pixels: the first glyph's ink starts
// at x, the baseline is text_height's ascent below y. `scale` is the plot's text scale, an em size
// of text_em_px(scale) = 9 * scale pixels (scale clamped to [1, 100]). Coverage is mixed with the
// pixel in sRGB-encoded values; pixels outside the image are clipped; on a 4-channel image the
// alpha of inked pixels goes towards 1 with their coverage. Characters the font lacks draw as its
// missing-glyph box, malformed UTF-8 as U+FFFD. Throws std::runtime_error when the font is missing.
void draw_text(Image& img, int x, int y, const std::string& text, float r, float g, float b, int scale = 1);
// Width of the text's box: the inked extent of its glyphs spaced by their advances and kerning
// (within a pixel of the ink draw_text puts down); 0 for "".
int text_width(const std::string& text, int scale = 1);
// Height of a line of text: the font's ascenders and descenders at text_em_px(scale).
int text_height(int scale = 1);
int text_em_px(int scale);
}  // namespace mesolab
