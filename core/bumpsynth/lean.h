#pragma once
// [SECTION] LEAN mapping: bumpsynth.method = lean
// The modern counterpart of the paper's distance-dependent octaves: LEAN mapping (Olano and Baker
// 2010, "LEAN Mapping", I3D). The synthesised bumps are baked once into a periodic map and their
// slope moments are filtered by mip-mapping, so that a pixel's footprint, however large, is shaded
// by one Beckmann lobe whose mean and covariance are those of the bump slopes under it plus the
// bumps' own micro-lobe.
//
// Units and frames: slopes b = (m_x / m_z, m_y / m_z) of a normal m in the macro tangent frame
// (z along the macro normal; m_z clamped at kLeanMinCos for the slope), dimensionless.
//
// [SECTION] The map (the stage bumpsynth.lean_map)
// The bumps are those the truth integrates (technique.h, truth_bump): all bumpsynth.octaves_max
// octaves of noise (or the §7 index map with its detail), mapped to normals by the exact inversion
// of the 512² NDF. Texel (x, y) of the N x N finest level (N = bumpsynth.lean_size, a power of two;
// row 0 at v = 1, like the heightfields) holds the means over an s x s grid of points within it
// (s = bumpsynth.lean_supersample, points at the cells' centres) of
//     B = b,   M = (b_x², b_y², b_x b_y),   m̄ = m                                  (Olano–Baker §3.2)
// so that detail finer than a texel enters its second moments instead of aliasing. Each coarser
// level averages 2 x 2 texels (a box filter: moments filter linearly, the point of LEAN), down to 1 x 1.
// The bumps' own micro-lobe (the material's NDF D, which the truth shades each bump with in the
// bump's frame) enters as the covariance Σ0 of its slopes over the normal's disk (D is the density
// of (m_x, m_y), ndf.h): Σ0 = E_D[b bᵀ] (D symmetric: E_D[b] = 0), from the 512² table, cells at
// their centres (a rim cell's pulled inside |xy|² <= 1 - 1e-4 as in the Smith table).
//
// [SECTION] Filtering a footprint
// λ = log2(ℓ N) with ℓ the footprint's extent in uv, trilinear between levels ⌊λ⌋ and ⌊λ⌋ + 1
// (bilinear within a level, periodic; level 0 below λ = 0). The footprint is the pixel's uv
// differences across its 2 x 2 quad (GBuffer::uv_dx, uv_dy; dFdxFine, dFdyFine on the GPU). With
// bumpsynth.lean_anisotropy = n > 1, a footprint longer than it is wide is covered by
// t = min(n, ⌈major / minor⌉) trilinear taps spaced evenly along its major axis, each at
// ℓ = max(major / t, minor) (footprint assembly, Schilling et al. 1996, as GPUs' anisotropic
// filtering), and their moments averaged; n = 1 is isotropic trilinear filtering at ℓ = major.
//
// [SECTION] Shading (Olano–Baker eq. 5-8, in the macro tangent frame)
//   Σ = M - B Bᵀ + Σ0   (+ 1e-8 I),   h = normalize(wo + wi),   h̃ = (h_x, h_y) / h_z
//   P22(h̃) = exp(-½ (h̃ - B)ᵀ Σ⁻¹ (h̃ - B)) / (2π √det Σ),   D(h) = P22(h̃) / h_z⁴      (sr⁻¹)
// then the BRDF of brdf.h with this D and n = z: specular F D G / (4 wo_z wi_z), F Schlick's at
// wi·h with F0 = ks (fresnel on) else ks, G the implicit (wo_z wi_z) (masking off) or
// 1 / (1 + Λ(wo) + Λ(wi)) (masking on) with Beckmann's Λ (Walter et al. 2007's rational fit) at
// the lobe's roughness along the direction, α(w)² = 2 w_xyᵀ Σ w_xy / |w_xy|² (the mean slope does
// not shift it); diffuse kd albedo (m̄·wi) / π, m̄ the filtered mean normal (the footprint's mean of
// the truth's max(0, m·wi) wherever no bump faces away from the light), and the environment's
// irradiance at normalize(m̄) times kd albedo / π. Lights below the macro surface give nothing.
//
// [SECTION] Limits (what the truth has and LEAN does not)
// One Gaussian lobe per footprint: a multi-lobe or heavy-tailed NDF (GGX, a uniform
// distribution, a bump map's histogram) collapses to the Gaussian of its first two moments, and
// heavy tails (whose slope variance grows without bound towards the rim) make that Gaussian wide;
// the micro-lobe is added in slope space rather than rotated with each bump (Olano–Baker's
// approximation, exact for small slopes); the diffuse term ignores bumps facing away from the
// light; the footprint is the pixel's quad, not the truth's exact box; below one texel per pixel
// the bilinear moments blur what the map resolves (lean_size and lean_supersample are the knobs).
#include "core/bumpsynth/lut.h"
#include "core/math.h"
#include "core/stage.h"

#include <functional>
#include <vector>

namespace mesolab::bumpsynth {

class Ndf;

inline constexpr float kLeanMinCos = 1e-2f;  // the least m_z a slope is taken at

// The moments at a point or averaged over a footprint.
struct LeanMoments {
    vec2 B{0.f};      // mean slope
    vec3 M{0.f};      // (E b_x², E b_y², E b_x b_y)
    vec3 m{0, 0, 1};  // mean normal (not normalised)
    float lambda = 0; // the mip level (log2 of the footprint in finest texels; the largest of the taps)
};

struct LeanMap {
    struct Level {
        int n = 0;             // texels per side
        std::vector<vec4> a;   // (B_x, B_y, M_xx, M_yy)
        std::vector<vec4> b;   // (M_xy, m̄_x, m̄_y, m̄_z)
    };
    std::vector<Level> levels;  // levels[0]: N x N ... levels.back(): 1 x 1
    vec3 sigma0{0.f};           // Σ0 of the micro-lobe: (xx, yy, xy)
    int size() const { return levels.empty() ? 0 : levels[0].n; }
    size_t bytes() const;

    // Bakes the map from the bumps' normals m(uv) (a function of the periodic unit square).
    // InputError naming bumpsynth.lean_size for a size not a power of two in [16, 4096].
    static LeanMap bake(const std::function<vec3(vec2)>& bump, int size, int supersample, vec3 sigma0);

    // Bilinear (periodic) moments of level l at uv.
    LeanMoments at_level(int l, vec2 uv) const;
    // Trilinear at level λ (clamped to the map's levels).
    LeanMoments trilinear(vec2 uv, float lambda) const;
    // The footprint's moments: uv and its differences across the pixel's quad, anisotropy n >= 1.
    LeanMoments filter(vec2 uv, vec2 duv_dx, vec2 duv_dy, int anisotropy) const;
};

// Σ0 of an NDF's slopes (xx, yy, xy) over the normal's disk (see the file's head).
vec3 slope_covariance(const Ndf& ndf);

// The LEAN lobe of moments `mo` with micro-lobe Σ0: D(h) for a unit h in the macro tangent frame
// (0 for h_z <= 0), and the covariance it uses.
struct LeanLobe {
    vec2 B{0.f};
    float sxx = 0, syy = 0, sxy = 0;  // Σ
    LeanLobe(const LeanMoments& mo, vec3 sigma0);
    float D(vec3 h) const;
    // Beckmann's Λ along w (Walter et al. 2007), at α(w) above.
    float Lambda(vec3 w) const;
};

struct ShadingModel;
// Radiance towards wo from a light (direction wi, irradiance E) for the footprint's moments; wo, wi
// in the macro tangent frame.
vec3 lean_shade(const ShadingModel& s, const LeanLobe& lobe, const LeanMoments& mo, vec3 wo, vec3 wi, vec3 E, vec3 albedo);
}  // namespace mesolab::bumpsynth
