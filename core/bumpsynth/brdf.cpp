#include "core/bumpsynth/brdf.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>

namespace mesolab::bumpsynth {

// [SECTION] Smith masking
SmithTable SmithTable::build(const Ndf& ndf) {
    // The cells with mass, as (mass, m / m_z) pairs: A(ω) = Σ mass max(0, ω·m) / m_z.
    struct Cell { double mass; vec3 m_over_z; };
    std::vector<Cell> cells;
    const int R = ndf.resolution();
    for (int j = 0; j < R; ++j)
        for (int i = 0; i < R; ++i) {
            const double mass = ndf.mass(i, j);
            if (!(mass > 0.0)) continue;
            vec2 c = ndf.cell_centre(i, j);
            const float r2 = glm::dot(c, c);
            if (r2 > 0.9999f) c *= std::sqrt(0.9999f / r2);  // a rim cell's centre may lie outside the disk
            const float mz = std::sqrt(1.f - glm::dot(c, c));
            cells.push_back({mass, vec3(c.x, c.y, mz) / mz});
        }
    SmithTable t;
    t.g1_.assign(size_t(kTheta) * size_t(kPhi), 0.f);
    mesolab::parallel_for(0, kTheta - 1, [&](int j) {  // row kTheta - 1 (θ = π/2) stays 0
        const double theta = double(j) * (kPi / 2.0) / double(kTheta - 1);
        for (int p = 0; p < kPhi; ++p) {
            const double phi = 2.0 * kPi * double(p) / double(kPhi);
            const vec3 w(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
            double A = 0.0;
            for (const Cell& c : cells) A += c.mass * std::max(0.0, double(glm::dot(w, c.m_over_z)));
            t.g1_[size_t(j) * size_t(kPhi) + size_t(p)] = A > 0.0 ? float(std::min(1.0, std::cos(theta) / A)) : 1.f;
        }
    });
    return t;
}

float SmithTable::G1(vec3 w) const {
    if (!(w.z > 0.f)) return 0.f;
    const float len = glm::length(w);
    const float theta = std::acos(std::clamp(w.z / len, 0.f, 1.f));
    float phi = std::atan2(w.y, w.x);
    if (phi < 0.f) phi += 2.f * kPi;
    const float ft = theta / (kPi / 2.f) * float(kTheta - 1), fp = phi / (2.f * kPi) * float(kPhi);
    const int t0 = std::min(int(ft), kTheta - 2), p0 = int(fp) % kPhi, p1 = (p0 + 1) % kPhi;
    const float at = std::clamp(ft - float(t0), 0.f, 1.f), ap = fp - std::floor(fp);
    auto g = [&](int t, int p) { return g1_[size_t(t) * size_t(kPhi) + size_t(p)]; };
    const float a = g(t0, p0) + ap * (g(t0, p1) - g(t0, p0));
    const float b = g(t0 + 1, p0) + ap * (g(t0 + 1, p1) - g(t0 + 1, p0));
    return a + at * (b - a);
}

// [SECTION] The BRDF in a facet's frame
vec3 shade_facet(const ShadingModel& s, const Ndf& ndf, const SmithTable* smith, const LutEntry& f, vec3 wo, vec3 wi, vec3 E, vec3 albedo,
                 const vec3* mean_normal) {
    if (!(wo.z > 0.f) || !(wi.z > 0.f)) return vec3(0.f);
    const vec3 o(glm::dot(wo, f.t), glm::dot(wo, f.b), glm::dot(wo, f.m));
    const vec3 i(glm::dot(wi, f.t), glm::dot(wi, f.b), glm::dot(wi, f.m));
    if (!(i.z > 0.f)) return vec3(0.f);
    vec3 L = s.kd * albedo * (kInvPi * (mean_normal ? std::max(0.f, glm::dot(i, *mean_normal)) : i.z));
    if (o.z > 0.f) {
        const vec3 h = glm::normalize(o + i);
        const float D = ndf.eval(h);
        const vec3 F = s.fresnel ? s.ks + (vec3(1.f) - s.ks) * std::pow(std::clamp(1.f - glm::dot(i, h), 0.f, 1.f), 5.f) : s.ks;
        if (s.masking && smith) {
            // f_s cos θi = F D G2 / (4 cos θo), G2 = 1 / (1/G1o + 1/G1i - 1); G2 / cos θo stays finite at grazing.
            const float g1o = std::max(smith->G1(o), 1e-7f), g1i = std::max(smith->G1(i), 1e-7f);
            const float G2 = 1.f / (1.f / g1o + 1.f / g1i - 1.f);
            L += F * (D * G2 / (4.f * std::max(o.z, 1e-7f)));
        } else {
            L += F * (D * i.z / 4.f);
        }
    }
    return L * E;
}

// [SECTION] Synthesis
vec2 synthesis_inputs(const Synthesis& s, vec2 uv, int k) {
    if (s.index_map) return index_inputs(*s.index_map, s.index_detail, uv, k);
    return s.noise_texture ? s.noise_texture->inputs(uv, k) : noise_inputs(*s.cdfs, uv, k);
}

FacetBlend facets_at(const Synthesis& s, vec2 uv, float octaves) {
    const int K = s.octaves_max;
    FacetBlend b;
    const float o = std::clamp(std::isfinite(octaves) ? octaves : 0.f, 0.f, float(K));
    int k = int(std::floor(o));
    b.w = o - float(k);
    if (k >= K) k = K, b.w = 0.f;
    b.k = k;
    vec2 uc(0.f), uf(0.f);
    if (!s.index_map && !s.noise_texture && b.w > 0.f) {  // one pass over k + 1 octaves for both (noise.h)
        noise_inputs_fading(*s.cdfs, uv, k, uc, uf);
    } else {
        if (k > 0) uc = synthesis_inputs(s, uv, k);
        if (b.w > 0.f) uf = synthesis_inputs(s, uv, k + 1);
    }
    if (k > 0) b.coarse_entry = s.lut->entry(uc), b.coarse = s.lut->at(b.coarse_entry.x, b.coarse_entry.y);
    if (b.w > 0.f) b.fine_entry = s.lut->entry(uf), b.fine = s.lut->at(b.fine_entry.x, b.fine_entry.y);
    else b.fine_entry = b.coarse_entry, b.fine = b.coarse;
    return b;
}
}  // namespace mesolab::bumpsynth
