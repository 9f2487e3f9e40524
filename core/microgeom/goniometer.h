#pragma once
// The virtual goniometer: a BRDF simulated from the heightfield (Heidrich et al. 2000, §6,
// Fig. 9: geometry, bump map and BRDF as levels of detail of one surface structure), and BTF
// slices (the images the goniometer averages).
//
// [SECTION] Model (texture space, §6)
// "A single BRDF sample is the average radiance of a whole image of the heightfield"; no
// geometry is needed: "the masking problem can be solved by using the same data structures as
// used for the shadow test, only with the viewing direction". Directions are in the local frame
// (z = macro normal). A light from wi carries irradiance 1 perpendicular to wi (E = 1 at normal
// incidence, as ScatterSettings::light_E). Per texel x with normal n_x and albedo rho_x:
//   L(x, wi)     = rho_x/pi max(0, n_x.wi) V(x, wi) + rho_x/pi E_ind(x, wi)
//                  (scatter() with light_dir = wi, light_E = 1, env = null: `direct` +
//                   albedo/pi * E_indirect; the depth/sampling/ellipse settings are scatter's)
//   L(x, wi, wo) = L(x, wi) + [phong] ks (s + 8)/(8 pi) max(0, n_x.h)^s max(0, n_x.wi) V(x, wi),
//                  h = normalize(wi + wo)   (the lobe on the direct term only, as in scatter.h)
//   m(x, wo)     = V(x, wo) max(0, n_x.wo) / n_x.z     masking weight: the visible projected area
//                  of the texel's facet towards wo (facet area 1/n_x.z texel areas); V(x, wo) is
//                  visibility_texture(wo), or ellipse_visibility_texture(wo) with ellipses (§4)
//   T(wi, wo)    = sum_x L(x, wi, wo) m(x, wo) / sum_x m(x, wo)   (0 if the sum is 0)
// T is the radiance the goniometer sees from wo: the BRDF times cos(theta_i), f = T / wi.z.
// Self-normalising (rather than dividing by N wo.z, which equals sum_x m for an exact heightfield
// visibility) keeps grazing views finite. For wi.z <= 0 or wo.z <= 0, T = 0.
//   T_env(wo)    = the same average of rho_x/pi E_ind(x) from scatter() with no light and a
//                  constant environment of radiance 1: the radiance towards wo under a uniform
//                  white sky (a flat field gives rho; a white field tends to 1 with depth). The
//                  renderer scales it by the real environment.
//
// [SECTION] Table (fit = Table): the paper's "dense regular mesh of samples" (its 16^4 took 7-8
// hours). Nodes: theta_i = i/(n_theta - 1) * pi/2 (i = 0..n_theta-1, so theta reaches the
// horizon), phi_j = j/n_phi * 2 pi (j = 0..n_phi-1), node index i * n_phi + j; node direction
// (sin theta cos phi, sin theta sin phi, cos theta), computed in double (so the horizon nodes
// have z = 6e-17 > 0). table[light_node * nodes + view_node] = T(node, node) (the light nodes
// at exactly the node direction). View nodes with theta > pi/2 - kGonioHorizonEps are simulated
// at theta = pi/2 - kGonioHorizonEps: at the horizon itself a flat field's masking weights all
// vanish (0/0); this keeps the grazing limit there. All theta = 0 nodes are one direction: one
// scatter solve and one masking texture for all of them. Cost: one scatter solve per distinct
// light node + one for env, one masking texture per distinct view node, then a matrix product
// (lights x texels) * (texels x views) per channel (+ the Blinn-Phong sums when `phong`, one
// pass over the texels per (light, view) pair). Light solves run in parallel (TBB) in blocks of 8.
// Memory: the normalised masking weights, 4 bytes x texels x (1 + (n_theta - 1) n_phi). Bricks
// 128^2, N = 100, depth 2, 2 cores, Release: ~0.6 s at resolution 8, ~2.8 s at 16 (241 light
// solves of ~10 ms); with `phong` ~0.9 s and ~7 s; the paper's 16^4 took 7-8 hours.
//
// [SECTION] Spherical harmonics (fit = SH): "several hundred random samples projected into ... a
// hierarchical basis such as spherical harmonics". `samples` pairs (wi, wo), both uniform in
// solid angle on the upper hemisphere, from std::mt19937(seed): per sample four numbers
// u = (rng() >> 8) * 2^-24, in the order wi.z = 1 - u1, phi_i = 2 pi u2, wo.z = 1 - u3,
// phi_o = 2 pi u4. y_s = T(wi_s, wo_s) (goniometer_average). Real SH Y_k (real_sh below),
// B = sh_bands^2 per direction, f(wi, wo) ~ sum_{a,b} c[a * B + b] Y_a(wi) Y_b(wo), per channel
// by Tikhonov-regularised least squares with a smoothness penalty: minimise
// |A c - y|^2 + lambda sum_k w_k c_k^2, A[s][a * B + b] = Y_a(wi_s) Y_b(wo_s),
// w_(a,b) = (1 + l_a (l_a + 1) + l_b (l_b + 1))^2 (l_a: the band of Y_a; the squared eigenvalue of
// 1 - the Laplacian on sphere x sphere, so high bands are damped most) and
// lambda = kGonioShLambda * |A|_F^2 / B^2 (relative to the mean diagonal of A^T A). (Measured on
// bricks 64^2, 300 samples: a uniform penalty overfits from 4 bands on; this one keeps the RMS
// table error at ~2% of max T for 3..5 bands.) Solved in the primal (B^2 x B^2) or dual
// (samples x samples) form, whichever is smaller. Never throws or gives NaN on a bad fit.
// The fit is then tabulated at the nodes (exact node directions, clamped >= 0) into `table`, so
// rendering always uses `eval`; `env` is simulated exactly as for Table.
//
// [SECTION] Look-up (eval; a GLSL shader replicates this exactly)
// eval(wi, wo): wi and wo are normalised (zero length or non-finite: 0); 0 if wi.z <= 0 or
// wo.z <= 0. For each of w = wi, wo:
//   t     = acos(min(w.z, 1)) / (pi/2) * (n_theta - 1), clamped to [0, n_theta - 1]
//   i0    = min(floor(t), n_theta - 2), a = t - i0, i1 = i0 + 1            (a in [0, 1])
//   u     = atan2(w.y, w.x) / (2 pi) (0 when w.x = w.y = 0), u = u - floor(u)
//   s     = u * n_phi, j = floor(s), b = s - j, j0 = j mod n_phi, j1 = (j + 1) mod n_phi
//   taps  (i0, j0) (1-a)(1-b), (i0, j1) (1-a) b, (i1, j0) a (1-b), (i1, j1) a b
// result = sum over the 4 x 4 tap pairs of w_light w_view table[(iL n_phi + jL) * nodes +
// (iV n_phi + jV)], nodes = n_theta * n_phi: bilinear in (t, s) for wi and for wo, periodic in phi.
// eval_env(wo): the same 4 taps of wo over `env`.
#include "core/heightfield/heightfield.h"
#include "core/image.h"
#include "core/math.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/scatter.h"
#include "core/microgeom/visibility.h"
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace mesolab::microgeom {

inline constexpr double kGonioHorizonEps = 1e-3;  // radians: view nodes at the horizon are simulated this far above it
inline constexpr double kGonioShLambda = 1e-5;    // SH fit: Tikhonov weight relative to the mean diagonal of A^T A

struct GonioSettings {
    ScatterSettings scatter;  // depth, sampling, paths, seed, shadows, importance, ellipses; light_dir/light_E/env are ignored
    bool phong = false;       // Blinn-Phong lobe on the direct term (see above)
    vec3 ks{0.f};
    float shininess = 32.f;
    int resolution = 8;       // nodes: resolution in theta x resolution in phi, for wi and for wo (the paper's 16^4: 16), [2, 64]
    enum class Fit { Table, SH } fit = Fit::Table;
    int samples = 300;        // SH: random (wi, wo) pairs, each one goniometer image, >= 1
    int sh_bands = 3;         // SH: bands 0..sh_bands-1 per direction (sh_bands^2 coefficients each), [1, 8]
    uint32_t seed = 1;        // SH: sample pairs
    // The light images elsewhere (the GPU, made for the same hf, dirs, vis and `scatter`), in
    // batches of lights->batch(); null: scatter() on the CPU, 8 lights in parallel at a time.
    LightSolver* lights = nullptr;
};

struct SimulatedBrdf {
    int n_theta = 0, n_phi = 0;  // table layout (always filled; for SH the fit tabulated at the nodes)
    std::vector<vec3> table;     // [light_node * nodes + view_node], node = i_theta * n_phi + i_phi: T(wi, wo)
    std::vector<vec3> env;       // [view_node]: T_env(wo)
    std::vector<float> shadow;   // [light_node * nodes + view_node]: masked average of V(x, wi) [n_x.wi > 0] (the `shadow` AOV)
    int sh_bands = 0;            // SH fit (fit == SH): c[a * B + b], B = sh_bands^2
    std::vector<vec3> sh;
    int images = 0;              // goniometer images computed (scatter solves, env included)
    double fit_residual = 0;     // SH: sqrt(sum |clamped fit - y|^2 / sum |y|^2) over the samples and channels

    int nodes() const { return n_theta * n_phi; }
    // Unit direction of node (i_theta, i_phi) (as in the header comment; computed in double).
    vec3 node_direction(int i_theta, int i_phi) const;
    vec3 eval(vec3 wi, vec3 wo) const;      // from `table`, by the formula above
    vec3 eval_env(vec3 wo) const;           // from `env`
    float eval_shadow(vec3 wi, vec3 wo) const;  // from `shadow`, same taps as eval
    vec3 eval_sh(vec3 wi, vec3 wo) const;   // the SH fit directly, clamped >= 0 (0 below the horizon or without a fit)
    size_t bytes() const;                   // table + env + sh
};

// The real spherical harmonics of bands 0..bands-1 at unit w (bands^2 values, bands in [1, 8]):
// index k = l (l + 1) + m, Y_l^0 = K_l^0 P_l^0(cos theta), Y_l^m = sqrt 2 K_l^m cos(m phi)
// P_l^m(cos theta) (m > 0), Y_l^-m = sqrt 2 K_l^m sin(m phi) P_l^m(cos theta), with
// K_l^m = sqrt((2l + 1)/(4 pi) (l - m)!/(l + m)!) and P_l^m the associated Legendre functions
// with the Condon-Shortley phase (Y_0^0 = 0.2821, Y_1^0 = 0.4886 z, Y_1^1 = -0.4886 x):
// orthonormal over the sphere.
void real_sh(int bands, vec3 w, double* out);

// The BRDF table (and SH fit) for the settings; `progress` gets fractions in [0, 1] on the calling
// thread and may throw to cancel. InputError naming microgeom.brdf_resolution / brdf_samples /
// sh_bands for out-of-range settings, microgeom.visibility when vis does not belong to hf and dirs.
SimulatedBrdf simulate_brdf(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g,
                            const std::function<void(double)>& progress = {});

// One goniometer image, a BTF slice in texture space: per texel L(x, wi, wo) V(x, wo) (the
// radiance towards wo, 0 where masked), RGB, hf.width x hf.height, row 0 at the top (as
// Heightfield). All zero when wi.z <= 0 or wo.z <= 0.
Image goniometer_image(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g, vec3 wi, vec3 wo);

// The average the goniometer takes of one image: T(wi, wo) by the formula above (wi, wo
// normalised here). One scatter solve.
vec3 goniometer_average(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g, vec3 wi, vec3 wo);
}  // namespace mesolab::microgeom
