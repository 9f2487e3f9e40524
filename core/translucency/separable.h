#pragma once
// [SECTION] Method separable of technique translucency: screen-space separable subsurface
// scattering (Jimenez, Zsolnai, Jarabo, Freude, Auzinger, Wu, von der Pahlen, Wimmer and Gutierrez
// 2015, "Separable Subsurface Scattering", Computer Graphics Forum 34(6); the screen-space blur of
// Jimenez, Sundstedt and Gutierrez 2009).
//
// What a frame does, per pixel of the method's objects, on both devices:
//   1. irradiance  E(x) entering the medium at the pixel's surface point: every light times the
//                  Fresnel transmittance T(cos θi) (Schlick, as the paper's method) and its shadow
//                  map, plus the environment times the hemispherical mean of T; the view depth of
//                  the point (mm) and the size of a pixel there (mm, at the depth, facing the camera).
//   2. two blurs   B = A_y A_x E: the profile's 2D filter R_d(√(x² + y²)) replaced by the product of
//                  its 1D marginals (§4 of the paper, "the separable approximation"),
//                      R_d(x, y) ≈ a(x) a(y),  a(x) = ∫ R_d(√(x² + y²)) dy / √R_total   (mm⁻¹),
//                  sampled at `translucency.separable_taps` offsets x_i (mm, denser near the centre:
//                  x_i ∝ t_i², t_i uniform in [−1, 1], the outermost where R_d holds 99.5% of
//                  R_total), each tap weighted by the integral of a over its strip (so the weights
//                  sum to √R_total exactly and a flat E gives B = R_total E). A tap at x_i mm lies
//                  x_i / (pixel size) pixels away along the image's row (then column), read
//                  bilinearly from the four pixels around it.
//                  Following the surface (the paper's depth correction): a pixel of another object,
//                  of the background or outside the image gives the centre's value; a pixel of the
//                  object at view depth z_j gives mix(E_j, E_centre, min(1, |z_j − z_centre| / |x_i|))
//                  (a surface turned more than 45° from the image plane between the two is treated
//                  as not the same surface).
//   3. display     L_o = T(cos θo) B / π, the paper's outgoing term (translucency.h).
// What it cannot do, by construction: light that crosses the object (the blur sees only the
// visible surface: thin parts seen from the lit side stay dark behind), distances on surfaces
// seen obliquely (foreshortened in the image: the blur is too wide there), and ρ textures (the
// albedo map and the veins are the atlas's). Profiles: the dipole (the paper's, default) or
// Christensen and Burley's normalised profile (burley.h), `translucency.separable_profile`.
#include "core/math.h"
#include "core/translucency/dipole.h"
#include "core/translucency/profile.h"

#include <memory>

#include <vector>

namespace mesolab::translucency {

// The integral of R_d over the strip |x| ≤ m of the plane (mm; per channel): ∫∫_{|x|≤m} R_d(r) dA.
// In polar form, ∫ R_d(r) L(r, m) dr with L the length of the circle of radius r inside the strip
// (2πr for r ≤ m, 4 r asin(m / r) beyond). S(∞) = R_total.
dvec3 strip_integral(const Profile& p, double m);

// The 1D kernel of both passes.
struct SeparableKernel {
    std::vector<float> offset_mm;  // tap positions x_i, ascending, symmetric, 0 in the middle
    std::vector<vec3> weight;      // a_i per channel: the strip integral of a around x_i
    dvec3 total{0.0};              // R_total per channel (Σ_i a_i)² per channel
    float reach_mm = 0.f;          // the outermost tap
};
// `taps` odd, ≥ 3. `reach` the fraction of R_total within the outermost tap's radius.
SeparableKernel make_separable_kernel(const Profile& p, int taps, double reach = 0.995);

// The kernel of a medium, profile and tap count, made once and kept (the latest 64) for every frame,
// device and panel that asks for it.
std::shared_ptr<const SeparableKernel> separable_kernel(const Medium& medium, bool burley, int taps);

// The size of a pixel at view depth z (world units) of a perspective camera whose projection's
// [1][1] is proj11, for an image `height` pixels high.
inline float pixel_size_at(float z, float proj11, int height) { return 2.f * z / (proj11 * float(height)); }
}  // namespace mesolab::translucency
