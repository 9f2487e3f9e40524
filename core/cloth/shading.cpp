// Technique cloth: CPU shading of the garment's pixels (reflectance.h for a point's maths).
#include "core/cloth/stages.h"
#include "core/parallel.h"
#include "core/cloth/technique.h"
#include "core/render.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace mesolab::cloth {

// [SECTION] Footprint
double uv_footprint(const GBuffer& gb, size_t pixel) {
    return double(std::max(glm::length(gb.uv_dx[pixel]), glm::length(gb.uv_dy[pixel])));
}

// [SECTION] Shading
void ClothTechnique::shade_cpu(const ShadeContext& ctx) const {
    struct Obj {
        Settings s;
        std::shared_ptr<const BrdfPyramid> pyr;
    };
    std::vector<Obj> objs(ctx.scene.objects.size());
    for (int o : ctx.objects) {
        objs[size_t(o)] = {Settings::from(ctx.scene, ctx.scene.objects[size_t(o)]), ctx.eval.get(stages::fit, o)};
        if (!objs[size_t(o)].pyr) throw std::logic_error("cloth: the evaluation lacks cloth.fit for object " + std::to_string(o));
    }
    const int out_alpha = ctx.out.index("alpha"), out_level = ctx.out.index("mip_level"), out_index = ctx.out.index("brdf_index");
    const bool constant_env = ctx.lighting.env.constant();
    const vec3 env_const = ctx.lighting.env.color * ctx.lighting.env.intensity;
    const GBuffer& gb = ctx.gbuffer;
    if (gb.uv_dx.size() != gb.uv.size()) throw std::logic_error("cloth: the G-buffer lacks uv derivatives (DrawItem::uv_derivatives)");
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const int object = gb.object[px];
            const Obj& b = objs[size_t(object)];
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame tf = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            dvec3 v = dvec3(tf.to_local(wo));
            v.z = std::max(v.z, 1e-4);
            v = glm::normalize(v);
            const double footprint = uv_footprint(gb, px) * b.s.repeat;
            const dvec2 uv = dvec2(gb.uv[px]) * b.s.repeat;
            dvec3 L(0.0);
            ClothSample last;
            bool lit = false;
            for (const Light& light : ctx.lighting.lights) {
                vec3 wi, E;
                light.sample(p, wi, E);
                const dvec3 l = dvec3(tf.to_local(wi));
                if (l.z <= 0.0) continue;  // behind the garment's surface
                last = shade(*b.pyr, uv, footprint, b.s.mip, b.s.mip_bias, l, v, dvec3(E));
                L += last.radiance;
                lit = true;
            }
            if (!lit) last = shade(*b.pyr, uv, footprint, b.s.mip, b.s.mip_bias, dvec3(0, 0, 1), v, dvec3(0.0));
            // Holes show the background along the pixel's ray (nothing in texture mode).
            vec3 bg(0.f);
            if (!ctx.camera.texture_mode) bg = constant_env ? env_const : ctx.lighting.env.radiance(ctx.camera.ray_dir(x, y));
            const float a = float(std::clamp(last.alpha, 0.0, 1.0));
            ctx.out.put(AovWriter::kRadiance, x, y, a * vec3(L) + (1.f - a) * bg);
            ctx.out.put(AovWriter::kNormal, x, y, tf.N);
            ctx.out.put(out_alpha, x, y, a);
            ctx.out.put(out_level, x, y, float(last.level));
            ctx.out.put(out_index, x, y, float(last.index));
        }
    });
}
}  // namespace mesolab::cloth
