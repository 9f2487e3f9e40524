// Technique basic: CPU shading (basic.h gives the maths; gpu/basic/basic.frag is the GPU twin).
#include "core/basic/stages.h"
#include "core/parallel.h"
#include "core/basic/technique.h"
#include "core/render.h"

#include <map>

namespace mesolab::basic {

void BasicTechnique::shade_cpu(const ShadeContext& ctx) const {
    const GBuffer& gb = ctx.gbuffer;
    // Materials parsed once per frame; albedo maps by object.
    std::map<int, std::pair<Material, std::shared_ptr<const Image>>> mats;
    for (int i : ctx.objects) {
        const auto& o = ctx.scene.objects[size_t(i)];
        mats[i] = {Material::from(o.material, ctx.scene.resolve(o.material.get_string("albedo_map"))), ctx.eval.get(stages::albedo, i)};
    }
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const auto& [m, map] = mats.at(gb.object[px]);
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            vec3 n = gb.normal[px];
            if (glm::dot(n, wo) < 0.f) n = -n;  // two-sided
            vec3 tex(1.f);
            if (map) tex = sample_albedo(*map, gb.uv[px]);
            vec3 L(0.f);
            for (const Light& l : ctx.lighting.lights) {
                vec3 wi, E;
                l.sample(p, wi, E);
                const float cos_i = glm::dot(n, wi);
                if (cos_i <= 0.f) continue;
                L += brdf(m, n, wo, wi, tex) * E * cos_i;
            }
            L += m.kd * tex * kInvPi * ctx.lighting.env_irradiance(n);
            ctx.out.put(AovWriter::kRadiance, x, y, L);
            ctx.out.put(AovWriter::kNormal, x, y, n);
        }
    });
}
}  // namespace mesolab::basic
