#pragma once
// [SECTION] Virtual acquisition of a stitch (Daubert et al. 2001, §4, Fig. 3), ray cast with
// Embree 3.
//
// Lighting: the stitch mesh (its 3 × 3 tiles) is lit per light direction l at every vertex,
// directly (n·l where a shadow ray towards l escapes) and indirectly by `bounces` bounces through
// precomputed visibility (the micro-geometry paper's method on a triangle mesh): per vertex,
// `visibility_rays` cosine-distributed directions over its hemisphere, each remembered as the
// point it hits (triangle and barycentrics) or as escaping. The yarn is Lambertian with the
// vertex's colour ρ: L_0 = L_direct = ρ/π · n·l · V(l), and each bounce gathers the previous one,
// L_{b+1} = L_direct + ρ/π · (π/K) Σ_k L_b(hit_k) (the method of dependent tests: the same K
// directions every bounce). The paper's acquisition is one bounce; bounce b adds at most ρ^b
// times the direct light (less where the gathering rays escape), so the series converges.
// Light of unit irradiance on a plane perpendicular to l; no environment.
//
// Sampling: a grid of `spatial` × `spatial` points on the top face of the centre tile's box;
// for each view direction v a ray from far along v through the point, back along −v: the first
// surface it meets (parallax) gives the radiance for every light, and alpha 1; a ray that leaves
// the fabric through a hole gives 0 and alpha 0. The value stored is the pattern's BRDF
// f_r(l, v) = L_o / (E_0 cos θ_l), θ_l from the pattern's normal (+z). Per point the normals
// of the surface its rays hit are averaged into its normal; its tangent is the pattern's x axis.
// Light and view directions: `directions` each, spread evenly over the hemisphere (a Fibonacci
// spiral in cos θ, from cos θ = 1 down to 0.05).
#include "core/cloth/pyramid.h"
#include "core/cloth/stitch.h"
#include "core/stage.h"

#include <atomic>

namespace mesolab::cloth {

struct AcquireParams {
    int spatial = 32;          // sample points per side (a power of two)
    int directions = 32;       // light directions, and as many view directions
    int visibility_rays = 64;  // per vertex, for the indirect bounces (0: direct light only)
    int bounces = 1;           // indirect bounces (0: direct light only)
};

// n unit directions over the upper hemisphere, a Fibonacci spiral with cos θ evenly from 1 down
// to z_min (0.05 for the acquisition, see above).
std::vector<dvec3> hemisphere_directions(int n, double z_min = 0.05);

// InputError naming cloth.spatial (not a power of two in [1, 256]), cloth.directions (outside
// [4, 128]) or cloth.bounces (outside [0, 64]). Progress: ("cloth.acquire", fraction); a set `cancel` stops it with Cancelled.
SampleGrid acquire(const StitchMesh& stitch, const AcquireParams& p, const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr);
}  // namespace mesolab::cloth
