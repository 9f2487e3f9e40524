#pragma once
// Curved base geometry (Heidrich et al. 2000, §5). The heightfield is bent by curvatures
// kappa_u, kappa_v (radians per texel; a paraboloid z -= (kappa_u x^2 + kappa_v y^2)/2 around
// each point, positive = convex). Visibility is assumed unchanged (S_i stay valid), but:
//  - the direction from p to the point q that S_j[p] names bends: with q at horizontal offset
//    (dx, dy) texels, q drops by (kappa_u dx^2 + kappa_v dy^2)/2, and d_j'(p) = normalize(q' - p).
//    Directions to the environment (no hit) do not bend.
//  - the bent directions no longer sample the sphere uniformly: each path through direction j
//    is weighted by the importance I_j(p) = (area of the triangle fan around d_j' on the unit
//    sphere) / (area of the fan around d_j), the paper's estimate of the change in sampling rate.
//  - where a bent triangle turns over (its orientation flips), visibility would change: the
//    texel is flagged (AOV `folded`, and a warning) instead of giving unflagged garbage.
// Curvature 0 gives importance 1 everywhere and no flags: exactly the flat result.
#include "core/microgeom/directions.h"
#include "core/microgeom/heightfield.h"
#include "core/microgeom/visibility.h"
#include <cstdint>
#include <functional>
#include <vector>

namespace mesolab::microgeom {

struct Bending {
    float ku = 0.f, kv = 0.f;  // radians per texel
    bool zero() const { return ku == 0.f && kv == 0.f; }
    // From the total bend across the field in degrees (the public parameters).
    static Bending from_degrees(float across_u_deg, float across_v_deg, int width, int height);
};

struct Importance {
    int width = 0, height = 0, count = 0;
    std::vector<float> w;          // [texel][direction], > 0 where the direction is above the texel's plane
    std::vector<uint8_t> folded;   // per texel: 1 where a bent triangle turned over
    size_t folded_count = 0;
    float at(size_t texel, int dir) const { return w.empty() ? 1.f : w[texel * size_t(count) + size_t(dir)]; }
};

// Empty weights (all 1) for zero curvature.
Importance compute_importance(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                              const std::function<void(double)>& progress = {});

// Bent direction j at texel (x, y) (local frame), per the model above.
vec3 bent_direction(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b, int x, int y, int j);
}  // namespace mesolab::microgeom
