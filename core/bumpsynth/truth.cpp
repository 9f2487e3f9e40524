// Technique bumpsynth: its truth. What the NDF and the distance-dependent octaves stand in for: per
// pixel, the footprint (a box filter: the pixel's square carried onto the surface's uv) integrated over
// the finest synthesised bumps, all bumpsynth.octaves_max octaves of them wherever the eye is, each
// bump's normal shaded with the micro-BRDF the real-time path applies at full detail (brdf.h: the NDF
// looked up in the bump's frame, Schlick's Fresnel and Smith masking as the material asks, the diffuse
// term with the albedo map).
//
// The bumps are those the synthesis draws, without its approximations: the procedural noise (never the
// baked noise texture), its inputs mapped to normals by the exact inversion of the NDF's CDFs rather
// than the nearest entry of a table, and the NDF tabulated at 512^2 cells whatever
// bumpsynth.ndf_resolution and lut_size say (technique.h, TruthNdf). With index_map on, the bump
// map's own normals through an index texture into that NDF, plus its detail octaves.
//
// Delta lights on near-mirror facets: the kernel is the NDF's cell, 2/512 of the normal's disk
// (0.22 degrees at the pole; a bump map's histogram: 2/R with R for 2 normals per cell, technique.h):
// a lobe narrower than that is spread over the cell, on the truth as in the real-time table. Everything else comes from the path tracer (core/truth/truth.h): shadows of the
// macro-surface, light between its parts and the environment where a path escapes. Paths go on from a
// bump by its lobes: the diffuse cosine-weighted about the bump's normal, the specular by reflecting
// about a normal drawn from the NDF in the bump's frame (uniform within the drawn cell: direct light,
// which looks the NDF up bilinearly, and sampled light see the same 512^2 NDF up to its interpolation).
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/technique.h"
#include "core/render.h"
#include "core/scene_stages.h"

#include <algorithm>
#include <cmath>

namespace mesolab::bumpsynth {
namespace {
float luminance(vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

class BumpsynthTruthMaterial final : public TruthMaterial {
public:
    BumpsynthTruthMaterial(std::shared_ptr<const TruthNdf> t, std::shared_ptr<const NoiseCdfs> cdfs, IndexDetail detail, int octaves,
                           ShadingModel model, std::shared_ptr<const Image> albedo)
        : t_(std::move(t)), cdfs_(std::move(cdfs)), detail_(detail), K_(octaves), model_(model), albedo_(std::move(albedo)) {}

    bool footprint() const override { return true; }

    // The point of the pixel's footprint this sample stands for.
    static vec2 uv_of(const TruthHit& h) { return h.uv + (h.jitter.x - 0.5f) * h.duv_dx + (h.jitter.y - 0.5f) * h.duv_dy; }

    // The bump at uv: its inputs at K octaves through the exact inversion of the NDF.
    LutEntry bump(vec2 uv) const {
        const vec2 u = t_->index_map ? index_inputs(*t_->index_map, detail_, uv, K_) : noise_inputs(*cdfs_, uv, K_);
        return microfacet_frame(t_->lut.sample_uniform(double(u.x), double(u.y)));
    }
    vec3 texture(vec2 uv) const { return albedo_ ? basic::sample_albedo(*albedo_, uv) : vec3(1.f); }

    vec3 fcos(const TruthHit& h, vec3 wo, vec3 wi) const override {
        const vec2 uv = uv_of(h);
        const TangentFrame fr = tangent_frame(h.n, h.tangent, wo);
        return shade_facet(model_, t_->ndf, t_->smith ? &*t_->smith : nullptr, bump(uv), fr.to_local(wo), fr.to_local(wi), vec3(1.f), texture(uv));
    }
    vec3 f(const TruthHit& h, vec3 wo, vec3 wi) const override { return fcos(h, wo, wi) / std::max(1e-6f, glm::dot(h.n, wi)); }

    // One lobe, chosen by its albedo's share: the diffuse one cosine-weighted about the bump's normal,
    // the specular one by reflecting wo about a normal the NDF draws in the bump's frame.
    vec3 sample(const TruthHit& h, vec3 wo, TruthRng& rng, vec3& wi) const override {
        const vec2 uv = uv_of(h);
        const TangentFrame fr = tangent_frame(h.n, h.tangent, wo);
        const LutEntry b = bump(uv);
        const vec3 tex = texture(uv);
        const vec3 kd = model_.kd * tex;
        const float ls = luminance(model_.ks), ld = luminance(kd);
        if (!(ls + ld > 0.f)) return vec3(0.f);
        const float ps = ls / (ls + ld);
        const vec3 wo_l = fr.to_local(wo);
        const vec3 o(glm::dot(wo_l, b.t), glm::dot(wo_l, b.b), glm::dot(wo_l, b.m));
        const float u0 = rng.next(), u1 = rng.next(), u2 = rng.next();
        vec3 i;
        vec3 w(0.f);
        if (u0 < ps) {
            if (!(o.z > 0.f)) return vec3(0.f);
            const vec3 m = t_->lut.sample_uniform(double(u1), double(u2));
            const float oh = glm::dot(o, m);
            if (!(oh > 0.f)) return vec3(0.f);
            i = 2.f * oh * m - o;
            if (!(i.z > 0.f)) return vec3(0.f);
            const vec3 F = model_.fresnel ? model_.ks + (vec3(1.f) - model_.ks) * std::pow(std::clamp(1.f - glm::dot(i, m), 0.f, 1.f), 5.f) : model_.ks;
            // f_s cos θi over the density of i, D(m) m_z / (4 o·m): D cancels.
            float g;
            if (model_.masking && t_->smith) {
                const float g1o = std::max(t_->smith->G1(o), 1e-7f), g1i = std::max(t_->smith->G1(i), 1e-7f);
                g = 1.f / (1.f / g1o + 1.f / g1i - 1.f) / std::max(o.z, 1e-7f);
            } else {
                g = i.z;
            }
            w = F * (g * oh / std::max(m.z, 1e-7f)) / ps;
        } else {
            const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
            i = vec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.f, 1.f - u1)));
            if (!(i.z > 0.f)) return vec3(0.f);
            w = kd / (1.f - ps);
        }
        const vec3 wi_l = i.x * b.t + i.y * b.b + i.z * b.m;
        if (!(wi_l.z > 0.f) || !(wo_l.z > 0.f)) return vec3(0.f);  // below the macro-surface: shade_facet's zero
        wi = glm::normalize(fr.to_world(wi_l));
        return w;
    }

private:
    std::shared_ptr<const TruthNdf> t_;
    std::shared_ptr<const NoiseCdfs> cdfs_;
    IndexDetail detail_;
    int K_;
    ShadingModel model_;
    std::shared_ptr<const Image> albedo_;
};
}  // namespace

TruthObject BumpsynthTechnique::truth_object(const Scene& s, const Evaluation& ev, int object) const {
    const SceneObject& o = s.objects.at(size_t(object));
    const ParamTable& m = o.material;
    auto t = ev.get(stages::truth_ndf, object);
    IndexDetail detail;
    if (t && t->index_map) detail = index_detail(*t->index_map, noise_from_material(m), float(m.get_float("index_noise")));
    TruthObject ob;
    ob.mesh = drawn_mesh(s, ev, object);
    ob.to_world = object_to_world(o);
    ob.material = std::make_shared<BumpsynthTruthMaterial>(std::move(t), index_mode(o) ? nullptr : ev.get(stages::noise_cdf, object), detail,
                                                           int(m.get_int("octaves_max")), shading_from_material(m), ev.get(stages::albedo, object));
    return ob;
}

std::vector<StageName> BumpsynthTechnique::truth_stages() const { return {stages::truth_ndf, stages::noise_cdf, stages::albedo}; }

std::vector<std::string> BumpsynthTechnique::truth_params() const {
    return keys({"octaves_max", "noise_frequency", "noise_gain", "noise_seed", "index_noise", "ks", "kd", "fresnel", "masking"});
}
}  // namespace mesolab::bumpsynth
