// GPU pass of technique bumpsynth: uploads the NDF, the look-up table, the resampled input CDFs, the
// noise texture and the Smith table (each once per stage result), draws a depth pre-pass and shades
// with bumpsynth.frag.
#include "core/bumpsynth/bumpsynth.h"
#include "core/bumpsynth/consistent.h"
#include "core/bumpsynth/stages.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/bumpsynth/synthesis.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>
#include <map>

namespace mesolab::gpu {
namespace {

using namespace mesolab::bumpsynth;

class BumpsynthPass final : public TechniquePass {
public:
    explicit BumpsynthPass(const Technique& t)
        : program_(Program::graphics("shaders/mesh.vert", "bumpsynth/bumpsynth.frag", {"MESOLAB_SNAP_VERTICES"}, fragment_outputs(t))),
          depth_(Program::graphics("shaders/mesh.vert", "bumpsynth/depth.frag", {"MESOLAB_SNAP_VERTICES"})) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.bumpsynth");
        // The GL objects of the stage results (made once per result, kept in the renderer's resource cache).
        GpuResources& res = ctx.renderer.resources();
        struct Bound { GLuint ndf, lut, noise, smith, albedo, index; GLuint cdf; };
        std::map<int, Bound> bound;
        for (int i : ctx.objects) {
            const Evaluation& ev = ctx.eval;
            Bound b{};
            // kautz-consistent: one layer per octave count k = 0..K of the NDF and Smith table its
            // unresolved bumps produce; the paper: one layer, the NDF's own.
            const auto consistent = ev.get(bumpsynth::stages::consistent, i);
            if (consistent) {
                b.ndf = res.get<Texture>(consistent, "consistent_ndf", [&] {
                    std::vector<const Ndf*> layers;
                    for (const Ndf& d : consistent->ndf) layers.push_back(&d);
                    return upload_ndf(layers);
                }).get();
            } else {
                b.ndf = res.get<Texture>(ev.get(bumpsynth::stages::ndf, i), "ndf", [&] { return upload_ndf({ev.get(bumpsynth::stages::ndf, i).get()}); }).get();
            }
            b.lut = res.get<Texture>(ev.get(bumpsynth::stages::lut, i), "lut", [&] { return upload_lut(*ev.get(bumpsynth::stages::lut, i)); }).get();
            if (auto index = ev.get(bumpsynth::stages::index_map, i)) {
                b.index = res.get<Texture>(index, "index_map", [&] { return upload_index(*index); }).get();
            } else if (auto cdfs = ev.get(bumpsynth::stages::noise_cdf, i)) {
                b.cdf = res.get<Buffer>(cdfs, "cdf", [&] { return make_storage_buffer(cdfs->table.data(), cdfs->table.size() * sizeof(float)); }).get();
            }
            if (auto tex = ev.get(bumpsynth::stages::noise_texture, i))
                b.noise = res.get<Texture>(tex, "noise_texture", [&] { return upload_noise(*tex); }).get();
            if (consistent && !consistent->smith.empty()) {
                b.smith = res.get<Texture>(consistent, "consistent_smith", [&] {
                    std::vector<const SmithTable*> layers;
                    for (const SmithTable& t : consistent->smith) layers.push_back(&t);
                    return upload_smith(layers);
                }).get();
            } else if (auto smith = ev.get(bumpsynth::stages::masking, i); smith && !consistent) {
                b.smith = res.get<Texture>(smith, "masking", [&] { return upload_smith({smith.get()}); }).get();
            }
            if (auto albedo = ev.get(bumpsynth::stages::albedo, i)) b.albedo = ctx.renderer.texture(albedo);
            bound[i] = b;
        }
        // Depth pre-pass: the shading pass (noise, look-ups, BRDF) then runs once per visible pixel,
        // not for every hidden fragment drawn before the nearest one (the teapot's back, its handle).
        // Texture mode draws everything at depth 0 in uv: nothing is hidden there.
        const bool prepass = !ctx.camera.texture_mode;
        if (prepass) {
            depth_.use();
            glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
            for (int i : ctx.objects) {
                ctx.renderer.set_camera_uniforms(depth_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
                ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
            }
            glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
            glDepthFunc(GL_LEQUAL);
        }
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(i)];
            const Bound& b = bound.at(i);
            const Synthesis syn = synthesis_for(ctx.scene, ctx.eval, i);  // the material, parsed once
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(o));
            program_.bind_texture(1, GL_TEXTURE_2D_ARRAY, b.ndf, "u_ndf");
            program_.bind_texture(2, GL_TEXTURE_2D_ARRAY, b.lut, "u_lut");
            program_.bind_texture(4, GL_TEXTURE_2D_ARRAY, b.smith, "u_smith");
            program_.bind_texture(5, GL_TEXTURE_2D, b.albedo, "u_albedo");
            set_synthesis_uniforms(program_, syn, {.cdf = b.cdf, .noise = b.noise, .index = b.index}, 3, 6);
            glUniform1i(program_.uniform("u_ndf_res"), syn.ndf->resolution());
            glUniform1i(program_.uniform("u_masking"), b.smith ? 1 : 0);
            glUniform1i(program_.uniform("u_fresnel"), syn.model.fresnel ? 1 : 0);
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(syn.model.ks));
            glUniform3fv(program_.uniform("u_kd"), 1, glm::value_ptr(syn.model.kd));
            glUniform1f(program_.uniform("u_detail_distance"), syn.detail_distance);
            glUniform1i(program_.uniform("u_has_albedo"), b.albedo ? 1 : 0);
            glUniform1i(program_.uniform("u_consistent"), syn.consistent ? 1 : 0);
            if (syn.consistent)
                glUniform3fv(program_.uniform("u_mean_normal"), GLsizei(syn.consistent->mean_normal.size()),
                             glm::value_ptr(syn.consistent->mean_normal[0]));
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glDepthFunc(GL_LESS);
        glBindVertexArray(0);
        check_gl("bumpsynth.draw");
    }

private:

    // NDF: (value, 1 where the cell meets the disk), cell (i, j) at texel (i + 1, j + 1) inside a
    // border of (0, 0) (bumpsynth.frag ndf_eval); one layer per table.
    static Texture upload_ndf(const std::vector<const Ndf*>& ndfs) {
        const int R = ndfs.front()->resolution(), W = R + 2;
        const size_t layer = size_t(W) * size_t(W) * 2;
        std::vector<float> rg(layer * ndfs.size(), 0.f);
        for (size_t l = 0; l < ndfs.size(); ++l)
            for (int j = 0; j < R; ++j)
                for (int i = 0; i < R; ++i) {
                    const size_t k = l * layer + (size_t(j + 1) * size_t(W) + size_t(i + 1)) * 2;
                    rg[k] = ndfs[l]->value(i, j);
                    rg[k + 1] = ndfs[l]->cell_area(i, j) > 0.0 ? 1.f : 0.f;
                }
        return make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_RG32F, .width = W, .height = W, .layers = int(ndfs.size())},
                            {GL_RG, GL_FLOAT, rg.data()});
    }

    // Look-up table: layers m, t, b.
    static Texture upload_lut(const Lut& lut) {
        const int S = lut.size();
        std::vector<float> rgba(size_t(S) * size_t(S) * 4 * 3, 0.f);
        const size_t layer = size_t(S) * size_t(S) * 4;
        for (size_t k = 0; k < lut.entries().size(); ++k) {
            const LutEntry& e = lut.entries()[k];
            for (int c = 0; c < 3; ++c) {
                rgba[k * 4 + size_t(c)] = e.m[c];
                rgba[layer + k * 4 + size_t(c)] = e.t[c];
                rgba[2 * layer + k * 4 + size_t(c)] = e.b[c];
            }
        }
        return make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_RGBA32F, .width = S, .height = S, .layers = 3}, {GL_RGBA, GL_FLOAT, rgba.data()});
    }

    // Noise texture: RG32F mip chain, fetched texel by texel (bilinear and wrapping in the shader,
    // as on the CPU: gpu/bumpsynth/noise_texture.glsl says why).
    static Texture upload_noise(const NoiseTexture& n) {
        // Complete with all its levels (texelFetch reads any level; the filters are never used).
        const TextureSpec spec{.format = GL_RG32F, .width = n.size, .height = n.size, .levels = int(n.levels.size()),
                               .min_filter = GL_NEAREST_MIPMAP_NEAREST, .mag_filter = GL_NEAREST};
        Texture t = make_texture(spec);
        for (int l = 0; l < spec.levels; ++l) upload_texture(t, spec, l, {GL_RG, GL_FLOAT, n.levels[size_t(l)].data()});
        return t;
    }

    // Index texture: RG32F, fetched texel by texel (bilinear in the shader, as on the CPU).
    static Texture upload_index(const IndexMap& m) {
        return make_texture({.format = GL_RG32F, .width = m.width, .height = m.height}, {GL_RG, GL_FLOAT, m.u.data()});
    }

    static Texture upload_smith(const std::vector<const SmithTable*>& tables) {
        std::vector<float> v;
        for (const SmithTable* t : tables) v.insert(v.end(), t->values().begin(), t->values().end());
        return make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_R32F, .width = SmithTable::kPhi, .height = SmithTable::kTheta,
                             .layers = int(tables.size())},
                            {GL_RED, GL_FLOAT, v.data()});
    }

    Program program_, depth_;
};
}  // namespace

void register_bumpsynth_gpu(std::map<std::string, PassFactory>& out) {
    out["bumpsynth"] = [](const Technique& t) { return std::make_unique<BumpsynthPass>(t); };
}
}  // namespace mesolab::gpu
