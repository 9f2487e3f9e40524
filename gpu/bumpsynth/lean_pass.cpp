// GPU pass of method lean of technique bumpsynth (core/bumpsynth/lean.h): uploads the LEAN map's
// moments (two RGBA32F textures, one mip level per map level) and shades with lean.frag.
#include "core/bumpsynth/bumpsynth.h"
#include "core/bumpsynth/lean.h"
#include "core/bumpsynth/stages.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>

namespace mesolab::gpu {
namespace {

using namespace mesolab::bumpsynth;

// The moments of every level of `map`, one member of Level (a or b) per texture.
Texture upload_moments(const LeanMap& map, std::vector<vec4> LeanMap::Level::*member) {
    const TextureSpec spec{.format = GL_RGBA32F, .width = map.size(), .height = map.size(), .levels = int(map.levels.size()),
                           .min_filter = GL_NEAREST_MIPMAP_NEAREST};
    Texture t = make_texture(spec);
    for (size_t l = 0; l < map.levels.size(); ++l)
        upload_texture(t, spec, int(l), {GL_RGBA, GL_FLOAT, (map.levels[l].*member).data()});
    return t;
}

class LeanPass final : public TechniquePass {
public:
    explicit LeanPass(const Technique& t) : program_(Program::graphics("shaders/mesh.vert", "bumpsynth/lean.frag", {"MESOLAB_SNAP_VERTICES"}, fragment_outputs(t))) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.bumpsynth/lean");
        GpuResources& res = ctx.renderer.resources();
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const ParamTable& m = ctx.scene.objects[size_t(i)].material;
            const auto map = ctx.eval.get(bumpsynth::stages::lean_map, i);
            if (!map) throw std::logic_error("bumpsynth/lean: the frame's stages were not evaluated for object " + std::to_string(i));
            const GLuint a = res.get<Texture>(map, "lean_a", [&] { return upload_moments(*map, &LeanMap::Level::a); }).get();
            const GLuint b = res.get<Texture>(map, "lean_b", [&] { return upload_moments(*map, &LeanMap::Level::b); }).get();
            const auto albedo = ctx.eval.get(bumpsynth::stages::albedo, i);
            const ShadingModel model = shading_from_material(m);
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
            program_.bind_texture(1, GL_TEXTURE_2D, a, "u_moments_a");
            program_.bind_texture(2, GL_TEXTURE_2D, b, "u_moments_b");
            program_.bind_texture(3, GL_TEXTURE_2D, albedo ? ctx.renderer.texture(albedo) : 0, "u_albedo");
            glUniform1i(program_.uniform("u_size"), map->size());
            glUniform1i(program_.uniform("u_levels"), int(map->levels.size()));
            glUniform3fv(program_.uniform("u_sigma0"), 1, glm::value_ptr(map->sigma0));
            glUniform1i(program_.uniform("u_anisotropy"), int(m.get_int("lean_anisotropy")));
            glUniform1f(program_.uniform("u_octaves"), float(m.get_int("octaves_max")));
            glUniform1i(program_.uniform("u_masking"), model.masking ? 1 : 0);
            glUniform1i(program_.uniform("u_fresnel"), model.fresnel ? 1 : 0);
            glUniform3fv(program_.uniform("u_ks"), 1, glm::value_ptr(model.ks));
            glUniform3fv(program_.uniform("u_kd"), 1, glm::value_ptr(model.kd));
            glUniform1i(program_.uniform("u_has_albedo"), albedo ? 1 : 0);
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
        check_gl("bumpsynth/lean.draw");
    }

private:
    Program program_;
};
}  // namespace

void register_bumpsynth_lean_gpu(std::map<std::string, PassFactory>& out) {
    out["bumpsynth/lean"] = [](const Technique& t) { return std::make_unique<LeanPass>(t); };
}
}  // namespace mesolab::gpu
