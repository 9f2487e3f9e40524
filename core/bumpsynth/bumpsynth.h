#pragma once
// Technique `bumpsynth`: real-time bump map synthesis from a normal density function (Kautz,
// Heidrich, Seidel 2001). Stages (each per object, shared by objects with equal keys):
//   bumpsynth.bump_normals   the normals of a bump map (ndf = normal_map | heightfield; bump_map.h)
//   bumpsynth.ndf            the tabulated NDF (ndf.h) from bumpsynth.ndf and its source keys
//   bumpsynth.lut            the normal look-up table L(r1, r2) for uniform inputs (lut.h)
//   bumpsynth.index_map      §7: the bump map's normals as inputs of the look-up table (index_map on)
//   bumpsynth.noise_cdf      G_k of the fractal noise for k = 1..octaves_max (noise.h; not with index_map)
//   bumpsynth.noise_texture  the paper's mip-mapped noise texture (noise = texture only)
//   bumpsynth.masking        the Smith table of the NDF (masking on only)
//   bumpsynth.albedo         the albedo map
//   bumpsynth.truth_ndf      the truth's NDF, table and Smith table at 512^2 cells (truth.cpp)
// A frame shades every pixel with brdf.h's synthesis at o(d) octaves (d: eye distance; all
// octaves in camera.mode=texture). AOVs: radiance, normal (the microfacet normal in the surface's
// tangent frame, blended while an octave fades in), octaves (o at the pixel).
// Sweep metric: bumpsynth.ndf_histogram, the synthesised normals' histogram against the NDF (sweep_metric.h).
#include "core/basic/basic.h"
#include "core/bumpsynth/bump_map.h"
#include "core/bumpsynth/lut.h"
#include "core/bumpsynth/ndf.h"
#include "core/bumpsynth/noise.h"
#include "core/bumpsynth/brdf.h"
#include "core/stage.h"

namespace mesolab::bumpsynth {

// The bump map an object's material names (ndf = normal_map | heightfield; bump_map.h).
BumpNormals bump_normals_from_material(const Scene& s, const ParamTable& m);
// The NDF an object's material describes (InputError naming the key for bad values or files). For a
// bump-map source, `normals` are its normals when already read (else they are read here).
// `resolution`: cells per side (0: bumpsynth.ndf_resolution; the truth tabulates at its own).
Ndf ndf_from_material(const Scene& s, const ParamTable& m, const BumpNormals* normals = nullptr, int resolution = 0);
NoiseParams noise_from_material(const ParamTable& m);
ShadingModel shading_from_material(const ParamTable& m);

// The synthesis of object `object` from an evaluation that ran the frame stages (null members
// where a stage was not needed: noise_texture with procedural noise, smith without masking).
Synthesis synthesis_for(const Scene& s, const Evaluation& ev, int object);

// The octave count at a world point seen from `eye` (all octaves in texture mode).
float pixel_octaves(const Synthesis& syn, bool texture_mode, vec3 eye, vec3 p);
}  // namespace mesolab::bumpsynth
