#pragma once
// [SECTION] The truth of cloth (core/truth/truth.h): the stitch's yarns themselves, one periodic tile
// of them instanced over the garment along its pattern tiles, path traced with the yarn's BRDF.
//
// The tile: the yarn tubes of the stitch (stitch.h) polygonised by marching cubes at
// kTruthStitchResolution cells per tile side whatever cloth.stitch_resolution says, keeping the
// triangles whose centroid lies in the centre tile [0, tile.x) x [0, tile.y): the field is periodic
// and the grid aligned with the tiles, so the copies meet edge to edge. Each vertex keeps the colour
// of its yarn, the albedo of the Lambertian yarn the acquisition assumes (acquire.h).
//
// The garment: pattern point (x, y, z) of tile (i, j) sits at uv = ((i + x / tile.x) / repeat,
// (j + y / tile.y) / repeat) on the drawn garment (the uv the real-time path multiplies by
// cloth.repeat), raised along the garment's normal by (z - z_mid) s, z_mid the middle of the yarns'
// skeletons and s the garment's mean world length per pattern unit (sqrt(world area / uv area) /
// (repeat sqrt(tile.x tile.y))): x along the garment's tangent (+u), y along +v, z its normal, as the
// acquisition's frame. Normals follow the same frame. Light passes through the holes between yarns
// to whatever lies behind. A pixel that sees the fabric stands for its whole square (the camera's
// rays spread over it: TruthMaterial::pixel_filter), as the real-time mip levels filter the
// stitches a pixel covers.
#include "core/cloth/stitch.h"
#include "core/mesh.h"

#include <vector>

namespace mesolab::cloth {

inline constexpr int kTruthStitchResolution = 48;

struct TruthFabric {
    TriMesh mesh;
    std::vector<vec3> color;  // per vertex: the yarn's albedo
    float half_thickness = 0.f;  // the largest |z - z_mid| of a vertex, in the mesh's units
    vec2 tile{1.f};              // the tile's period in pattern units (truth_stitch_tile)
};

// The centre tile's yarns (see above); mesh in pattern units, half_thickness about z_mid.
TruthFabric truth_stitch_tile(const StitchParams& p);

// The tile instanced over `base` (object space, uv over [0, 1]^2, normals and tangents) repeat x
// repeat times (see above).
TruthFabric truth_fabric(const TruthFabric& tile, const TriMesh& base, int repeat);

// Triangles of truth_fabric: the tile's times repeat².
inline double truth_fabric_triangles(const TruthFabric& tile, int repeat) { return double(tile.mesh.triangle_count()) * double(repeat) * double(repeat); }
}  // namespace mesolab::cloth
