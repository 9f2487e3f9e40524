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
            const GLuint normals = res.get<Texture>(hf, "normals", [&] { return field_normals_texture(*hf); }).get();
            const GLuint albedo = res.get<Texture>(hf, "albedo", [&] { return rgb_field_texture(hf->albedo, hf->width, hf->height); }).get();
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
            program_.bind_texture(1, GL_TEXTURE_2D_ARRAY, horizon, "u_horizon");
            program_.bind_texture(2, GL_TEXTURE_2D, normals, "u_normals");
            program_.bind_texture(3, GL_TEXTURE_2D, albedo, "u_albedo");
            glUniform2i(program_.uniform("u_size"), hf->width, hf->height);
            glUniform1i(program_.uniform("u_directions"), map->directions);
            glUniform1f(program_.uniform("u_tiling"), float(m.get_float("tiling")));
            const bool phong = m.get_string("brdf") == "blinn-phong";
            const vec3 ks = phong ? m.get_vec3("ks") : vec3(0.f);
            glUniform1i(program_.uniform("u_phong"), phong ? 1 : 0);
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(ks));
            glUniform1f(program_.uniform("u_shininess"), float(m.get_float("shininess")));
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
