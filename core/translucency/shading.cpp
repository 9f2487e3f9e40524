// Technique translucency: CPU shading, L_o = rho T(cos theta_o) B / pi (gpu/translucency/translucency.frag is the GPU twin).
#include "core/error.h"
#include "core/parallel.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/technique.h"
#include "core/translucency/reference.h"
#include "core/translucency/paper.h"
#include "core/translucency/technique.h"
#include "core/translucency/translucency.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace mesolab::translucency {

void TranslucencyTechnique::shade_cpu(const ShadeContext& ctx) const {
    struct Obj {
        Settings s;
        const Maps* maps = nullptr;
        const std::vector<vec3>* reference = nullptr;
        std::shared_ptr<const std::vector<vec3>> rho;
        int size = 0;
    };
    const auto& maps = ctx.step(steps::combine);
    const auto& refs = ctx.step(steps::reference);
    std::vector<Obj> objs(ctx.scene.objects.size());  // by object id
    for (int o : ctx.objects) {
        Obj& b = objs[size_t(o)];
        b.s = Settings::from(ctx.scene.objects[size_t(o)]);
        b.maps = &maps.at(o);
        if (auto it = refs.find(o); it != refs.end()) b.reference = &it->second;
        b.rho = ctx.eval.get(stages::albedo, o);
        b.size = ctx.eval.get(stages::atlas, o)->atlas.size;
    }
    const int out_irr = ctx.out.index("irradiance"), out_rad = ctx.out.index("radiosity"), out_loc = ctx.out.index("local"),
              out_glo = ctx.out.index("global"), out_ref = ctx.out.index("reference"), out_err = ctx.out.index("error"),
              out_exi = ctx.out.index("exitance");
    // The parts only the displayed response or a requested AOV needs are looked up.
    const bool parts = ctx.out.wanted(out_rad) || ctx.out.wanted(out_loc) || ctx.out.wanted(out_glo) || ctx.out.wanted(out_ref) || ctx.out.wanted(out_err);
    const GBuffer& gb = ctx.gbuffer;
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const Obj& b = objs[size_t(gb.object[px])];
            const TexelTap tap(b.size, gb.uv[px]);
            const vec3 wo = ctx.camera.wo(gb.position[px]);
            vec3 n = gb.normal[px];
            if (glm::dot(n, wo) < 0.f) n = -n;
            const Response r = b.s.response;
            const bool need_local = parts || r == Response::Both || r == Response::Local;
            const bool need_global = parts || r == Response::Both || r == Response::Global;
            const vec3 local = need_local ? tap(*b.maps, &MapTexel::local) : vec3(0.f), global = need_global ? tap(*b.maps, &MapTexel::global) : vec3(0.f);
            const vec3 ref = b.reference ? tap(*b.reference) : vec3(0.f);
            const vec3 B = r == Response::Local ? local : r == Response::Global ? global : r == Response::Reference ? ref : local + global;
            const vec3 rho = b.rho ? tap(*b.rho) : vec3(1.f);
            const float T = float(fresnel_transmittance(std::clamp(glm::dot(n, wo), 0.f, 1.f), b.s.medium.eta));
            ctx.out.put(AovWriter::kRadiance, x, y, rho * B * (T * kInvPi));
            ctx.out.put(AovWriter::kNormal, x, y, n);
            if (ctx.out.wanted(out_irr)) ctx.out.put(out_irr, x, y, tap(*b.maps, &MapTexel::irradiance));
            // ∫ L_o cos θo dωo / rho = B (2 ∫ T(μ) μ dμ): the hemispherical mean of T (dipole.h).
            if (ctx.out.wanted(out_exi)) ctx.out.put(out_exi, x, y, B * float(diffuse_transmittance(b.s.medium.eta)));
            if (!parts) continue;
            ctx.out.put(out_rad, x, y, local + global);
            ctx.out.put(out_loc, x, y, local);
            ctx.out.put(out_glo, x, y, global);
            ctx.out.put(out_ref, x, y, ref);
            ctx.out.put(out_err, x, y, b.reference ? local + global - ref : vec3(0.f));
        }
    });
}
}  // namespace mesolab::translucency
