// Technique microgeom: CPU shading of every level of detail (see microgeom.h).
#include "core/microgeom/stages.h"
#include "core/parallel.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/technique.h"
#include "core/render.h"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <cmath>
#include <utility>

namespace mesolab::microgeom {

// [SECTION] The bump level's look-up (microgeom.h)
FieldSample sample_field(const Heightfield& hf, float c, float r) {
    FieldSample s;
    const float c0f = std::floor(c), r0f = std::floor(r), fc = c - c0f, fr = r - r0f;
    for (int k = 0; k < 2; ++k) {
        s.tx[k] = ((int(c0f) + k) % hf.width + hf.width) % hf.width;
        s.ty[k] = ((int(r0f) + k) % hf.height + hf.height) % hf.height;
    }
    s.w[0] = (1 - fc) * (1 - fr), s.w[1] = fc * (1 - fr), s.w[2] = (1 - fc) * fr, s.w[3] = fc * fr;
    vec3 n_loc(0.f), albedo(0.f);
    for (int k = 0; k < 4; ++k) {
        n_loc += s.w[k] * hf.normal(s.tx[k & 1], s.ty[k >> 1]);
        albedo += s.w[k] * hf.albedo[hf.index(s.tx[k & 1], s.ty[k >> 1])];
    }
    s.n_loc = glm::normalize(n_loc);
    s.albedo = albedo;
    return s;
}

// [SECTION] Per-frame inputs
Material Material::from(const ParamTable& m) {
    Material r;
    r.tiling = float(m.get_float("tiling"));
    r.phong = m.get_string("brdf") == "blinn-phong";
    r.ks = r.phong ? m.get_vec3("ks") : vec3(0.f);
    r.shininess = float(m.get_float("shininess"));
    r.shadows = m.get_string("shadows") != "none";
    return r;
}

ObjectFrame ObjectFrame::from(const Scene& s, const Evaluation& ev, int object) {
    ObjectFrame f;
    f.material = Material::from(s.objects.at(size_t(object)).material);
    f.hf = ev.get(microgeom::stages::heightfield, object);
    f.dirs = ev.get(microgeom::stages::directions, object);
    f.vis = ev.get(microgeom::stages::visibility, object);
    f.env = ev.get(microgeom::stages::scatter_env, object);
    f.lights = ev.get(microgeom::stages::scatter, object);
    f.table = ev.get(microgeom::stages::scatter_directions, object);
    f.imp = ev.get(microgeom::stages::importance, object);
    f.ell = ev.get(microgeom::stages::ellipses, object);
    f.brdf = ev.get(microgeom::stages::brdf, object);
    if (!f.hf || !f.dirs || !f.vis) throw std::logic_error("microgeom: the frame's stages were not evaluated for object " + std::to_string(object));
    return f;
}

// [SECTION] CPU shading (bump level of detail; texture mode = the heightfield's texels 1:1)
void MicrogeomTechnique::shade_cpu(const ShadeContext& ctx) const {
    // Inputs and materials parsed once per frame, by object.
    std::map<int, ObjectFrame> objects;
    for (int i : ctx.objects) objects.emplace(i, ObjectFrame::from(ctx.scene, ctx.eval, i));
    const GBuffer& gb = ctx.gbuffer;
    const AovWriter& out = ctx.out;
    const int direct_out = out.index("direct"), indirect_out = out.index("indirect"), shadow_out = out.index("shadow"), folded_out = out.index("folded");
    // One pixel's AOVs (those the frame holds).
    auto store = [&](int x, int y, vec3 L, vec3 n, vec3 direct, vec3 indirect, float shadow) {
        out.put(AovWriter::kRadiance, x, y, L);
        out.put(AovWriter::kNormal, x, y, n);
        out.put(direct_out, x, y, direct);
        out.put(indirect_out, x, y, indirect);
        out.put(shadow_out, x, y, shadow);
    };

    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const int obj = gb.object[px];
            const ObjectFrame& of = objects.at(obj);
            const Heightfield& hf = *of.hf;
            const DirectionSet& dirs = *of.dirs;
            const Visibility& vis = *of.vis;
            const Material& m = of.material;

            // Macro frame (two-sided) and the texel position of this pixel.
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec3 N = frame.N, T = frame.T, B = frame.B;
            const float tiling = ctx.camera.texture_mode ? 1.f : m.tiling;
            const vec2 uv = gb.uv[px];
            const float c = uv.x * float(hf.width) * tiling - 0.5f, r = (1.f - uv.y) * float(hf.height) * tiling - 0.5f;
            auto to_local = [&](vec3 w) { return frame.to_local(w); };

            // BRDF level: a smooth surface with the simulated BRDF (it folds in shadows, masking and
            // scattering); the environment part is exact for a constant environment and scaled by the
            // irradiance at the macro normal for a map.
            if (const SimulatedBrdf* brdf = of.brdf.get()) {
                const vec3 v_loc = to_local(wo);
                vec3 Lo_lights(0.f);
                float shadow_first = 0.f;
                for (size_t li = 0; li < ctx.lighting.lights.size(); ++li) {
                    vec3 wi, E;
                    ctx.lighting.lights[li].sample(p, wi, E);
                    const vec3 l_loc = to_local(wi);
                    Lo_lights += brdf->eval(l_loc, v_loc) * E;
                    if (li == 0) shadow_first = brdf->eval_shadow(l_loc, v_loc);
                }
                const vec3 Lo_env = ctx.lighting.env_lighting ? brdf->eval_env(v_loc) * ctx.lighting.env_irradiance(N) * kInvPi : vec3(0.f);
                store(x, y, Lo_lights + Lo_env, N, Lo_lights, Lo_env, shadow_first);
                continue;
            }

            // Micro normal and albedo, bilinear.
            const FieldSample fs = sample_field(hf, c, r);
            const int(&tx)[2] = fs.tx;
            const int(&ty)[2] = fs.ty;
            const float(&wts)[4] = fs.w;
            const vec3 n_loc = fs.n_loc, albedo = fs.albedo;
            const vec3 n = glm::normalize(T * n_loc.x + B * n_loc.y + N * n_loc.z);
            const bool phong = m.phong, shadows = m.shadows;
            const vec3 ks = m.ks;
            const float shininess = m.shininess;
            const EllipseMap* ellipses = of.ell.get();

            // Direct light: per pixel, exact shadows bilinear over the 4 texels.
            vec3 direct(0.f);
            float shadow0 = 0.f;
            for (size_t li = 0; li < ctx.lighting.lights.size(); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                const float cos_i = glm::dot(n, wi);
                float V = 0.f;
                if (cos_i > 0.f) {
                    if (!shadows) {
                        V = 1.f;
                    } else {
                        const vec3 l_loc = glm::normalize(to_local(wi));
                        if (ellipses) {
                            for (int k = 0; k < 4; ++k) {
                                const int ex = tx[k & 1], ey = ty[k >> 1];
                                if (glm::dot(hf.normal(ex, ey), l_loc) > 0.f) V += wts[k] * ellipse_visibility(ellipses->at(ex, ey), l_loc, ellipses->edge);
                            }
                        } else {
                        vec3 bary;
                        const auto& tri = dirs.triangles[size_t(dirs.locate(l_loc, bary))];
                        for (int k = 0; k < 4; ++k) V += wts[k] * visibility_fraction(hf, vis, tri, bary, tx[k & 1], ty[k >> 1], l_loc);
                        }
                    }
                }
                if (li == 0) shadow0 = V;
                if (cos_i <= 0.f || V <= 0.f) continue;
                const vec3 f = micro_brdf(albedo, n, wo, wi, phong, ks, shininess);
                direct += f * E * cos_i * V;
            }

            // Scattered light: environment part, plus each light's part scaled by its irradiance
            // (non-planar bases: blended over the spherical triangle of its tangent-space direction).
            vec3 E_ind(0.f);
            const LightScatter* es = of.env.get();
            if (es) E_ind += sample_bilinear(es->result.E_indirect, hf.width, hf.height, true, c, r);
            const LightsScatter* ls = of.lights.get();
            for (size_t li = 0; ls && li < std::min(ls->lights.size(), ctx.lighting.lights.size()); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                E_ind += sample_bilinear(ls->lights[li].result.E_indirect, hf.width, hf.height, true, c, r) * E;
            }
            const DirectionalScatter* table = of.table.get();
            for (size_t li = 0; table && li < ctx.lighting.lights.size(); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                E_ind += table->irradiance(dirs, glm::normalize(to_local(wi)), c, r) * E;
            }
            const vec3 indirect = albedo * kInvPi * E_ind;
            store(x, y, direct + indirect, n, direct, indirect, shadow0);
            const Importance* imp = of.imp.get();
            if (imp && !imp->folded.empty() && out.wanted(folded_out)) {
                const int fx = ((int(std::floor(c + 0.5f)) % hf.width) + hf.width) % hf.width, fy = ((int(std::floor(r + 0.5f)) % hf.height) + hf.height) % hf.height;
                out.put(folded_out, x, y, float(imp->folded[hf.index(fx, fy)]));
            }
        }
    });
}
}  // namespace mesolab::microgeom
