#pragma once
// Meshes the translucency tests share.
#include "core/mesh.h"
#include "core/translucency/mesh_prep.h"

namespace mesolab::translucency::test {
// The UV sphere of `resolution` segments, prepared as translucency.mesh prepares it (no decimation).
inline PreparedMesh prepared_sphere(int resolution) {
    const TriMesh s = make_primitive(Primitive::Sphere, resolution);
    return prepare_mesh(s.position, s.index, 0);
}
}  // namespace mesolab::translucency::test
