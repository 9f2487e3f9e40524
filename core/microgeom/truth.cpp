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
#include "core/scene_stages.h"

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

TruthObject MicrogeomTechnique::truth_object(const Scene& s, const Evaluation& ev, int object) const {
    const SceneObject& o = s.objects.at(size_t(object));
    const ParamTable& m = o.material;
    const bool phong = m.get_string("brdf") == "blinn-phong";
    TruthObject t;
    t.mesh = ev.get(stages::truth_surface, object);
    t.to_world = object_to_world(o);
    t.material = std::make_shared<MicrogeomTruthMaterial>(ev.get(stages::heightfield, object), float(m.get_float("tiling")), phong,
                                                          phong ? m.get_vec3("ks") : vec3(0.f), float(m.get_float("shininess")));
    return t;
}

std::vector<StageName> MicrogeomTechnique::truth_stages() const { return {stages::heightfield, stages::truth_surface}; }

std::vector<std::string> MicrogeomTechnique::truth_params() const {
    return {"microgeom.tiling", "microgeom.brdf", "microgeom.ks", "microgeom.shininess"};
}
}  // namespace mesolab::microgeom
