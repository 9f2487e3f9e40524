#pragma once
// Shading with the NDF (Kautz, Heidrich, Seidel 2001, §3.1, §5.1) and the per-pixel synthesis.
//
// [SECTION] The BRDF (in a frame whose z axis is the normal it shades)
//   specular  f_s = F(wi·h) D(h) G / (4 (n·wi)(n·wo)),   h = normalize(wi + wo)       (sr^-1)
//   diffuse   f_d = kd albedo(uv) / π
// F: Schlick's approximation F0 + (1 - F0)(1 - wi·h)^5 with F0 = ks (fresnel on), else F = ks.
// G: the Smith height-correlated masking-shadowing of the same NDF, G = 1 / (1 + Λ(wo) + Λ(wi))
// (masking on), else the implicit G = (n·wi)(n·wo) of the paper, which shades with p(h) directly
// (§3.1: "we currently do not include these terms"), so that f_s = F D / 4.
// Radiance from a light of irradiance E (W/m², at normal incidence): L = (f_s + f_d) E max(0, n·wi).
//
// [SECTION] Smith masking for any NDF (SmithTable)
// For the normalised NDF (∫ D (m·n) dω = 1) the Smith masking function is exact in closed form over
// the table: G1(ω) = (ω·n) / A(ω), A(ω) = ∫ D(m) max(0, ω·m) dω_m = Σ_cells mass · max(0, ω·m)/m_z
// (projected area of the visible microfacets), Λ = 1/G1 - 1. G1 is tabulated over θ in [0, π/2]
// (65 nodes, G1(π/2) = 0) and φ in [0, 2π) (64 nodes, periodic) and interpolated bilinearly; it
// satisfies the weak white furnace ∫ D(h) G1(wo) / (4 |n·wo|) dwi = 1 (Heitz 2014), which the tests check.
//
// [SECTION] Synthesis at a pixel (§5.1)
// The microfacet at uv with o(d) = k + w octaves: k octaves (k = 0: the macro frame, no bumps) and
// k + 1 octaves, each the nearest look-up-table entry of its inputs u = G_k(r_k) (procedural noise),
// of the noise texture's level K - k, or of the index map with k - 1 octaves of detail (bump_map.h);
// the two shadings blend with weight w (procedural noise: both inputs from one pass over k + 1
// octaves, noise_inputs_fading). The half vector is
// projected into the microfacet's frame {t_m, b_m, m} and the NDF looked up there (§5.1), i.e. the
// BRDF above is evaluated in that frame: with n = m, wo and wi expressed in {t_m, b_m, m}.
// Both must also be above the macro surface (wo·n > 0 and wi·n > 0); a facet facing away from the
// eye or the light reflects nothing specular.
#include "core/bumpsynth/bump_map.h"
#include "core/bumpsynth/lut.h"
#include "core/bumpsynth/ndf.h"
#include "core/bumpsynth/noise.h"
#include "core/image.h"
#include "core/math.h"
#include <vector>

namespace mesolab::bumpsynth {

struct ConsistentNdfs;

class SmithTable {
public:
    static constexpr int kTheta = 65, kPhi = 64;
    static SmithTable build(const Ndf& ndf);
    // G1 for a unit direction w in the NDF's frame (0 for w.z <= 0).
    float G1(vec3 w) const;
    // kPhi x kTheta values, row-major by θ (row j at θ = j π/2 / (kTheta - 1)), for a texture.
    const std::vector<float>& values() const { return g1_; }

private:
    std::vector<float> g1_;
};

struct ShadingModel {
    vec3 ks{0.9f};
    vec3 kd{0.1f};
    bool fresnel = false;
    bool masking = false;
};

// Radiance toward wo from one light (direction wi, irradiance E) for the facet frame f; wo, wi and
// f are in the macro tangent frame (z = macro normal). `smith` is needed when masking is on.
// `mean_normal` (kautz-consistent, consistent.h): the diffuse term's normal in the facet's frame, the
// unresolved bumps' mean (|m̄| < 1) instead of the facet's own; null: the facet's.
vec3 shade_facet(const ShadingModel& s, const Ndf& ndf, const SmithTable* smith, const LutEntry& f, vec3 wo, vec3 wi, vec3 E,
                 vec3 albedo = vec3(1.f), const vec3* mean_normal = nullptr);

// What a pixel's synthesis needs. The inputs come from index_map when non-null (§7, bump_map.h),
// else from noise_texture when non-null (noise = texture), else from the procedural noise (cdfs).
struct Synthesis {
    const Ndf* ndf = nullptr;
    const Lut* lut = nullptr;
    const NoiseCdfs* cdfs = nullptr;
    const NoiseTexture* noise_texture = nullptr;
    const IndexMap* index_map = nullptr;
    IndexDetail index_detail;
    const SmithTable* smith = nullptr;
    ShadingModel model;
    int octaves_max = 1;          // K
    float detail_distance = 4.f;  // eye distance beyond which there are no bumps (scene units)
    const Image* albedo = nullptr;  // albedo map (null: none)
    // kautz-consistent: per octave count the NDF of the unresolved bumps, their mean normal and
    // Smith table, which shade the facet of k octaves instead of ndf and smith (consistent.h).
    const ConsistentNdfs* consistent = nullptr;
};

// The two microfacets a pixel blends (coarse: k octaves, fine: k + 1, weight w of fine), and their
// look-up-table entries (a, b): (-1, -1) for the macro frame (k = 0); fine = coarse when w = 0.
struct FacetBlend {
    LutEntry coarse, fine;
    float w = 0.f;
    int k = 0;
    ivec2 coarse_entry{-1}, fine_entry{-1};
};
FacetBlend facets_at(const Synthesis& s, vec2 uv, float octaves);

// Inputs u of k >= 1 octaves at uv, from the index map, the procedural noise or the noise texture.
vec2 synthesis_inputs(const Synthesis& s, vec2 uv, int k);
}  // namespace mesolab::bumpsynth
