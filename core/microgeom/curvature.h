#pragma once
// Curved base geometry (Heidrich et al. 2000, §5). The heightfield is bent by curvatures
// kappa_u, kappa_v (radians per texel; a paraboloid z -= (kappa_u x^2 + kappa_v y^2)/2 around
// each point, positive = convex). Visibility is assumed unchanged (S_i stay valid), but:
//  - the direction from p to the point q that S_j[p] names bends: with q at horizontal offset
//    (dx, dy) texels, q drops by (kappa_u dx^2 + kappa_v dy^2)/2, and d_j'(p) = normalize(q' - p).
//    Directions to the environment (no hit) do not bend.
//  - the bent directions no longer sample the sphere uniformly: each path through direction j
//    is weighted by its importance I_j(p) = (area of the triangle fan around d_j' on the unit
//    sphere) / (area of the fan around d_j), the paper's estimate of the change in sampling rate.
//    Only triangles whose three corners all hit the heightfield enter that ratio: a triangle
//    spanning a hit and an environment direction straddles a silhouette, where the directions
//    are discontinuous, and its stretching is not a change of sampling rate. On a convex base
//    the far side of a valley drops, the solid angle it fills shrinks (I < 1), and the sky
//    uncovered above it belongs to the environment; on a concave base the valley's far side
//    rises and covers sky.
//  - the quadrature weights of the gather (scatter.h) follow: w_j(p) ~ max(0, n_p . d_j') Omega_j I_j
//    for hits, and the environment directions (unbent) share whatever the bent hits leave of the
//    flat cosine-weighted total, W0(p) = sum_j max(0, n_p . d_j) Omega_j. If the hits alone
//    exceed W0 (strong concave bending), they are scaled to W0 and the environment gets
//    nothing. Per texel, sum_j w_j = 1: a white furnace still conserves energy exactly.
//  - where a bent triangle turns over (its orientation flips), visibility would change: the
//    texel is flagged (AOV `folded`, and a warning) instead of giving unflagged garbage.
// Curvature 0 gives importance 1 everywhere and no flags: exactly the flat result.
#include "core/heightfield/heightfield.h"
#include "core/microgeom/directions.h"
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
    std::vector<float> I;          // [texel][direction]: fan-area ratio, > 0 (1 for unbent directions)
    std::vector<float> w;          // [texel][direction]: normalised gather weights, >= 0, sum 1 per texel
    std::vector<uint8_t> folded;   // per texel: 1 where a bent triangle turned over
    size_t folded_count = 0;
    // Sized for a field and direction set, with no weights yet (empty: the flat quadrature).
    static Importance sized(int width, int height, int count) {
        Importance imp;
        imp.width = width, imp.height = height, imp.count = count;
        return imp;
    }
    // Every direction unbent: I = 1, w = 0, nothing folded (the start of a computation).
    void allocate() {
        const size_t T = size_t(width) * size_t(height);
        I.assign(T * size_t(count), 1.f);
        w.assign(T * size_t(count), 0.f);
        folded.assign(T, 0);
        folded_count = 0;
    }
    bool empty() const { return w.empty(); }
    float importance(size_t texel, int dir) const { return I.empty() ? 1.f : I[texel * size_t(count) + size_t(dir)]; }
    float weight(size_t texel, int dir) const { return w[texel * size_t(count) + size_t(dir)]; }
};

// Empty (no weights: the flat quadrature) for zero curvature.
Importance compute_importance(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                              const std::function<void(double)>& progress = {});

// Bent direction j at texel (x, y) (local frame), per the model above.
vec3 bent_direction(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b, int x, int y, int j);
}  // namespace mesolab::microgeom
