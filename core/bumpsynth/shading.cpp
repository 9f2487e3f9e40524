// Technique bumpsynth: CPU shading (brdf.h gives the synthesis and the BRDF;
// gpu/bumpsynth/bumpsynth.frag is the GPU twin).
#include "core/bumpsynth/consistent.h"
#include "core/bumpsynth/stages.h"
#include "core/parallel.h"
#include "core/bumpsynth/technique.h"
#include "core/render.h"

#include <algorithm>
#include <cmath>

namespace mesolab::bumpsynth {

void BumpsynthTechnique::shade_cpu(const ShadeContext& ctx) const {
    const GBuffer& gb = ctx.gbuffer;
    const int octaves_out = ctx.out.index("octaves"), entry_out = ctx.out.index("entry"), entry_fine_out = ctx.out.index("entry_fine");
    // Materials parsed once per frame into each object's synthesis.
    std::map<int, Synthesis> syns;
    for (int i : ctx.objects) syns[i] = synthesis_for(ctx.scene, ctx.eval, i);
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const int obj = gb.object[px];
            const Synthesis& syn = syns.at(obj);
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec2 uv = gb.uv[px];
            const float o = pixel_octaves(syn, ctx.camera.texture_mode, ctx.camera.eye, p);
            const FacetBlend fb = facets_at(syn, uv, o);
            const vec3 tex = syn.albedo ? basic::sample_albedo(*syn.albedo, uv) : vec3(1.f);
            const vec3 wo_t = frame.to_local(wo);
            // The facet of k octaves, shaded with the NDF (the paper) or with the NDF its unresolved
            // bumps produce, their mean normal for the diffuse term (kautz-consistent).
            auto shade = [&](const LutEntry& f, int k) {
                const ConsistentNdfs* c = syn.consistent;
                const Ndf& ndf = c ? c->ndf[size_t(k)] : *syn.ndf;
                const SmithTable* smith = c ? (c->smith.empty() ? nullptr : &c->smith[size_t(k)]) : syn.smith;
                const vec3* mean = c ? &c->mean_normal[size_t(k)] : nullptr;
                vec3 L(0.f);
                for (const Light& l : ctx.lighting.lights) {
                    vec3 wi, E;
                    l.sample(p, wi, E);
                    L += shade_facet(syn.model, ndf, smith, f, wo_t, frame.to_local(wi), E, tex, mean);
                }
                if (!mean) return L + syn.model.kd * tex * kInvPi * ctx.lighting.env_irradiance(frame.to_world(f.m));
                const vec3 mbar = mean->x * f.t + mean->y * f.b + mean->z * f.m;  // in the macro tangent frame
                const float len = glm::length(mbar);
                return L + syn.model.kd * tex * (kInvPi * len) * ctx.lighting.env_irradiance(frame.to_world(mbar / len));
            };
            const vec3 L = fb.w > 0.f ? glm::mix(shade(fb.coarse, fb.k), shade(fb.fine, fb.k + 1), fb.w) : shade(fb.coarse, fb.k);
            const vec3 n = fb.w > 0.f ? glm::normalize(glm::mix(fb.coarse.m, fb.fine.m, fb.w)) : fb.coarse.m;
            ctx.out.put(AovWriter::kRadiance, x, y, L);
            ctx.out.put(AovWriter::kNormal, x, y, n);
            ctx.out.put(octaves_out, x, y, o);
            ctx.out.put(entry_out, x, y, vec3(vec2(fb.coarse_entry), float(fb.k)));
            ctx.out.put(entry_fine_out, x, y, vec3(vec2(fb.fine_entry), float(fb.w > 0.f ? fb.k + 1 : fb.k)));
        }
    });
}
}  // namespace mesolab::bumpsynth
