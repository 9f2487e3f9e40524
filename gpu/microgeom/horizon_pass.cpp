// GPU pass of method horizon of technique microgeom (core/microgeom/horizon.h): uploads the horizon
// map (an R32F array texture, one layer per azimuth), the heightfield's normals and albedo (shared
// with the other microgeom passes) and shades with horizon.frag.
#include "core/microgeom/horizon.h"
#include "core/microgeom/microgeom.h"
#include "core/microgeom/stages.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/microgeom/field_textures.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>

namespace mesolab::gpu {
namespace {

using namespace mesolab::microgeom;

class HorizonPass final : public TechniquePass {
public:
    explicit HorizonPass(const Technique& t)
        : program_(Program::graphics("shaders/mesh.vert", "microgeom/horizon.frag", {"MESOLAB_SNAP_VERTICES"}, fragment_outputs(t))) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.microgeom/horizon");
        GpuResources& res = ctx.renderer.resources();
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const ParamTable& m = ctx.scene.objects[size_t(i)].material;
            const auto hf = ctx.eval.get(microgeom::stages::heightfield, i);
            const auto map = ctx.eval.get(microgeom::stages::horizon_map, i);
            if (!hf || !map) throw std::logic_error("microgeom/horizon: the frame's stages were not evaluated for object " + std::to_string(i));
            const GLuint horizon = res.get<Texture>(map, "horizon", [&] {
                return make_texture({.target = GL_TEXTURE_2D_ARRAY, .format = GL_R32F, .width = map->width, .height = map->height, .layers = map->directions},
                                    {GL_RED, GL_FLOAT, map->sin_theta.data()});
            }).get();
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
            program_.bind_texture(1, GL_TEXTURE_2D_ARRAY, horizon, "u_horizon");
            bind_field_material(program_, res, hf, m, 2);
            glUniform1i(program_.uniform("u_directions"), map->directions);
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
        check_gl("microgeom/horizon.draw");
    }

private:
    Program program_;
};
}  // namespace

void register_microgeom_horizon_gpu(std::map<std::string, PassFactory>& out) {
    out["microgeom/horizon"] = [](const Technique& t) { return std::make_unique<HorizonPass>(t); };
}
}  // namespace mesolab::gpu
