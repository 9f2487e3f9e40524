#pragma once
// Levels of detail of a micro-geometry (Heidrich et al. 2000, §1 and §6, Fig. 9): the same
// heightfield as
//   geometry  displaced geometry: the base surface re-tessellated at one vertex per texel and
//             moved along its normal by the height (minus the field's mean height, so the
//             average surface stays where the base is); shaded exactly like the bump level
//             (macro frame from the base, micro normal, S_i shadows and scattering from the
//             texture), so it differs from `bump` only by parallax, occlusion and silhouettes;
//   bump      the base surface with the heightfield as a bump map (shading.cpp);
//   brdf      the base surface with the heightfield's simulated BRDF (goniometer.h), no texture.
#include "core/heightfield/heightfield.h"
#include "core/mesh.h"
#include <string>

namespace mesolab::microgeom {

// Segments (along u) a procedural base needs for one vertex per texel of a heightfield tiled
// `tiling` times, never fewer than `base_resolution`; capped at `cap` (*capped set when it was).
// (The teapot's atlas cells leave 4% of uv between patches, so it gets slightly more than one.)
int displacement_resolution(const std::string& type, int base_resolution, int field_width, int field_height, float tiling, int cap, bool* capped);

// Displace `base` (object space, with uv) along its normals by the heightfield tiled `tiling`
// times over (u, v): offset = (h(u,v) - mean h) / texel_size * texel length, where the texel
// length at a vertex is sqrt(world area / uv area) of its triangles divided by (width * tiling)
// (the height is in texels, so slopes are kept). Heights are looked up bilinearly with the
// shading's texel convention (c = u W tiling - 0.5, r = (1 - v) H tiling - 0.5, wrapping).
// Normals and tangents stay those of the base: shading takes the micro normal from the field.
// Vertices are displaced independently: where a base has separate vertices at one position with
// different uvs (the teapot's patch borders), cracks can open.
TriMesh displace(const TriMesh& base, const Heightfield& hf, float tiling);
}  // namespace mesolab::microgeom
