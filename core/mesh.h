#pragma once
// Triangle meshes: procedural primitives (with a (u,v) parametrisation in [0,1]^2 so that
// camera.mode=texture can render texture space 1:1) and mesh files read with OpenMesh.
#include "core/math.h"
#include <cstdint>
#include <string>
#include <memory>
#include <vector>

namespace mesolab {

// Indexed triangle mesh, structure of arrays. All per-vertex arrays have the same length.
struct TriMesh {
    std::vector<vec3> position;      // object space
    std::vector<vec3> normal;        // unit shading normals
    std::vector<vec3> tangent;       // unit dP/du direction (orthogonalised against normal)
    std::vector<vec2> uv;            // texture coordinates; [0,1]^2 for procedural shapes
    std::vector<uint32_t> index;     // 3 per triangle, counter-clockwise seen from outside
    bool has_uv = false;             // false for mesh files without texture coordinates

    size_t vertex_count() const { return position.size(); }
    size_t triangle_count() const { return index.size() / 3; }
};

enum class Primitive { Sphere, Plane, Torus, Cylinder, Teapot };

// Procedural primitives of unit size, tessellated with `resolution` segments along u
// (and max(2, resolution/2) along v for the sphere, resolution along v otherwise; the teapot
// below has its own layout), 3 <= resolution <= 16384 (InputError naming geometry.resolution
// otherwise; a torus also needs 0 < minor_ratio < 1). Vertices lie on a (u, v) grid whose last
// column (and, on the torus, last row) repeats the first with u=1 (v=1), so uv is continuous
// inside every triangle and the triangles tile [0,1]^2 exactly once. Normals are analytic;
// tangents are the dP/du direction.
//  Sphere:   radius 1, centre 0; u = azimuth/(2pi) from +x, v = 1 - polar angle/pi (polar angle
//            from +z): v=0 at the south pole (-z), v=1 at the north pole (+z). In the two pole
//            rows one triangle per cell has zero surface area (two corners are the pole) but
//            keeps its uv area; pole vertices take the tangent of their u column.
//  Plane:    [-1,1]^2 in the xy plane, normal +z; u along +x, v along +y.
//  Torus:    major radius 1, minor radius `minor_ratio` (0<r<1), around the z axis;
//            u = azimuth around z, v = angle around the tube / 2pi (v=0 on the outer equator,
//            increasing towards +z).
//  Cylinder: radius 1, height 2 along z (no caps); u = azimuth, v = (z+1)/2.
//  Teapot:   the Utah teapot from Newell's 32 bicubic Bezier patches (306 control points,
//            z up; patches 0-3 rim, 4-11 body, 12-15 handle, 16-19 spout, 20-27 lid, 28-31
//            bottom), each tessellated on an n x n grid, n = max(2, resolution/8) segments per
//            patch side: 32 * n^2 * 2 triangles, e.g. resolution 64 -> 4096 triangles and 128 ->
//            16384 (close to the ~17,000 of the paper's teapot). Centred and scaled so that the
//            surface's bounding box is centred at the origin with largest half-extent 1 (along x,
//            handle to spout tip; the same map at every resolution, so coarse tessellations
//            reach slightly less far). Vertices are per patch, not welded (border vertices of
//            neighbouring patches coincide): patch by patch, each patch's (n+1)^2 grid row by
//            row along t, s fastest (s runs along a row of 4 control points, t across the rows).
//            Triangles are counter-clockwise in (s, t) and dP/ds x dP/dt points outwards: a patch
//            whose normal points towards the box centre on the whole would have its s reversed
//            (none does in Newell's table read this way). The first row of the knob's patches
//            20-23 (the top) and of the bottom's 28-31 (the bottom centre) collapses to a point,
//            so one triangle per cell of those rows has zero area; there dP/ds vanishes and the
//            normal and tangent are taken a step of 1e-5 of the way towards the patch centre
//            (straight up / down; the tangent of their s column). Normals are analytic, tangents the dP/ds direction (= +u).
//            uv is an atlas: patch i fills cell (i % 8, i / 8) of an 8 x 4 grid over [0,1]^2,
//            (s, t) mapped linearly into the cell inset by 2% of its size on each side, so every
//            triangle's uv lies in one cell, the cells do not touch, and the triangles cover
//            0.96^2 of the square (texture mode leaves the gaps between cells empty).
TriMesh make_primitive(Primitive p, int resolution, float minor_ratio = 0.35f);

// The primitive a geometry.type names: "sphere", "plane", "torus", "cylinder" or "teapot";
// InputError naming geometry.type for anything else (including "mesh", which is no primitive).
Primitive primitive_named(const std::string& type);

// Read a mesh file (OBJ, OFF, PLY, STL, OM) with OpenMesh. Triangulates polygons (fans);
// computes area-weighted vertex normals when the file has none (or a zero one); keeps texture
// coordinates when present, per face corner where the file gives them per corner (OBJ "vt"),
// splitting vertices along uv seams; tangents are the accumulated per-triangle dP/du where uv
// exist, otherwise an arbitrary unit vector perpendicular to the normal.
// Throws InputError starting with the path: "no such file", "could not be read as a mesh (...)",
// "mesh has no triangles", "vertex N has a non-finite coordinate" (N counts from 0).
TriMesh load_mesh(const std::string& path);

// Apply a uniform scale then a translation to positions (normals/tangents unchanged).
void transform_mesh(TriMesh& m, float scale, vec3 translation);

// Axis-aligned bounds of positions.
struct Bounds { vec3 lo{0.f}, hi{0.f}; };
Bounds bounds(const TriMesh& m);
// The same for a shared, immutable mesh, walked once: the answer is kept while the mesh lives
// (keyed by its owner and address, so a new mesh at a freed address is walked anew). Frames ask
// for every drawn mesh's bounds each frame, and a displaced level of detail has millions of
// vertices. Thread-safe.
Bounds bounds(const std::shared_ptr<const TriMesh>& m);
}  // namespace mesolab
