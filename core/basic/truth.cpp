// Technique basic: its truth. The object's own mesh with the same material (Lambert with the
// albedo map, energy-normalised Blinn-Phong), path traced: what the rasteriser leaves out is the
// shadows, the interreflections and the environment's exact (not SH9) light.
#include "core/basic/stages.h"
#include "core/basic/technique.h"
#include "core/scene_stages.h"

#include <algorithm>
#include <cmath>

namespace mesolab::basic {
namespace {
class BasicTruthMaterial final : public TruthMaterial {
public:
    BasicTruthMaterial(Material m, std::shared_ptr<const Image> map) : m_(std::move(m)), map_(std::move(map)) {}
    vec3 f(const TruthHit& h, vec3 wo, vec3 wi) const override {
        return brdf(m_, h.n, wo, wi, map_ ? sample_albedo(*map_, h.uv) : vec3(1.f));
    }
    // A mixture of the cosine lobe and the Blinn-Phong lobe, chosen in proportion to the weights
    // kd and ks (mean over channels): the half vector h with pdf (s + 1) / (2π) cos^s θh, so wi has
    // (s + 1) / (2π) cos^s θh / (4 wo·h). The weight is f cos θi over the mixture's pdf.
    vec3 sample(const TruthHit& h, vec3 wo, TruthRng& rng, vec3& wi) const override {
        const float kd = (m_.kd.x + m_.kd.y + m_.kd.z) / 3.f, ks = (m_.ks.x + m_.ks.y + m_.ks.z) / 3.f;
        const float p_spec = kd + ks > 0.f ? ks / (kd + ks) : 0.f;
        const vec3 t = std::fabs(h.n.x) > 0.9f ? glm::normalize(glm::cross(vec3(0.f, 1.f, 0.f), h.n)) : glm::normalize(glm::cross(vec3(1.f, 0.f, 0.f), h.n));
        const vec3 b = glm::cross(h.n, t);
        const float u0 = rng.next(), u1 = rng.next(), u2 = rng.next();
        const float phi = 2.f * kPi * u2;
        if (u0 < p_spec) {
            const float cos_h = std::pow(u1, 1.f / (m_.shininess + 1.f)), sin_h = std::sqrt(std::max(0.f, 1.f - cos_h * cos_h));
            const vec3 hv = sin_h * std::cos(phi) * t + sin_h * std::sin(phi) * b + cos_h * h.n;
            wi = 2.f * glm::dot(wo, hv) * hv - wo;
        } else {
            const float r = std::sqrt(u1);
            wi = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.f, 1.f - u1)) * h.n;
        }
        const float cos_i = glm::dot(wi, h.n);
        if (cos_i <= 0.f) return vec3(0.f);
        const vec3 hv = glm::normalize(wo + wi);
        const float cos_h = std::max(0.f, glm::dot(hv, h.n)), wo_h = glm::dot(wo, hv);
        const float pdf_spec = wo_h > 0.f ? (m_.shininess + 1.f) / (2.f * kPi) * std::pow(cos_h, m_.shininess) / (4.f * wo_h) : 0.f;
        const float pdf = (1.f - p_spec) * cos_i * kInvPi + p_spec * pdf_spec;
        if (!(pdf > 0.f)) return vec3(0.f);
        return f(h, wo, wi) * (cos_i / pdf);
    }

private:
    Material m_;
    std::shared_ptr<const Image> map_;
};
}  // namespace

TruthObject truth_object(const Scene& s, const Evaluation& ev, int object) {
    const SceneObject& o = s.objects.at(size_t(object));
    TruthObject t;
    t.mesh = ev.get(mesolab::stages::geometry, object);
    t.to_world = object_to_world(o);
    t.material = std::make_shared<BasicTruthMaterial>(Material::from(o.material, s.resolve(o.material.get_string("albedo_map"))),
                                                      ev.get(stages::albedo, object));
    return t;
}

std::optional<TruthDecl> BasicTechnique::truth() const {
    return TruthDecl{.params = {"basic.kd", "basic.ks", "basic.shininess", "basic.albedo_map"},
                     .stages = {stages::albedo},
                     .object = truth_object};
}
}  // namespace mesolab::basic
