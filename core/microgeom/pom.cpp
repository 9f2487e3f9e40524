// Method pom of technique microgeom: parallax occlusion mapping with self-shadowing (see pom.h).
// Its keys, its stage (the heights in texel units), the march and its CPU shading; the GPU pass
// is gpu/microgeom/pom_pass.cpp with pom.frag.
#include "core/microgeom/pom.h"
#include "core/microgeom/microgeom.h"
#include "core/microgeom/stages.h"
#include "core/parallel.h"
#include "core/render.h"
#include "core/technique.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace mesolab::microgeom {

// [SECTION] The field and the march
PomField PomField::from(const Heightfield& hf) {
    PomField f;
    f.width = hf.width, f.height = hf.height;
    double mean = 0.0;
    for (float h : hf.h) mean += h;
    mean /= double(std::max<size_t>(1, hf.h.size()));
    const float inv_s = 1.f / hf.texel_size;
    f.z.resize(hf.h.size());
    for (size_t i = 0; i < hf.h.size(); ++i) f.z[i] = (hf.h[i] - float(mean)) * inv_s;
    if (!f.z.empty()) {
        const auto [lo, hi] = std::minmax_element(f.z.begin(), f.z.end());
        f.z_min = *lo, f.z_max = *hi;
    }
    return f;
}

PomHit pom_march(const PomField& f, float c0, float r0, vec3 v, int steps, int refine) {
    const float vz = std::max(v.z, kPomMinCos);
    const float dc = v.x / vz, dr = -v.y / vz;
    // g(z) = z - H(p(z)): > 0 above the field, <= 0 at or below it.
    const auto g = [&](float z) { return z - f.at(c0 + z * dc, r0 + z * dr); };
    const float span = f.z_max - f.z_min;
    if (!(span > 0.f)) return {c0 + f.z_max * dc, r0 + f.z_max * dr, f.z_max};
    // 1. Linear search from the top: the first height at or below the field.
    const int n = std::max(1, steps);
    const float dz = span / float(n);
    float z_hi = f.z_max, z_lo = f.z_min;
    for (int i = 1; i <= n; ++i) {
        const float z = i == n ? f.z_min : f.z_max - float(i) * dz;
        if (i == n || g(z) <= 0.f) {
            z_lo = z, z_hi = i == 1 ? f.z_max : f.z_max - float(i - 1) * dz;
            break;
        }
    }
    // 2. Halvings of the bracket, then one secant step through its ends.
    for (int k = 0; k < refine; ++k) {
        const float zm = 0.5f * (z_lo + z_hi);
        if (g(zm) <= 0.f) z_lo = zm;
        else z_hi = zm;
    }
    // (A ray that touches the field at the bracket's top, g = 0 there, hits there.)
    const float g_hi = g(z_hi), g_lo = g(z_lo);
    const float t = g_hi <= 0.f ? 0.f : g_lo <= 0.f ? g_hi / (g_hi - g_lo) : 1.f;
    const float z = z_hi + t * (z_lo - z_hi);
    return {c0 + z * dc, r0 + z * dr, z};
}

float pom_visibility(const PomField& f, float c, float r, float z, vec3 l, int steps) {
    if (steps <= 0) return 1.f;
    if (!(l.z > 0.f)) return 0.f;
    const float lz = std::max(l.z, kPomMinCos);
    const float dc = l.x / lz, dr = -l.y / lz;
    const float span = f.z_max - z;
    if (!(span > 0.f)) return 1.f;
    const float dz = span / float(steps);
    const float bias = 1e-3f * (f.z_max - f.z_min);
    for (int j = 1; j < steps; ++j) {  // the last height is z_max: nothing rises above it
        const float zj = float(j) * dz;
        if (f.at(c + zj * dc, r + zj * dr) > z + zj + bias) return 0.f;
    }
    return 1.f;
}

namespace {

// [SECTION] The method
class PomMethod final : public Method {
public:
    PomMethod() : Method("microgeom", "pom", "Parallax occlusion mapping with self-shadowing (Tatarchuk 2006; Policarpo et al. 2005)") {}

    void declare_params(ParamGroup& p) const override {
        p.add_int("pom_steps", 32).used_when("method", {"pom"}).range(1, 1024).log().more_accurate(Accuracy::Higher, int64_t(512))
            .doc("Parallax occlusion mapping: heights sampled along the view ray between the field's top and bottom in the linear search");
        p.add_int("pom_refine", 4).used_when("method", {"pom"}).range(0, 24).more_accurate(Accuracy::Higher, int64_t(16))
            .doc("Halvings of the step that brackets the hit (binary search), before one secant step through its ends");
        p.add_int("pom_shadow_steps", 32).used_when("method", {"pom"}).range(0, 1024).more_accurate(Accuracy::Higher, int64_t(512))
            .doc("Heights sampled along the ray from the hit towards each light for self-shadowing (hard shadows); 0: none");
        p.section("Parallax occlusion mapping", {"pom_steps", "pom_refine", "pom_shadow_steps"});
    }

    void declare_stages(StageGraph& g) const override {
        g.add(stages::pom_field, {.help = "The heights in texel units above the base and their range, for parallax occlusion mapping",
                                  .scope = StageScope::Object,
                                  .technique = "microgeom",
                                  .inputs = {stages::heightfield},
                                  .run = [](StageContext& ctx) { return stage_result(stages::pom_field, PomField::from(*ctx.input(stages::heightfield))); }});
    }

    std::vector<StageName> frame_stages() const override { return {stages::heightfield, stages::pom_field}; }

    void shade_cpu(const ShadeContext& ctx) const override;

    // Both paths march the same texel-space ray through the same bilinear heights (texelFetch
    // with the CPU's weights) with the same steps; what differs is float evaluation, which can
    // move a hit across a step of the linear search or a shadow test across the field's height
    // where a ray grazes a feature: there a pixel shows another point of the field. Measured
    // (llvmpipe, 2 cores; tests/microgeom/pom_test.cpp and the pom presets): off edges every value
    // within 2e-4, no outlier; interior_outliers 1e-3 leaves room for another GPU's fused
    // multiply-adds at grazing rays.
    FrameAgreement agreement() const override {
        return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.995, .interior_max = 2e-3, .interior_outliers = 1e-3,
                .why = "float evaluation; the march's steps and shadow tests are discrete choices where a ray grazes the field"};
    }
};

struct PomObject {
    std::shared_ptr<const Heightfield> hf;
    std::shared_ptr<const PomField> field;
    PomSettings st;
    FieldMaterial mat;
};

void PomMethod::shade_cpu(const ShadeContext& ctx) const {
    std::map<int, PomObject> objects;
    for (int i : ctx.objects) {
        const ParamTable& m = ctx.scene.objects[size_t(i)].material;
        PomObject o;
        o.hf = ctx.eval.get(stages::heightfield, i);
        o.field = ctx.eval.get(stages::pom_field, i);
        if (!o.hf || !o.field) throw std::logic_error("microgeom/pom: the frame's stages were not evaluated for object " + std::to_string(i));
        o.st = {int(m.get_int("pom_steps")), int(m.get_int("pom_refine")), int(m.get_int("pom_shadow_steps"))};
        o.mat = FieldMaterial::from(m, ctx.camera.texture_mode);
        objects.emplace(i, std::move(o));
    }
    const GBuffer& gb = ctx.gbuffer;
    const AovWriter& out = ctx.out;
    const int direct_out = out.index("direct"), indirect_out = out.index("indirect"), shadow_out = out.index("shadow"), folded_out = out.index("folded");
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const PomObject& o = objects.at(gb.object[px]);
            const Heightfield& hf = *o.hf;
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec2 uv = gb.uv[px];
            const float c0 = uv.x * float(hf.width) * o.mat.tiling - 0.5f, r0 = (1.f - uv.y) * float(hf.height) * o.mat.tiling - 0.5f;
            const PomHit hit = pom_march(*o.field, c0, r0, frame.to_local(wo), o.st.steps, o.st.refine);

            // The heightfield's normal and albedo at the hit, bilinear (as the bump level).
            const FieldSample fs = sample_field(hf, hit.c, hit.r);
            const vec3 n_loc = fs.n_loc, albedo = fs.albedo;
            const vec3 n = glm::normalize(frame.T * n_loc.x + frame.B * n_loc.y + frame.N * n_loc.z);

            vec3 direct(0.f);
            float shadow0 = 0.f;
            for (size_t li = 0; li < ctx.lighting.lights.size(); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                const float cos_i = glm::dot(n, wi);
                const float V = cos_i > 0.f ? pom_visibility(*o.field, hit.c, hit.r, hit.z, glm::normalize(frame.to_local(wi)), o.st.shadow_steps) : 0.f;
                if (li == 0) shadow0 = V;
                if (cos_i <= 0.f || V <= 0.f) continue;
                const vec3 f = micro_brdf(albedo, n, wo, wi, o.mat.phong, o.mat.ks, o.mat.shininess);
                direct += f * E * cos_i * V;
            }
            const vec3 env = ctx.lighting.env_lighting ? albedo * kInvPi * ctx.lighting.env_irradiance(n) : vec3(0.f);
            out.put(AovWriter::kRadiance, x, y, direct + env);
            out.put(AovWriter::kNormal, x, y, n);
            out.put(direct_out, x, y, direct);
            out.put(indirect_out, x, y, env);
            out.put(shadow_out, x, y, shadow0);
            out.put(folded_out, x, y, 0.f);
        }
    });
}
}  // namespace
}  // namespace mesolab::microgeom

namespace mesolab {
void register_microgeom_pom(Registry& r) { r.add_method(std::make_unique<microgeom::PomMethod>()); }
}  // namespace mesolab
