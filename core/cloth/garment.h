#pragma once
// [SECTION] Procedural garments for the cloth technique: meshes with uv over [0, 1]², unit
// normals, tangents along +u (the pattern's x, the weft or course direction), triangles
// counter-clockwise seen from the normal's side.
//   curtain  a hanging sheet, 2 wide and 2 high, in the xz plane facing −y, with `folds` vertical
//            folds of depth `depth` (deeper towards the hem): y = depth (0.6 + 0.2 (1 − z)) sin(π folds (x + 1)).
//            u runs along x (by arc length, so the pattern is not stretched in the folds), v up.
//   sleeve   a tube of radius 0.35 around an arc bent by `bend` radians over its length 2 (an
//            elbow); u around the tube, v along it.
#include "core/mesh.h"

#include <string>

namespace mesolab::cloth {

TriMesh make_curtain(int folds, float depth, int resolution);
TriMesh make_sleeve(float bend, int resolution);
// "curtain" or "sleeve" at its defaults; InputError naming cloth.garment otherwise.
TriMesh make_garment(const std::string& name, int resolution);
}  // namespace mesolab::cloth
