// GPU pass of technique basic: one draw per object with shaders/mesh.vert + basic/basic.frag.
#include "core/basic/basic.h"
#include "core/basic/stages.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>

namespace mesolab::gpu {
namespace {

class BasicPass final : public TechniquePass {
public:
    explicit BasicPass(const Technique& t) : program_(Program::graphics("shaders/mesh.vert", "basic/basic.frag", {"MESOLAB_SNAP_VERTICES"}, fragment_outputs(t))) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.basic");
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(i)];
            const basic::Material m = basic::Material::from(o.material, ctx.scene.resolve(o.material.get_string("albedo_map")));
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(o));
            glUniform3fv(program_.uniform("u_kd"), 1, glm::value_ptr(m.kd));
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(m.ks));
            glUniform1f(program_.uniform("u_shininess"), m.shininess);
            const auto map = ctx.eval.get(basic::stages::albedo, i);
            glUniform1i(program_.uniform("u_has_albedo"), map ? 1 : 0);
            program_.bind_texture(1, GL_TEXTURE_2D, map ? ctx.renderer.texture(map) : 0, "u_albedo");
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
    }

private:
    Program program_;
};
}  // namespace

void register_basic_gpu(std::map<std::string, PassFactory>& out) {
    out["basic"] = [](const Technique& t) { return std::make_unique<BasicPass>(t); };
}
}  // namespace mesolab::gpu
