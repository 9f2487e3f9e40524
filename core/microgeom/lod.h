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

// [SECTION] The truth's surface (core/truth/truth.h)
// The heightfield as the triangles through its texel centres: the piecewise-linear surface that
// takes texel (x, y)'s height at its centre, (c, r) = (x, y) in the shading's texel coordinates
// (c = u W tiling - 0.5, r = (1 - v) H tiling - 0.5), with each cell split along the diagonal the
// base's own triangles use (from low (u, v) to high (u, v)), tiled `tiling` times over (u, v)
// (every field wraps there, as on the geometry level of detail).
float height_through_centres(const Heightfield& hf, float c, float r);

// Segments along u for truth_surface: two per texel of the tiled field (so that texel centres
// are vertices and each cell's diagonal is an edge of the finer triangles, which then represent the
// surface through the centres exactly on a grid base), never fewer than `base_resolution`; the
// sphere and the teapot twice as many (mesh.h). Capped at 16384 (*capped set when it was).
int truth_surface_resolution(Primitive base, int base_resolution, int field_width, int field_height, float tiling, bool* capped);
// Triangles truth_surface makes.
double truth_surface_triangles(Primitive base, int resolution);

// The base primitive (mesh.h) tessellated at `resolution` and displaced along its normals by
// height_through_centres, as `displace` does (mean height removed, heights in texels scaled by
// the texel's world length). On a plane, curvature_u / curvature_v (degrees across one tile of the
// field, + convex, - concave; §5) bend it into a cylinder along u, then along v, keeping lengths
// along the bend. No normals or tangents: the truth shades with the triangles' geometric normals.
TriMesh truth_surface(Primitive base, int resolution, float minor_ratio, const Heightfield& hf, float tiling, float curvature_u_deg,
                      float curvature_v_deg);
}  // namespace mesolab::microgeom
