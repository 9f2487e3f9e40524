// GPU pass of method pom of technique microgeom (core/microgeom/pom.h): uploads the heights in
// texel units, the heightfield's normals and albedo (shared with the paper's pass) and shades
// with pom.frag.
#include "core/microgeom/microgeom.h"
#include "core/microgeom/pom.h"
#include "core/microgeom/stages.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/microgeom/field_textures.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>

namespace mesolab::gpu {
namespace {

using namespace mesolab::microgeom;

class PomPass final : public TechniquePass {
public:
    explicit PomPass(const Technique& t) : program_(Program::graphics("shaders/mesh.vert", "microgeom/pom.frag", {"MESOLAB_SNAP_VERTICES"}, fragment_outputs(t))) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.microgeom/pom");
        GpuResources& res = ctx.renderer.resources();
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const ParamTable& m = ctx.scene.objects[size_t(i)].material;
            const auto hf = ctx.eval.get(microgeom::stages::heightfield, i);
            const auto field = ctx.eval.get(microgeom::stages::pom_field, i);
            if (!hf || !field) throw std::logic_error("microgeom/pom: the frame's stages were not evaluated for object " + std::to_string(i));
            const GLuint heights = res.get<Texture>(field, "heights", [&] {
                return make_texture({.format = GL_R32F, .width = field->width, .height = field->height}, {GL_RED, GL_FLOAT, field->z.data()});
            }).get();
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
            program_.bind_texture(1, GL_TEXTURE_2D, heights, "u_heights");
            bind_field_material(program_, res, hf, m, 2);
            glUniform2f(program_.uniform("u_z_range"), field->z_min, field->z_max);
            glUniform1i(program_.uniform("u_steps"), int(m.get_int("pom_steps")));
            glUniform1i(program_.uniform("u_refine"), int(m.get_int("pom_refine")));
            glUniform1i(program_.uniform("u_shadow_steps"), int(m.get_int("pom_shadow_steps")));
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
        check_gl("microgeom/pom.draw");
    }

private:
    Program program_;
};
}  // namespace

void register_microgeom_pom_gpu(std::map<std::string, PassFactory>& out) {
    out["microgeom/pom"] = [](const Technique& t) { return std::make_unique<PomPass>(t); };
}
}  // namespace mesolab::gpu
