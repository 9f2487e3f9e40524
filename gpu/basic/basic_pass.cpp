// GPU pass of technique basic: one draw per object with shaders/mesh.vert + basic/basic.frag.
#include "core/basic/basic.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>

namespace mesolab::gpu {
namespace {

class BasicPass final : public TechniquePass {
public:
    BasicPass() : program_(Program::graphics("shaders/mesh.vert", "basic/basic.frag")) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("basic.draw");
        auto maps = ctx.eval.get<basic::AlbedoMaps>("basic.albedo");
        program_.use();
        ctx.renderer.draw_buffers({"radiance", "normal"});
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(i)];
            const basic::Material m = basic::Material::from(o.material, ctx.scene.resolve(o.material.get_string("albedo_map")));
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(o));
            glUniform3fv(program_.uniform("u_kd"), 1, glm::value_ptr(m.kd));
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(m.ks));
            glUniform1f(program_.uniform("u_shininess"), m.shininess);
            const bool has_map = !m.albedo_map.empty() && maps && maps->count(m.albedo_map);
            glUniform1i(program_.uniform("u_has_albedo"), has_map ? 1 : 0);
            // The map's address in the stage result is stable while the result is cached.
            program_.bind_texture(1, GL_TEXTURE_2D,
                                  has_map ? ctx.renderer.texture(maps->at(m.albedo_map), &maps->at(m.albedo_map)) : 0,
                                  "u_albedo");
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
    }

private:
    Program program_;
};
}  // namespace

void register_basic_gpu(std::map<std::string, PassFactory>& out) {
    out["basic"] = [] { return std::make_unique<BasicPass>(); };
}
}  // namespace mesolab::gpu
