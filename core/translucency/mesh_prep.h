#pragma once
// [SECTION] Mesh preparation for translucency (Lensch et al. 2002, §5: "simplified ... to
// triangles of similar size"). The global response has one hat basis function per vertex, so
// the mesh must be one connected surface without duplicated vertices: a scanned mesh read from a
// file (or a primitive, whose seams repeat vertices) is repaired, then simplified.
//
//   weld        vertices closer than 1e-6 of the bounding box's diagonal become one
//   clean       triangles with a repeated corner, no area, a non-finite corner or the same
//               corners as another triangle are removed
//   manifold    a triangle that would make an edge or a vertex non-manifold keeps its own copies
//               of the offending corners (it is kept, detached along that edge)
//   decimate    OpenMesh's decimater down to `target_vertices` (0 = keep): quadric error as the
//               priority; collapses that flip a normal (> 60°) or leave a triangle with an aspect
//               ratio worse than 1:6 are refused, so triangles stay well shaped
//   renumber    vertices in the order of a 3D Hilbert curve through their positions, so that
//               vertices near each other on the surface get nearby numbers: a row of the
//               factors (the vertices within the dipole's reach) is then mostly runs of
//               consecutive columns, and the product reads E and adds to B in cache lines it has
//               just used (bunny at 10,000 vertices: mean run 1.6 → 13 columns)
// Holes stay holes (their boundary edges are counted). Everything repaired is counted and said
// in `warnings`.
#include "core/math.h"

#include <cstdint>
#include <string>
#include <vector>

namespace mesolab::translucency {

// Edges where the surface turns by more than this (a box's, a tetrahedron's) keep their two
// faces' normals apart: averaged across them, a flat face's interpolated normal would lean away
// from it by up to half the turn (a 2 x 2 x 0.4 box: 8-24° at its corners), and a light grazing
// the face would see its far part from behind (cos θ ≤ 0, no light). Smooth meshes turn by
// less: a 16-segment sphere 23°, an 8-segment one 45°, an icosahedron 42°.
inline constexpr float kCreaseDegrees = 60.f;

struct PreparedMesh {
    std::vector<vec3> position;
    std::vector<vec3> normal;      // area-weighted vertex normals
    // 3 per triangle: the area-weighted normal of the triangles around the corner's vertex that
    // turn less than kCreaseDegrees from this one (the shading and illumination normal).
    std::vector<vec3> corner_normal;
    std::vector<uint32_t> index;   // 3 per triangle, counter-clockwise from outside
    std::vector<vec2> corner_uv;   // 3 per triangle when the input had texture coordinates (else empty)

    int welded_vertices = 0;       // vertices merged into another
    int removed_triangles = 0;     // degenerate or duplicate
    int detached_triangles = 0;    // kept with their own copies of non-manifold corners
    int boundary_edges = 0;        // edges of one triangle only (holes, open borders)
    int input_vertices = 0;        // after welding, before decimation
    std::vector<std::string> warnings;

    size_t vertex_count() const { return position.size(); }
    size_t triangle_count() const { return index.size() / 3; }
};

// InputError naming translucency.vertices for a negative target, or the mesh when no triangle
// is left after cleaning. A target above the vertex count keeps every vertex.
// `uv` (one per input vertex, optional) gives corner_uv: the decimated mesh's vertices are input
// vertices, and a corner takes its vertex's coordinates (at a welded seam, those of the side the
// triangle lies on).
PreparedMesh prepare_mesh(const std::vector<vec3>& position, const std::vector<uint32_t>& index, int target_vertices,
                          const std::vector<vec2>* uv = nullptr);

// PreparedMesh::corner_normal for a mesh (positions, 3 indices per triangle).
std::vector<vec3> corner_normals(const std::vector<vec3>& position, const std::vector<uint32_t>& index);
}  // namespace mesolab::translucency
