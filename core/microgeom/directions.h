#pragma once
// Direction sets over the whole sphere (Heidrich et al. 2000, §3-§5): N nearly uniformly
// distributed unit directions (a spherical Fibonacci lattice: deterministic for N), their
// spherical triangulation (the convex hull of the points, every triangle counter-clockwise seen
// from outside), and per direction its share of the sphere (a third of the solid angle of each
// adjacent spherical triangle: the triangle-fan area of §5; the shares sum to 4 pi).
#include "core/math.h"
#include <array>
#include <vector>

namespace mesolab::microgeom {

struct DirectionSet {
    std::vector<vec3> d;                         // unit directions
    std::vector<std::array<int, 3>> triangles;   // indices into d
    std::vector<float> solid_angle;              // per direction, sr; sum = 4 pi
    std::vector<std::vector<int>> fan;           // triangles adjacent to each direction

    int size() const { return int(d.size()); }
    // The spherical triangle containing unit vector w, and barycentric weights of its three
    // corners (non-negative, summing to 1; from the planar triangle hit by the ray along w).
    // Always succeeds for a unit w (the hull encloses the origin). Starts in the fan of
    // nearest(w) and walks across edges (~0.2 us at N = 1024, ~0.7 us at N = 65536).
    int locate(vec3 w, vec3& bary) const;
    // Index of the direction nearest to w (largest dot product): a window of ~sqrt(N) indices
    // around w's height on the Fibonacci lattice, then a greedy walk on the triangulation (exact
    // on a Delaunay triangulation; brute force for N <= 64 or without a triangulation).
    int nearest(vec3 w) const;
};

// N in [4, 65536]; throws InputError naming microgeom.directions otherwise. Direction i has
// z = 1 - (2i + 1)/N and phi = i * pi (3 - sqrt 5). The triangulation is built by a randomised
// incremental convex hull (fixed shuffle: deterministic), O(N log N): ~1 ms for N = 1024,
// ~0.2 s for N = 65536.
DirectionSet make_direction_set(int n);

// Solid angle of the spherical triangle (a, b, c) of unit vectors (Van Oosterom & Strackee).
float spherical_triangle_area(vec3 a, vec3 b, vec3 c);
}  // namespace mesolab::microgeom
