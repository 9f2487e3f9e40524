#pragma once
// [SECTION] Heightfields: micro-geometry shared by the techniques.
// A heightfield is a grid of heights over a base surface, with a per-texel albedo. microgeom
// (Heidrich et al. 2000) lights it with precomputed visibility; bumpsynth (Kautz et al. 2001,
// bumpsynth.ndf = heightfield) takes the histogram of its normals as an NDF. This module builds
// the fields (procedural or from images), gives them an albedo (a procedural rule or an albedo
// map), and answers the queries every technique needs (heights, normals, bilinear look-ups).
// The parameters that describe a heightfield are declared once for every technique: params.h.
//
// Local frame: x along +u, y along +v, z = height (the base surface's normal). Texel (x, y),
// with y the image row from the TOP, has its centre at uv = ((x + 0.5)/W, 1 - (y + 0.5)/H) and at
// local position P(x, y) = ((x + 0.5) s, (H - y - 0.5) s, h(x, y)), s = texel size. The surface
// is the triangulated grid of texel centres: cell (x, y)-(x+1, y+1) is split into two triangles
// along the diagonal from (x, y) to (x+1, y+1) (image rows, so that diagonal runs from the cell's
// top-left to bottom-right). Periodic fields wrap cells across the borders; otherwise the
// surface ends at the outermost texel centres.
#include "core/image.h"
#include "core/math.h"
#include "core/sampling.h"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace mesolab {

struct Heightfield {
    int width = 0, height = 0;
    float texel_size = 1.f;     // world units per texel (s)
    bool periodic = true;
    std::vector<float> h;       // heights in world units (height scale applied), row-major, row 0 at the top
    std::vector<vec3> albedo;   // linear RGB per texel

    size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
    // Height with wrap-around (periodic) or clamping at the borders. Inline, with the wrap only
    // outside the field: precomputations call it several times per texel.
    float at(int x, int y) const {
        if (unsigned(x) < unsigned(width) && unsigned(y) < unsigned(height)) return h[index(x, y)];
        return at_outside(x, y);
    }
    // Local-frame position of texel (x, y)'s centre.
    vec3 position(int x, int y) const { return {(float(x) + 0.5f) * texel_size, (float(height - y) - 0.5f) * texel_size, at(x, y)}; }
    // Unit normal from central differences (one-sided at non-periodic borders), local frame.
    vec3 normal(int x, int y) const;
    float min_height() const;
    float max_height() const;

private:
    float at_outside(int x, int y) const;
};

// Bilinear, wrapping (periodic) or clamped look-up of a per-texel quantity (heights, albedo, any
// w x h row-major texture laid out like a heightfield) at continuous texel coordinates (c, r)
// (texel (x, y) at (x, y)). Inline: the scattering and shading loops call it per texel.
template <class T>
inline T sample_bilinear(const T* tex, int w, int h, bool periodic, float c, float r) {
    const Edge e = periodic ? Edge::Wrap : Edge::Clamp;
    return BilinearTaps(c, r, w, h, e, e).blend(tex, w);
}
template <class T>
inline T sample_bilinear(const std::vector<T>& tex, int w, int h, bool periodic, float c, float r) {
    return sample_bilinear(tex.data(), w, h, periodic, c, r);
}

// [SECTION] Procedural fields
// Parameters of the procedural fields. Heights come out in units of texels before `height_scale`
// (world height = value * height_scale * texel_size), so the shapes keep their slopes at any
// resolution. Triangles, bricks and bumps are the fields of Heidrich et al.'s Table 1 (their
// Fig. 2 shows the triangles). Every field is a function of the texel centre's position in the
// unit tile, with period 1, so it tiles seamlessly at any resolution in [8, 4096]:
//   triangles  Heidrich et al.'s Fig. 2 ridges: a symmetric triangle wave along x, 4 periods
//              across, constant along y, peaks at half the period (45-degree faces at height_scale
//              1); albedo red (0.8, 0.08, 0.08) exactly where the central difference dh/dx > 0
//              (normal.x < 0), white 0.8 elsewhere (`albedo` is not used).
//   bricks     running bond, 4 courses of 2 bricks (2:1 aspect), mortar joints 1/8 of the course
//              height wide at height 0, bricks raised by 1/6 of the course height with a bevel of
//              slope 2; albedo: bricks albedo * (0.75, 0.3, 0.2) / 0.8 with a per-brick +-10%
//              variation, mortar (0.6, 0.6, 0.58).
//   bumps      4x4 bumps r0 cos^2(pi/2 d/r0), r0 = 0.4 of the cell (height = radius).
//   vgrooves   4 V grooves along y, each as wide as its period, bottom at height 0, walls of
//              slope tan(90 - vgroove_angle/2) (so the depth follows from the angle).
//   gaussian   periodic Gaussian random surface: white noise (std::mt19937 + Box-Muller: the same
//              heights on every platform for a seed) convolved periodically with a Gaussian of
//              std dev `correlation` texels (truncated at 4 sigma), mean 0, scaled so that the RMS
//              slope sqrt(<|grad h|^2>) from central differences in texel units (Beckmann m)
//              is `rms_slope` exactly.
//   flat       h = 0.
// Out-of-range values are InputErrors naming <group>.<key> (microgeom.<key> by default).
struct ProceduralParams {
    std::string name;            // triangles | bricks | bumps | vgrooves | gaussian | flat
    int resolution = 64;         // width = height = resolution
    float height_scale = 1.f;
    float texel_size = 1.f;
    bool periodic = true;
    float vgroove_angle = 90.f;  // vgrooves: opening angle of the V, degrees, in [1, 179]
    float rms_slope = 0.5f;      // gaussian: RMS slope sqrt(<|grad h|^2>) (dimensionless, >= 0)
    float correlation = 4.f;     // gaussian: correlation length, texels, in (0, min(resolution, 64)]
    uint32_t seed = 1;           // gaussian: seed (deterministic for a seed)
    vec3 albedo{0.8f};           // base albedo; the rules above modulate it
    std::string group = "microgeom";  // the parameter group named in errors (every technique reads the same keys)
};

// The known procedural names.
const std::vector<std::string>& procedural_names();
// Throws InputError naming <group>.heightfield for an unknown name (with a suggestion).
Heightfield make_procedural(const ProceduralParams& p);

// [SECTION] Heightfields from images
// Heightfield from an image (OpenImageIO: 8/16-bit, float EXR/TIFF; the first channel), heights
// = value * height_scale * texel_size (8/16-bit data normalised to [0, 1], not sRGB-decoded).
// NaN/Inf texels are an InputError naming the file and the texel; so are a missing or unreadable
// file and sizes outside 2..4096 texels a side. Albedo is set to `albedo` everywhere.
Heightfield load_heightfield(const std::string& path, float height_scale, float texel_size, bool periodic, vec3 albedo);

// [SECTION] Albedo maps
// Per-texel albedo from an image (8/16-bit sRGB or float linear; grey images give grey albedo),
// resampled bilinearly with wrap-around at the texel centres onto the heightfield's texels, times
// `tint`, clamped to 1. A negative or non-finite result is an InputError naming the file and
// `key` (the parameter that named it, e.g. microgeom.albedo_map).
void apply_albedo_map(Heightfield& hf, const std::string& path, vec3 tint, const std::string& key);
}  // namespace mesolab
