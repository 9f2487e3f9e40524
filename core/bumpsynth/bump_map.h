#pragma once
// Existing bump maps in bump-map synthesis (Kautz, Heidrich, Seidel 2001, §7): their NDF, and their
// normals as an index texture into the look-up table, with noise added when zooming in.
//
// [SECTION] Sources (BumpNormals)
// Per-texel unit normals in the macro tangent frame (x along +u, y along +v, z the macro normal),
// row 0 at the top, texel (x, y) centred at uv = ((x + 0.5)/W, 1 - (y + 0.5)/H): the heightfield's
// convention (core/heightfield/heightfield.h), so a heightfield and its bump map line up.
//  - A heightfield (bumpsynth.ndf = heightfield: a procedural field or a height image, with the
//    same parameters as microgeom's, core/heightfield/params.h): Heightfield::normal, central
//    differences in texel units × height scale.
//  - A normal map (bumpsynth.ndf = normal_map): RGB = (x, y, z), `unsigned` encoding 2v - 1 (the
//    usual one: 8/16-bit images, v in [0, 1]) or `signed` (stored as is: float images); y up (OpenGL,
//    Blender) or down (DirectX: y negated). Each is normalised. InputError naming the file and the
//    texel for fewer than 3 channels, a zero, non-finite or below-horizon (z < 0) normal.
// The NDF of a bump map is the histogram of these normals (Ndf::from_normals): every texel covers the
// same area of the uv square, i.e. the same projected area, so the histogram of (m_x, m_y) is the
// density D over the normal's disk that ndf.h tabulates (∫_disk D dx dy = 1, §3.1). A far-away
// surface shaded with this NDF is then the average of the bump map's near-field shading (§7).
//
// [SECTION] Index texture (IndexMap, §7)
// u(x, y) = Lut::index(m(x, y)): the uniform inputs whose look-up gives the texel's normal (the
// look-up table is built for uniform inputs, so no noise CDF is involved). Sampled like a GL_LINEAR,
// GL_REPEAT texture: bilinear between texel centres, wrapping. Interpolating inputs rather than normals
// is the paper's choice: between two texels the look-up gives normals the NDF holds (never one of
// zero density), a step where the two lie in different columns of the table.
//
// [SECTION] Detail when zooming in (index_inputs)
// k octaves: k = 0 the NDF alone (as with noise), k = 1 the bump map's own normals, and every further
// octave adds one octave of the fractal gradient noise of noise.h to the inputs, on a lattice of one
// cell per bump-map texel in the first detail octave (period W + c cells for channel c):
//     u_k = reflect(u + a Σ_{o < k-1} gain^o noise_o,c(uv) / √½),   reflect(r) ∈ [0, 1] folds r at 0 and 1
// with a = bumpsynth.index_noise (at most a / (1 - gain) away from u). Folding keeps the inputs inside
// the table without piling them up at its border. A fractional octave count blends the shading of k
// and k + 1 exactly as with noise inputs, so the bump map fades in from the NDF and the detail fades in
// over it without popping.
#include "core/bumpsynth/lut.h"
#include "core/bumpsynth/noise.h"
#include "core/math.h"
#include <string>
#include <vector>

namespace mesolab {
struct Heightfield;
}

namespace mesolab::bumpsynth {

struct BumpNormals {
    int width = 0, height = 0;
    std::vector<vec3> m;  // row-major, row 0 at the top
    const vec3& at(int x, int y) const { return m[size_t(y) * size_t(width) + size_t(x)]; }
};

BumpNormals normals_of(const Heightfield& f);

enum class NormalEncoding { unsigned_unit, signed_unit };  // 2v - 1, or as stored
struct NormalMapFormat {
    NormalEncoding encoding = NormalEncoding::unsigned_unit;
    bool y_down = false;  // DirectX convention
};
// Decodes an image (`where` names it in errors: the file).
BumpNormals decode_normal_map(const std::vector<float>& pixels, int width, int height, int channels, NormalMapFormat f,
                              const std::string& where);
// Reads and decodes a normal-map image (OpenImageIO).
BumpNormals read_normal_map(const std::string& path, NormalMapFormat f);

struct IndexMap {
    int width = 0, height = 0;
    std::vector<vec2> u;  // row-major, row 0 at the top
    vec2 at(int x, int y) const { return u[size_t(y) * size_t(width) + size_t(x)]; }
    vec2 bilinear(vec2 uv) const;  // GL_LINEAR + GL_REPEAT
};
IndexMap make_index_map(const BumpNormals& n, const Lut& lut);

// The detail noise: `noise.base_frequency` is the bump map's width (see above). The GPU computes
// the same bits from `octaves` and `scale` (gpu/bumpsynth/synthesis.glsl).
struct IndexDetail {
    NoiseParams noise;
    NoiseOctaves octaves;  // of noise
    float amplitude = 0.f;
    float scale = 0.f;     // amplitude / √½, the factor of the noise sum
};
IndexDetail index_detail(const IndexMap& map, const NoiseParams& n, float amplitude);

// Folds r into [0, 1] (period 2, mirror at 0 and 1).
float reflect_unit(float r);
// The inputs of k >= 1 octaves at uv (see above).
vec2 index_inputs(const IndexMap& map, const IndexDetail& d, vec2 uv, int k);
}  // namespace mesolab::bumpsynth
