#pragma once
// [SECTION] truth_error as pictures: the colours the window's Truth view shows and the figure
// `capture --aov truth_error` keeps beside the EXR (a legend below, drawn with the plots' text).
#include "core/image.h"
#include "core/render.h"

namespace mesolab {

// truth_error (RGB) as display colours: the mean over channels of (error / scale), clamped to
// [-1, 1], on a blue - white - red ramp (linear RGB). Background pixels (where `truth` shows no
// object) are dark grey.
Image error_colors(const Image& error, const Frame& truth, float scale);
// A scale for error_colors: the 99th percentile of |error| (mean over channels) on the object's
// pixels, rounded up to 1, 2 or 5 times a power of ten; 1 when there are none.
float error_scale(const Image& error, const Frame& truth);
// The error as a picture to keep: error_colors at error_scale over the frame, and below it a strip
// with the legend (the ramp from -scale to +scale and what it shows), in linear RGB (write it with
// write_png_srgb, as the plots). Throws std::runtime_error when the plot font is missing.
Image error_figure(const Image& error, const Frame& truth);
}  // namespace mesolab
