#pragma once
// [SECTION] Shading with a fitted fabric (Daubert et al. 2001, §6 and §6.1).
// A surface point of a garment is given by its pattern coordinates (uv times the repeat count:
// one unit per tile) and its footprint (how many tiles one pixel covers); light and view
// directions are given in the pattern's frame (the garment's interpolated normal as z, its
// tangent as x). The BRDF array entry under the point is evaluated in the entry's own frame:
// f_r = T(v̂) ∘ f_L(l̂, v̂), and the reflected radiance is f_r cos θ̂_l E (the paper's
// foreshortening, in the entry's frame); the table's alpha says whether a hole shows the
// background.
//
// Mip level: λ = log2(footprint × res) + bias, the number of sample points a pixel covers, as a
// power of two (0: a pixel per point or less). `off` always reads level 0 (aliasing when a
// pixel covers many points), `nearest` reads the level nearest λ, `blend` mixes the two levels
// around λ (the paper's two-pass blending).
#include "core/cloth/pyramid.h"

#include <string>

namespace mesolab::cloth {

enum class MipMode { Off, Nearest, Blend };
// "off", "nearest", "blend"; InputError naming cloth.mip otherwise.
MipMode mip_mode_named(const std::string& s);

struct ClothSample {
    dvec3 radiance{0.0};  // reflected radiance for the light's irradiance E
    double alpha = 1.0;
    double level = 0.0;   // the level read (fractional when blending)
    int index = 0;        // the entry read at the finer level: level offset + row-major index
};

// `uv`: pattern coordinates (wrapped into [0, 1) per tile); `footprint`: tiles per pixel (> 0);
// l, v: unit directions in the pattern frame; E: the light's irradiance, per channel.
ClothSample shade(const BrdfPyramid& p, dvec2 uv, double footprint, MipMode mode, double bias, dvec3 l, dvec3 v, dvec3 E);
}  // namespace mesolab::cloth
