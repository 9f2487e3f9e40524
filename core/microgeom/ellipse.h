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
//
// [SECTION] Curved base (§5)
// The paper adapts the ellipses to the local base curvature by fitting them "starting from the
// updated scattering directions d_j'" and stores only five fits per texel: zero curvature and a
// slight positive and negative curvature in each parametric direction, with "a linear
// approximation of the change of ellipse parameters" for any given curvature. Here:
//  - Bent fit. The points of texel p are, in direction-index order: the no-hit directions d_j
//    with d_j.z > 0, lit and unbent (environment directions do not bend, curvature.h); every
//    other direction shadowed at bent_direction(hf, dirs, vis, b, x, y, j), kept when the bent
//    direction has z > 0. So hit directions move (towards the horizon and possibly below it on a
//    convex base, where the occluders drop away; towards the zenith on a concave one, where hits
//    from slightly below the base plane can rise into the upper hemisphere), and kBelow directions
//    stay where they are: they are below p's own tangent plane, which the bending (a paraboloid
//    around p, curvature.h) does not move, and bent_direction leaves them unbent. Bending{} gives
//    exactly the points, order and fit of fit_ellipses(hf, dirs, vis) (bit-exact).
//  - Samples. flat (0), u_pos / u_neg (+-bend along u only), v_pos / v_neg (+-bend along v only),
//    bend in degrees across the field as Bending::from_degrees (step_u, step_v; the negative
//    samples use the exactly negated curvature).
//  - Interpolation. Per texel, with t_u = clamp(ku / step_u.ku, -1, 1) and t_v likewise (a
//    curvature beyond the samples is clamped to them, not extrapolated: the linear model is only
//    meant for slight curvatures, and extrapolated quadratic forms soon stop being ellipses):
//      X = X_flat + |t_u| (X_u - X_flat) + |t_v| (X_v - X_flat)
//    (X_u = the u_pos sample for t_u > 0, u_neg otherwise; likewise v), i.e. E_flat + (E_u - E_flat)
//    + (E_v - E_flat) with E_u, E_v linear between the flat fit and the sample on their side. X is
//    the centre c and the quadratic form Q = R diag(1/a^2, 1/b^2) R^T (symmetric 2x2; the angle
//    itself wraps at pi and is meaningless for circles, Q is neither). a, b and the angle come back
//    from the eigen-decomposition of Q (in double): the smaller eigenvalue gives the major radius.
//    Eigenvalues are clamped to [1/kMaxRadius^2, 1/kMinRadius^2] = [1e-6, 1e4] (radii in [0.01,
//    1000]; fitted radii stay below a few hundred): a sum that is no longer positive definite
//    becomes a strip across the whole unit disk along that axis rather than a hyperbola; a
//    (nearly) circular Q gets angle 0, as the fit's circles.
//  - Empty samples (kEmptyEllipse, nothing lit) have no meaningful centre or Q. Per texel the
//    nearest sample to (|t_u|, |t_v|) among flat (0, 0), u (1, 0) and v (0, 1) (ties: flat, then
//    u, then v) decides: if it is empty the result is kEmptyEllipse; otherwise every empty sample
//    among the three is replaced by the nearest one (it contributes no change), so a texel that is
//    shadowed from everywhere at one sample switches at the midpoint instead of sliding a tiny
//    ellipse in from outside the disk.
//  - Exactness: Bending{} returns the flat fit unchanged (bit-exact, no round trip); at exactly a
//    sample's curvature the result is that sample up to the float rounding of the Q round trip
//    (relative 1e-6 in a and b, 1e-6 in the centre; the angle where a and b differ).
#include "core/heightfield/heightfield.h"
#include "core/math.h"
#include "core/microgeom/curvature.h"
#include "core/microgeom/directions.h"
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

// [SECTION] Curved base (§5), see above
// Ellipses for a base bent by b: lit = the unbent no-hit upper directions, shadowed = the bent
// directions of all other directions that end up above the base plane (kBelow ones unbent).
// Bending{} gives exactly fit_ellipses(hf, dirs, vis). Parallel over rows, deterministic;
// progress and errors as fit_ellipses.
EllipseMap fit_ellipses(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                        const std::function<void(double)>& progress = {});

// The five samples of §5 and the curvatures they were fitted at.
struct CurvedEllipses {
    float bend_deg = 0;           // the +- bend of the samples (degrees across the field, >= 0)
    Bending step_u, step_v;       // Bending::from_degrees(bend, 0, w, h), (0, bend, w, h)
    EllipseMap flat, u_pos, u_neg, v_pos, v_neg;  // at Bending{}, step_u, -step_u, step_v, -step_v
    size_t bytes() const;
};

// The five fits in one pass, in parallel over rows (deterministic; each map is bit-identical to
// fit_ellipses at its curvature). |bend_deg| is used; 0 fits once and copies. About 5.5x
// fit_ellipses: 0.85 s for Bricks 128x128, N = 100 on 2 cores (Release). std::invalid_argument for a non-finite bend or mismatched visibility.
// `fit`, where given, fits one curvature's map instead (the GPU: gpu/microgeom/ellipse_gpu.h),
// called for the five in the order flat, u_pos, u_neg, v_pos, v_neg.
using EllipseFit = std::function<EllipseMap(Bending, const std::function<void(double)>&)>;
CurvedEllipses fit_curved_ellipses(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, float bend_deg,
                                   const std::function<void(double)>& progress = {}, const EllipseFit& fit = {});

// The ellipses at curvature b by the linear model above (|ku|, |kv| clamped to the samples'; a NaN
// component counts as 0).
// Every ellipse is well formed (finite, a >= b > 0, angle in [0, pi)). std::invalid_argument if
// the five maps differ in size. About 1 ms for 128x128.
EllipseMap interpolate_ellipses(const CurvedEllipses& c, Bending b);
}  // namespace mesolab::microgeom
