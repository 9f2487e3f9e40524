#pragma once
// [SECTION] Stitch micro-geometry (Daubert et al. 2001, §4): yarns as implicit surfaces around
// cubic Bézier skeleton curves, polygonised by marching cubes.
//
// A stitch is one tile of a periodic pattern in the xy plane (z up, the fabric's normal), in
// units of yarn spacing: yarns (chains of cubic Bézier segments, each with a colour) repeat
// with the tile. The implicit surface of a yarn is a tube of radius `yarn_radius` around its
// skeleton: f(x) = min over skeletons of |x − skeleton| − r (a signed distance, negative inside;
// the union of the yarns is the minimum). The mesh covers copies × copies tiles (3 × 3: the
// pattern's centre tile with its neighbours, so that masking and holes at its edges are right),
// closed where the grid ends.
//
// Stitches (cloth.stitch):
//   knit     plain knit (jersey) loops, seen from the face: a row of interlocked loops per course
//   purl     the same loops seen from the back (purl bumps)
//   loops2   knit loops whose courses alternate between the two colours
//   weave    plain weave: warp and weft over one, under one
//   twill    2/1 twill: over two, under one, shifted by one thread per row (diagonal ribs)
#include "core/math.h"
#include "core/mesh.h"

#include <string>
#include <vector>

namespace mesolab::cloth {

struct Bezier {
    vec3 p[4];
    vec3 at(float t) const;
};

struct Yarn {
    std::vector<Bezier> segments;  // consecutive: segments[i].p[3] == segments[i + 1].p[0]
    vec3 color{0.8f};
};

struct StitchParams {
    std::string stitch = "knit";
    float yarn_radius = 0.12f;   // in units of the yarn spacing (the distance between neighbouring wales / threads)
    float loop_height = 1.0f;    // course height of knitted stitches, in units of the spacing
    vec3 color_a{0.75f, 0.12f, 0.10f}, color_b{0.90f, 0.85f, 0.70f};
};

// The stitch names cloth.stitch accepts.
const std::vector<std::string>& stitch_names();

struct StitchPattern {
    std::vector<Yarn> yarns;  // the tile's yarns, extended over the copies around it
    vec2 tile{1.f};           // the pattern's period in x and y
    float z_lo = 0.f, z_hi = 0.f;  // skeleton extent in z (the surface adds the radius)
    float radius = 0.f;
};

// The pattern over `copies` × `copies` tiles centred on tile [0, tile.x) × [0, tile.y).
// InputError naming cloth.stitch (an unknown stitch), cloth.yarn_radius or cloth.loop_height
// (outside (0, 0.5) and [0.5, 3]).
StitchPattern make_stitch(const StitchParams& p, int copies = 3);

struct StitchMesh {
    TriMesh mesh;
    std::vector<vec3> color;  // per vertex: the colour of the yarn it lies on
    vec2 tile{1.f};
    vec3 lo{0.f}, hi{0.f};    // the centre tile's box: [0, tile] in xy, the yarns' z extent
    int grid_points = 0;
};

// Marching cubes over the pattern's field at `cells_per_tile` grid cells per tile side (the
// same cell size in z). InputError naming cloth.stitch_resolution outside [8, 256].
StitchMesh build_stitch_mesh(const StitchPattern& pattern, int cells_per_tile);
}  // namespace mesolab::cloth
