// Technique microgeom: its truth. The heightfield as explicit triangles through its texel centres
// on the base surface, tiled microgeom.tiling times and bent by the curvature on a plane (lod.h,
// truth_surface), shaded with the triangles' geometric normals and the micro-BRDF the real-time
// path applies: Lambert with the texels' albedo (bilinear, as the shading reads it) at every
// bounce, plus the normalised Blinn-Phong lobe for the direct light reflected towards the viewer
// (microgeom.brdf = blinn-phong; the scattering inside the field is Lambertian on both paths).
// Shadows, masking, every bounce and the environment where a path escapes come from the path
// tracer (core/truth/truth.h).
#include "core/heightfield/heightfield.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/technique.h"
#include "core/render.h"
#include "core/scene_stages.h"

#include <algorithm>
#include <cmath>

namespace mesolab::microgeom {
namespace {
class MicrogeomTruthMaterial final : public TruthMaterial {
public:
    MicrogeomTruthMaterial(std::shared_ptr<const Heightfield> hf, float tiling, bool phong, vec3 ks, float shininess)
        : hf_(std::move(hf)), tiling_(tiling), phong_(phong), ks_(ks), shininess_(shininess) {}

    vec3 albedo(const TruthHit& h) const {
        const float c = h.uv.x * float(hf_->width) * tiling_ - 0.5f, r = (1.f - h.uv.y) * float(hf_->height) * tiling_ - 0.5f;
        return sample_bilinear(hf_->albedo, hf_->width, hf_->height, true, c, r);
    }
    vec3 f(const TruthHit& h, vec3 wo, vec3 wi) const override {
        vec3 f = albedo(h) * kInvPi;
        if (phong_ && h.depth == 0) {
            const vec3 hv = glm::normalize(wo + wi);
            f += ks_ * (shininess_ + 8.f) / (8.f * kPi) * std::pow(std::max(0.f, glm::dot(h.n, hv)), shininess_);
        }
        return f;
    }
    // Paths continue by the Lambertian part only (cosine-weighted: the weight is the albedo).
    vec3 sample(const TruthHit& h, vec3 wo, TruthRng& rng, vec3& wi) const override {
        (void)wo;
        const float u1 = rng.next(), u2 = rng.next();
        const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
        const vec3 t = std::fabs(h.n.x) > 0.9f ? glm::normalize(glm::cross(vec3(0.f, 1.f, 0.f), h.n)) : glm::normalize(glm::cross(vec3(1.f, 0.f, 0.f), h.n));
        const vec3 b = glm::cross(h.n, t);
        const float z = std::sqrt(std::max(0.f, 1.f - u1));
        wi = r * std::cos(phi) * t + r * std::sin(phi) * b + z * h.n;
        if (z <= 0.f) return vec3(0.f);
        return albedo(h);
    }

private:
    std::shared_ptr<const Heightfield> hf_;
    float tiling_;
    bool phong_;
    vec3 ks_;
    float shininess_;
};
}  // namespace

TruthObject truth_object(const Scene& s, const Evaluation& ev, int object) {
    const SceneObject& o = s.objects.at(size_t(object));
    const ParamTable& m = o.material;
    const bool phong = m.get_string("brdf") == "blinn-phong";
    TruthObject t;
    t.mesh = ev.get(stages::truth_surface, object);
    t.to_world = object_to_world(o);
    t.material = std::make_shared<MicrogeomTruthMaterial>(ev.get(stages::heightfield, object), truth_tiling(s, o), phong,
                                                          phong ? m.get_vec3("ks") : vec3(0.f), float(m.get_float("shininess")));
    return t;
}

float truth_tiling(const Scene& s, const SceneObject& o) {
    if (s.camera.get_string("mode") != "texture") return float(o.material.get_float("tiling"));
    return o.geometry.get_string("type") == "plane" ? 3.f : 1.f;
}

// Texture mode: the heights' largest reach above the base, in object units (the displacement of
// lod.h at the largest world length per uv unit of the drawn base's triangles), and, on a bent
// plane, the bend's sag over the three tiles.
float truth_lift(const Scene& s, const Evaluation& ev, int object) {
    const SceneObject& o = s.objects.at(size_t(object));
    const auto hf = ev.get(stages::heightfield, object);
    const auto base = drawn_mesh(s, ev, object);
    if (!hf || !base) return 0.f;
    double per_uv = 0.0;
    for (size_t t = 0; t < base->triangle_count(); ++t) {
        const uint32_t a = base->index[3 * t], b = base->index[3 * t + 1], c = base->index[3 * t + 2];
        const double aw = 0.5 * double(glm::length(glm::cross(base->position[b] - base->position[a], base->position[c] - base->position[a])));
        const vec2 e1 = base->uv[b] - base->uv[a], e2 = base->uv[c] - base->uv[a];
        const double auv = 0.5 * std::fabs(double(e1.x) * e2.y - double(e1.y) * e2.x);
        if (auv > 0.0) per_uv = std::max(per_uv, std::sqrt(aw / auv));
    }
    double mean = 0.0, reach = 0.0;
    for (float h : hf->h) mean += h;
    mean /= double(std::max<size_t>(1, hf->h.size()));
    for (float h : hf->h) reach = std::max(reach, std::fabs(double(h) - mean));
    double lift = reach / hf->texel_size * per_uv / double(hf->width);
    const double bend = std::max(std::fabs(o.material.get_float("curvature_u")), std::fabs(o.material.get_float("curvature_v")));
    if (bend > 0.0) lift += 3.0;  // the plane's half-width three times over: above any bent copy
    return float(1.5 * lift);
}

std::optional<TruthDecl> MicrogeomTechnique::truth() const {
    return TruthDecl{.params = {"microgeom.tiling", "microgeom.brdf", "microgeom.ks", "microgeom.shininess", "microgeom.curvature_u", "microgeom.curvature_v"},
                     .stages = {stages::heightfield, stages::truth_surface},
                     .object = truth_object,
                     .lift = truth_lift};
}
}  // namespace mesolab::microgeom
