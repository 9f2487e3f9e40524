#pragma once
// [SECTION] Marching cubes: the iso-surface {f = iso} of a scalar field sampled on a regular
// grid, as a closed triangle mesh where the field is above iso on the grid's boundary.
//
// Each cube's surface is built from the segments it cuts on its six faces (no case table): on
// a face whose corners alternate inside/outside, the bilinear interpolant's saddle value decides
// whether the inside corners connect (the asymptotic decider, Nielson & Hamann 1991), computed
// from the face's corners in grid order so that both cubes sharing the face decide alike. The
// segments, oriented so that the inside lies to their left seen from outside the surface, chain
// into closed loops through the cube's edge crossings; a loop of three is a triangle, a longer
// one a fan around a vertex at its centroid (a fan from a loop vertex could draw a diagonal
// that the neighbouring cube draws too). A vertex sits at the linear crossing on each grid edge
// and is shared by the cubes around that edge, so the mesh is watertight and consistently oriented by construction: every edge is used
// by exactly two triangles, once in each direction.
#include "core/math.h"
#include "core/mesh.h"

#include <functional>
#include <vector>

namespace mesolab::cloth {

// Samples of a field on n.x × n.y × n.z points (x fastest), point (i, j, k) at origin + h (i, j, k).
struct ScalarGrid {
    glm::ivec3 n{0};
    vec3 origin{0.f};
    float h = 1.f;
    std::vector<float> v;
    size_t at(int i, int j, int k) const { return (size_t(k) * size_t(n.y) + size_t(j)) * size_t(n.x) + size_t(i); }
    float value(int i, int j, int k) const { return v[at(i, j, k)]; }
    vec3 point(int i, int j, int k) const { return origin + h * vec3(float(i), float(j), float(k)); }
};

// Inside: value < iso. Triangles are counter-clockwise seen from outside (the field's increasing
// side); normals are the field's normalised gradient (central differences), tangents an
// arbitrary unit vector perpendicular to it; no uv.
TriMesh marching_cubes(const ScalarGrid& g, float iso = 0.f);
}  // namespace mesolab::cloth
