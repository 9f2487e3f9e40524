// GPU pass of method separable of technique translucency (core/translucency/separable.h): the
// method's objects drawn alone into the irradiance and depth targets (with the lights' shadow maps),
// the two 1D blurs as compute dispatches, then the objects drawn into the frame reading the result
// at their pixels. The work after shading lives in the pass: it needs the frame's camera and size.
#include "core/error.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "core/translucency/separable.h"
#include "core/translucency/translucency.h"
#include "gpu/renderer.h"
#include "gpu/translucency/shadow_maps.h"

#include <glm/gtc/type_ptr.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace mesolab::gpu {
namespace {

using namespace mesolab::translucency;

class SeparablePass final : public TechniquePass {
public:
    explicit SeparablePass(const Technique& t)
        : prepass_(Program::graphics("shaders/mesh.vert", "translucency/separable_prepass.frag", {"MESOLAB_SNAP_VERTICES"})),
          blur_(Program::compute("translucency/separable_blur.comp")),
          shadow_(Program::graphics("translucency/shadow.vert", "translucency/shadow.frag")),
          technique_(t) {}

    // The technique declares more outputs than one framebuffer takes (as its own pass).
    bool output_variants() const override { return true; }

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.translucency/separable");
        if (ctx.camera.texture_mode)
            throw InputError("translucency.method = separable blurs in screen space: camera.mode = texture has no screen (use orbit)");
        GLint frame_fbo = 0, viewport[4] = {0, 0, 0, 0};
        glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &frame_fbo);
        glGetIntegerv(GL_VIEWPORT, viewport);
        const int W = ctx.camera.raster.width, H = ctx.camera.raster.height;
        resize(W, H);

        std::vector<Obj> objs;
        for (int o : ctx.objects) {
            const SceneObject& obj = ctx.scene.objects[size_t(o)];
            Obj b;
            b.o = o;
            b.s = Settings::from(obj, Settings::Medium_ | Settings::Shadows);
            b.s.burley = obj.material.get_string("separable_profile") == "burley";
            b.taps = int(obj.material.get_int("separable_taps"));
            b.mm_per_world = float(obj.material.get_float("mm_per_unit"));
            if (b.s.shadows) b.frames = draw_shadow_maps(ctx, o, *drawn_mesh(ctx.scene, ctx.eval, o), b.s.shadow_map, shadow_, shadows_[o]);
            objs.push_back(std::move(b));
        }

        // Irradiance, depth and pixel size of the method's objects alone.
        pre_.bind();
        const float none[4] = {0.f, 0.f, -1.f, 0.f}, zero[4] = {0.f, 0.f, 0.f, 0.f}, one = 1.f;
        glDepthMask(GL_TRUE);
        glClearNamedFramebufferfv(pre_.fbo(), GL_COLOR, 0, zero);
        glClearNamedFramebufferfv(pre_.fbo(), GL_COLOR, 1, none);
        glClearNamedFramebufferfv(pre_.fbo(), GL_DEPTH, 0, &one);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        prepass_.use();
        ctx.renderer.set_lighting_uniforms(prepass_, ctx.lighting, 0);
        glUniformMatrix4fv(prepass_.uniform("u_view"), 1, GL_FALSE, glm::value_ptr(ctx.camera.raster.view));
        glUniform1f(prepass_.uniform("u_proj11"), ctx.camera.raster.proj[1][1]);
        glUniform1f(prepass_.uniform("u_height"), float(H));
        for (const Obj& b : objs) {
            ctx.renderer.set_camera_uniforms(prepass_, ctx.camera, object_to_world(ctx.scene.objects[size_t(b.o)]));
            set_shadow_uniforms(prepass_, b.frames, shadows_[b.o], b.s.shadow_map, 6);
            glUniform1f(prepass_.uniform("u_eta"), float(b.s.medium.eta));
            glUniform1f(prepass_.uniform("u_env_transmittance"), float(diffuse_transmittance(b.s.medium.eta)));
            glUniform1f(prepass_.uniform("u_mm_per_world"), b.mm_per_world);
            glUniform1f(prepass_.uniform("u_object"), float(b.o));
            ctx.renderer.draw_object(ctx.scene, ctx.eval, b.o);
        }
        glBindVertexArray(0);

        // The two blurs, object by object (each with its material's kernel).
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
        blur_.use();
        const GLuint groups_x = GLuint((W + 7) / 8), groups_y = GLuint((H + 7) / 8);
        for (const Obj& b : objs) {
            const SeparableKernel& k = *separable_kernel(b.s.medium, b.s.burley, b.taps);
            std::vector<vec4> taps(k.offset_mm.size());
            for (size_t i = 0; i < taps.size(); ++i) taps[i] = vec4(k.weight[i], k.offset_mm[i]);
            glUniform1i(blur_.uniform("u_taps"), int(taps.size()));
            glUniform4fv(blur_.uniform("u_tap[0]"), GLsizei(taps.size()), glm::value_ptr(taps[0]));
            glUniform1f(blur_.uniform("u_object"), float(b.o));
            blur_.bind_texture(1, GL_TEXTURE_2D, pre_.color(1), "u_geom");
            for (int pass = 0; pass < 2; ++pass) {
                blur_.bind_texture(0, GL_TEXTURE_2D, pass == 0 ? pre_.color(0) : across_.get(), "u_value");
                glBindImageTexture(0, pass == 0 ? across_.get() : blurred_.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
                glUniform1i(blur_.uniform("u_vertical"), pass);
                glDispatchCompute(groups_x, groups_y, 1);
                glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
            }
        }
        glBindImageTexture(0, 0, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);

        // Into the frame.
        glBindFramebuffer(GL_FRAMEBUFFER, GLuint(frame_fbo));
        glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        const Program& p = display(ctx.outputs);
        p.use();
        p.bind_texture(1, GL_TEXTURE_2D, blurred_.get(), "u_B");
        p.bind_texture(2, GL_TEXTURE_2D, pre_.color(0), "u_E");
        for (const Obj& b : objs) {
            ctx.renderer.set_camera_uniforms(p, ctx.camera, object_to_world(ctx.scene.objects[size_t(b.o)]));
            glUniform1f(p.uniform("u_eta"), float(b.s.medium.eta));
            glUniform1f(p.uniform("u_t_mean"), float(diffuse_transmittance(b.s.medium.eta)));
            ctx.renderer.draw_object(ctx.scene, ctx.eval, b.o);
        }
        glBindVertexArray(0);
        check_gl("translucency/separable.draw");
    }

private:
    // An object's keys, read once per frame, and its shadow maps' frames.
    struct Obj {
        int o = 0;
        Settings s;
        int taps = 0;
        float mm_per_world = 1.f;
        std::vector<ShadowMap> frames;
    };

    void resize(int W, int H) {
        pre_.resize(W, H, 2);
        if (W == width_ && H == height_) return;
        across_ = make_texture({.format = GL_RGBA32F, .width = W, .height = H});
        blurred_ = make_texture({.format = GL_RGBA32F, .width = W, .height = H});
        width_ = W, height_ = H;
    }

    const Program& display(const std::vector<std::string>& outputs) {
        std::string key;
        for (const std::string& o : outputs) key += " " + o;
        auto it = display_.find(key);
        if (it != display_.end()) return it->second;
        return display_.emplace(key, Program::graphics("shaders/mesh.vert", "translucency/separable.frag", {"MESOLAB_SNAP_VERTICES"},
                                                       fragment_outputs(technique_, outputs)))
            .first->second;
    }

    Program prepass_, blur_, shadow_;
    const Technique& technique_;
    std::map<std::string, Program> display_;  // by the batch's outputs
    std::map<int, ShadowLayers> shadows_;
    RenderTarget pre_;  // 0: irradiance, 1: view depth (mm), pixel size (mm), object
    Texture across_, blurred_;
    int width_ = 0, height_ = 0;
};
}  // namespace

void register_translucency_separable_gpu(std::map<std::string, PassFactory>& out) {
    out["translucency/separable"] = [](const Technique& t) { return std::make_unique<SeparablePass>(t); };
}
}  // namespace mesolab::gpu
