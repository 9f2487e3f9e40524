// Technique microgeom: CPU shading of every level of detail (see microgeom.h).
#include "core/microgeom/goniometer.h"
#include "core/microgeom/technique.h"
#include "core/render.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <utility>

namespace mesolab::microgeom {

// [SECTION] CPU shading (bump level of detail; texture mode = the heightfield's texels 1:1)
void MicrogeomTechnique::shade_cpu(const ShadeContext& ctx) const {
    auto hfs = ctx.eval.get<PerObject<Heightfield>>("microgeom.heightfield");
    auto dirss = ctx.eval.get<PerObject<DirectionSet>>("microgeom.directions");
    auto viss = ctx.eval.get<PerObject<Visibility>>("microgeom.visibility");
    auto envs = ctx.eval.get<PerObject<LightScatter>>("microgeom.scatter_env");
    auto lights = ctx.eval.get<PerObject<LightsScatter>>("microgeom.scatter");
    auto tables = ctx.eval.get<PerObject<DirectionalScatter>>("microgeom.scatter_directions");
    const GBuffer& gb = ctx.gbuffer;
    Image& rad = ctx.frame.aov("radiance");
    Image& nrm = ctx.frame.aov("normal");
    Image& dir_img = ctx.frame.aov("direct");
    Image& ind_img = ctx.frame.aov("indirect");
    Image& sh_img = ctx.frame.aov("shadow");
    Image& fold_img = ctx.frame.aov("folded");
    auto imps = ctx.eval.get<PerObject<Importance>>("microgeom.importance");
    auto ells = ctx.eval.get<PerObject<EllipseMap>>("microgeom.ellipses");
    auto brdfs = ctx.eval.get<PerObject<SimulatedBrdf>>("microgeom.brdf");
    // One pixel's AOVs.
    auto store = [&](int x, int y, vec3 L, vec3 n, vec3 direct, vec3 indirect, float shadow) {
        for (auto [img, v] : {std::pair{&rad, L}, std::pair{&nrm, n}, std::pair{&dir_img, direct}, std::pair{&ind_img, indirect}}) {
            float* q = img->at(x, y);
            q[0] = v.x, q[1] = v.y, q[2] = v.z;
        }
        sh_img.at(x, y)[0] = shadow;
    };

    tbb::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const int obj = gb.object[px];
            const SceneObject& o = ctx.scene.objects[size_t(obj)];
            const Heightfield& hf = *hfs->get(obj);
            const DirectionSet& dirs = *dirss->get(obj);
            const Visibility& vis = *viss->get(obj);
            const ParamTable& m = o.material;

            // Macro frame (two-sided) and the texel position of this pixel.
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec3 N = frame.N, T = frame.T, B = frame.B;
            const float tiling = ctx.camera.texture_mode ? 1.f : float(m.get_float("tiling"));
            const vec2 uv = gb.uv[px];
            const float c = uv.x * float(hf.width) * tiling - 0.5f, r = (1.f - uv.y) * float(hf.height) * tiling - 0.5f;
            auto to_local = [&](vec3 w) { return frame.to_local(w); };

            // BRDF level: a smooth surface with the simulated BRDF (it folds in shadows, masking and
            // scattering); the environment part is exact for a constant environment and scaled by the
            // irradiance at the macro normal for a map.
            if (const SimulatedBrdf* brdf = brdfs ? brdfs->get(obj) : nullptr) {
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
            const float c0f = std::floor(c), r0f = std::floor(r), fc = c - c0f, fr = r - r0f;
            int tx[2], ty[2];
            for (int k = 0; k < 2; ++k) {
                tx[k] = ((int(c0f) + k) % hf.width + hf.width) % hf.width;
                ty[k] = ((int(r0f) + k) % hf.height + hf.height) % hf.height;
            }
            const float wts[4] = {(1 - fc) * (1 - fr), fc * (1 - fr), (1 - fc) * fr, fc * fr};
            vec3 n_loc(0.f), albedo(0.f);
            for (int k = 0; k < 4; ++k) {
                n_loc += wts[k] * hf.normal(tx[k & 1], ty[k >> 1]);
                albedo += wts[k] * hf.albedo[hf.index(tx[k & 1], ty[k >> 1])];
            }
            n_loc = glm::normalize(n_loc);
            const vec3 n = glm::normalize(T * n_loc.x + B * n_loc.y + N * n_loc.z);
            const bool phong = m.get_string("brdf") == "blinn-phong";
            const vec3 ks = phong ? m.get_vec3("ks") : vec3(0.f);
            const float shininess = float(m.get_float("shininess"));
            const bool shadows = m.get_string("shadows") != "none";
            const EllipseMap* ellipses = ells ? ells->get(obj) : nullptr;

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
                vec3 f = albedo * kInvPi;
                if (phong) {
                    const vec3 h = glm::normalize(wo + wi);
                    f += ks * (shininess + 8.f) / (8.f * kPi) * std::pow(std::max(0.f, glm::dot(n, h)), shininess);
                }
                direct += f * E * cos_i * V;
            }

            // Scattered light: environment part, plus each light's part scaled by its irradiance
            // (non-planar bases: blended over the spherical triangle of its tangent-space direction).
            vec3 E_ind(0.f);
            const LightScatter* es = envs ? envs->get(obj) : nullptr;
            if (es) E_ind += sample_bilinear(es->result.E_indirect, hf.width, hf.height, true, c, r);
            const LightsScatter* ls = lights ? lights->get(obj) : nullptr;
            for (size_t li = 0; ls && li < std::min(ls->lights.size(), ctx.lighting.lights.size()); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                E_ind += sample_bilinear(ls->lights[li].result.E_indirect, hf.width, hf.height, true, c, r) * E;
            }
            const DirectionalScatter* table = tables ? tables->get(obj) : nullptr;
            for (size_t li = 0; table && li < ctx.lighting.lights.size(); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                E_ind += table->irradiance(dirs, glm::normalize(to_local(wi)), c, r) * E;
            }
            const vec3 indirect = albedo * kInvPi * E_ind;
            store(x, y, direct + indirect, n, direct, indirect, shadow0);
            const Importance* imp = imps ? imps->get(obj) : nullptr;
            if (imp && !imp->folded.empty()) {
                const int fx = ((int(std::floor(c + 0.5f)) % hf.width) + hf.width) % hf.width, fy = ((int(std::floor(r + 0.5f)) % hf.height) + hf.height) % hf.height;
                fold_img.at(x, y)[0] = float(imp->folded[hf.index(fx, fy)]);
            }
        }
    });
}
}  // namespace mesolab::microgeom
