#pragma once
// Approximate shadows with per-texel ellipses (Heidrich et al. 2000, §4 "Shadows", Fig. 6).
//
// [SECTION] Representation
// For texel p, every direction d_i of the set D with d_i.z > 0 (the upper hemisphere of the base
// surface) is projected orthographically onto the base plane, i.e. its z coordinate in the local
// frame is dropped: P_i = (d_i.x, d_i.y), a point of the unit disk. The direction is lit at p
// when S_i[p] says no hit (Visibility::kNoHit) and shadowed otherwise (a hit, or kBelow: below
// p's tangent plane). Directions with d_i.z <= 0 are ignored: a light below the base plane is
// taken as shadowed everywhere (ellipse_visibility returns 0), so only the upper hemisphere has
// to be represented and lower directions never overlap upper ones in the projection.
//
// Per texel one ellipse in this projected-direction space, with centre c, major-axis angle phi
// (radians from +x towards +y, in [0, pi)) and radii a >= b > 0 (a along (cos phi, sin phi), b
// along (-sin phi, cos phi)), should contain the lit points and exclude the shadowed ones.
//
// [SECTION] Fitting (§4)
// Start from the covariance of the lit points: centre = their mean, axes = the eigenvectors,
// radii proportional to sqrt(eigenvalues) (the paper's start). The criterion is the paper's:
// maximise (lit points inside) - (shadowed points inside), i.e. the number of correctly
// classified points. For a given centre, angle and aspect rho = b / a, inside(P) is
// s(P) <= a with s(P) = sqrt(u^2 + (v / rho)^2) ((u, v): P in the ellipse's axes), so the best
// radius follows exactly from one sort of the s(P) and a sweep (the paper's radius optimisation,
// solved exactly rather than locally). Among equally good radii the one halfway between the two
// critical points is taken (the maximum margin: the boundary then lies where the exact test's
// interpolation crosses 1/2), and ties between candidates go to the larger margin. A
// deterministic pattern search over (centre, angle, log aspect) refines the covariance start
// (also tried: a circle at the mean, and the circle at the origin).
// Special cases: no lit upper direction -> the empty ellipse (kEmptyEllipse: a tiny circle
// outside the unit disk, so the evaluation formula needs no special case); no shadowed upper
// direction -> the circle at the origin of radius 1 + edge (every upward light lit).
//
// [SECTION] Evaluation (eq. 2-4, with an optional soft edge)
// For a unit direction w (local frame), exactly (this is the formula a shader must use):
//   w.z <= 0                                  -> V = 0
//   p = (w.x, w.y) - c
//   u = ( cos(phi) p.x + sin(phi) p.y) / a,  v = (-sin(phi) p.x + cos(phi) p.y) / b
//   q = u^2 + v^2                                               (eq. 4: inside iff q <= 1)
//   edge <= 0 (hard, the paper's test):   V = q <= 1 ? 1 : 0
//   edge  > 0 (soft):  g = 2 sqrt((u / a)^2 + (v / b)^2)       (|grad q| in projected space)
//                      dist = (q - 1) / max(g, 1e-6)          (signed distance to the boundary,
//                                                              first order; < 0 inside)
//                      V = clamp(0.5 - dist / edge, 0, 1)
// so V = 1/2 exactly on the boundary and V >= 1/2 iff q <= 1 for any edge: the soft and hard
// tests agree at threshold 1/2. The soft edge ramps over `edge` projected units around the
// boundary, like the exact test interpolating between a lit and a shadowed direction.
// EllipseMap::edge is half the typical direction spacing, 0.5 sqrt(4 pi / N) (0.177 at N = 100).
#include "core/math.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/heightfield.h"
#include "core/microgeom/visibility.h"
#include <functional>
#include <vector>

namespace mesolab::microgeom {

// One texel's ellipse, in projected-direction space (see above).
struct Ellipse {
    vec2 centre{0.f};
    float angle = 0.f;   // major axis, radians in [0, pi)
    float a = 1.f, b = 1.f;  // radii along the major and minor axis, a >= b > 0
};

// The ellipse lighting nothing in the upper hemisphere: centre (2, 0), radii 0.01.
inline constexpr Ellipse kEmptyEllipse{vec2(2.f, 0.f), 0.f, 0.01f, 0.01f};

struct EllipseMap {
    int width = 0, height = 0;
    float edge = 0.f;        // soft-edge width used by ellipse_visibility_texture (projected units)
    std::vector<Ellipse> e;  // row-major, row 0 at the top (as Heightfield)

    const Ellipse& at(int x, int y) const { return e[size_t(y) * size_t(width) + size_t(x)]; }
    size_t bytes() const { return e.size() * sizeof(Ellipse); }
};

// Soft-edge width for a set of n directions: half the typical spacing, 0.5 sqrt(4 pi / n).
float ellipse_edge(int n);

// Fits one ellipse per texel (§4), in parallel (TBB) over rows; deterministic (independent of
// the thread count). `progress` gets fractions in [0, 1] on the calling thread only and may throw
// to cancel. vis must have been computed for hf and dirs (same size and direction count;
// std::invalid_argument otherwise). About 0.3 s for Bricks 128x128 with N = 100 on 2 cores
// (Release; the paper's Table 1: 194 s).
EllipseMap fit_ellipses(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis,
                        const std::function<void(double)>& progress = {});

// Visibility (0..1) of unit direction w_local (local frame) for one texel's ellipse, by the
// formula above: hard (0 or 1) for edge <= 0, soft otherwise.
float ellipse_visibility(const Ellipse& e, vec3 w_local, float edge = 0.f);

// Per-texel ellipse visibility of direction w_local with the map's soft edge (map.edge), 0 where
// hf.normal(x, y) . w_local <= 0, like visibility_texture in scatter.h (shadow texture for the
// light, masking for the view). The map must be the same size as hf.
std::vector<float> ellipse_visibility_texture(const EllipseMap& map, const Heightfield& hf, vec3 w_local);
}  // namespace mesolab::microgeom
