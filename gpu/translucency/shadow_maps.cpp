// Technique translucency on the GPU: the lights' shadow maps of one object (see shadow_maps.h).
#include "gpu/translucency/shadow_maps.h"
#include "core/scene_stages.h"

#include <glm/gtc/type_ptr.hpp>
#include <algorithm>
#include <cmath>
#include <string>

namespace mesolab::gpu {

using translucency::ShadowMap;

void ShadowLayers::resize(int r, int n) {
    if (r == res && n == layers) return;
    color = make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_R32F, .width = r, .height = r, .layers = n});
    depth = make_texture({.format = GL_DEPTH_COMPONENT32F, .width = r, .height = r});
    GLuint id = 0;
    glCreateFramebuffers(1, &id);
    fbo = Framebuffer(id);
    glNamedFramebufferTexture(id, GL_DEPTH_ATTACHMENT, depth.get(), 0);
    glNamedFramebufferDrawBuffer(id, GL_COLOR_ATTACHMENT0);
    res = r, layers = n;
}

void ShadowLayers::begin(int i) const {
    glNamedFramebufferTextureLayer(fbo.get(), GL_COLOR_ATTACHMENT0, color.get(), 0, i);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo.get());
    glViewport(0, 0, res, res);
    const float far_distance[4] = {3e38f, 0.f, 0.f, 0.f}, one = 1.f;
    glDepthMask(GL_TRUE);
    glClearNamedFramebufferfv(fbo.get(), GL_COLOR, 0, far_distance);
    glClearNamedFramebufferfv(fbo.get(), GL_DEPTH, 0, &one);
}

std::vector<ShadowMap> draw_shadow_maps(DrawContext& ctx, int o, const TriMesh& mesh, int res, const Program& program, ShadowLayers& layers) {
    const mat4 model = object_to_world(ctx.scene.objects[size_t(o)]);
    std::vector<ShadowMap> frames;
    Bounds b{vec3(INFINITY), vec3(-INFINITY)};
    for (const vec3& p : mesh.position) {
        const vec3 q = vec3(model * vec4(p, 1.f));
        b.lo = glm::min(b.lo, q), b.hi = glm::max(b.hi, q);
    }
    const size_t n = std::min(ctx.lighting.lights.size(), size_t(translucency::kMaxShadowMaps));
    layers.resize(res, int(std::max<size_t>(n, 1)));
    for (size_t i = 0; i < n && !mesh.position.empty(); ++i) {
        frames.push_back(translucency::shadow_frame(ctx.lighting.lights[i], 0.5f * (b.lo + b.hi), 0.5f * glm::length(b.hi - b.lo), res));
        if (!frames.back().valid) continue;
        layers.begin(int(i));
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        program.use();
        glUniformMatrix4fv(program.uniform("u_model"), 1, GL_FALSE, glm::value_ptr(model));
        glUniformMatrix4fv(program.uniform("u_view_proj"), 1, GL_FALSE, glm::value_ptr(frames.back().view_proj));
        glUniform1i(program.uniform("u_point"), frames.back().point ? 1 : 0);
        glUniform3fv(program.uniform("u_origin"), 1, glm::value_ptr(frames.back().origin));
        glUniform3fv(program.uniform("u_dir"), 1, glm::value_ptr(frames.back().dir));
        ctx.renderer.draw_object(ctx.scene, ctx.eval, o);
        glBindVertexArray(0);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return frames;
}

void set_shadow_uniforms(const Program& p, const std::vector<ShadowMap>& frames, const ShadowLayers& layers, int res, int unit) {
    glUniform1i(p.uniform("u_shadow_count"), int(frames.size()));
    p.bind_texture(unit, GL_TEXTURE_2D_ARRAY, frames.empty() ? 0 : layers.color.get(), "u_shadow");
    for (size_t i = 0; i < size_t(translucency::kMaxShadowMaps); ++i) {
        std::string k = std::to_string(i);
        k.insert(k.begin(), '['), k.push_back(']');
        const bool on = i < frames.size() && frames[i].valid;
        glUniform1i(p.uniform(("u_shadow_valid" + k).c_str()), on ? 1 : 0);
        if (!on) continue;
        const ShadowMap& f = frames[i];
        glUniformMatrix4fv(p.uniform(("u_shadow_view_proj" + k).c_str()), 1, GL_FALSE, glm::value_ptr(f.view_proj));
        glUniform1i(p.uniform(("u_shadow_point" + k).c_str()), f.point ? 1 : 0);
        glUniform3fv(p.uniform(("u_shadow_origin" + k).c_str()), 1, glm::value_ptr(f.origin));
        glUniform3fv(p.uniform(("u_shadow_dir" + k).c_str()), 1, glm::value_ptr(f.dir));
        glUniform1f(p.uniform(("u_shadow_bias" + k).c_str()), f.bias);
    }
    glUniform1i(p.uniform("u_shadow_res"), res);
}
}  // namespace mesolab::gpu
