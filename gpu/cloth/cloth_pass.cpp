// GPU pass of technique cloth: one draw per garment with shaders/mesh.vert + cloth/cloth.frag,
// the object's BRDF pyramid packed into a shader storage buffer (core/cloth/cloth.h).
#include "core/cloth/stages.h"
#include "core/cloth/cloth.h"
#include "core/profile.h"
#include "core/scene_stages.h"
#include "gpu/renderer.h"

#include <algorithm>
#include <vector>

namespace mesolab::gpu {
namespace {

struct GpuPyramid {
    Buffer buffer;
    cloth::PackedPyramid layout;  // without its data, which lives in `buffer`
};

class ClothPass final : public TechniquePass {
public:
    // Vertices on the CPU rasteriser's sub-pixel grid (mesh.vert): the nearest sample point is a
    // discrete choice of the interpolated uv.
    explicit ClothPass(const Technique& t)
        : program_(Program::graphics("shaders/mesh.vert", "cloth/cloth.frag", {"MESOLAB_SNAP_VERTICES"}, fragment_outputs(t))) {}

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.cloth");
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(i)];
            const cloth::Settings s = cloth::Settings::from(ctx.scene, o);
            const auto pyr = ctx.eval.get(cloth::stages::fit, i);
            if (!pyr) continue;
            GpuPyramid& g = ctx.renderer.resources().get<GpuPyramid>(pyr, "packed", [&] {
                GpuPyramid out;
                out.layout = cloth::pack_pyramid(*pyr);
                out.buffer = make_storage_buffer(out.layout.data.data(), out.layout.data.size() * sizeof(vec4));
                out.layout.data.clear();
                out.layout.data.shrink_to_fit();
                return out;
            });
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(o));
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, g.buffer.get());
            glUniform1i(program_.uniform("u_res"), g.layout.res);
            glUniform1i(program_.uniform("u_levels"), int(g.layout.level_first.size()));
            glUniform1i(program_.uniform("u_stride"), g.layout.stride);
            glUniform1i(program_.uniform("u_max_lobes"), g.layout.lobes);
            glUniform1iv(program_.uniform("u_level_first"), GLsizei(std::min<size_t>(16, g.layout.level_first.size())), g.layout.level_first.data());
            glUniform1f(program_.uniform("u_repeat"), float(s.repeat));
            glUniform1i(program_.uniform("u_mip"), s.mip == cloth::MipMode::Off ? 0 : s.mip == cloth::MipMode::Nearest ? 1 : 2);
            glUniform1f(program_.uniform("u_bias"), float(s.mip_bias));
            // Shared table directions: the nearest three are found once per pixel (at most 128; else each entry searches).
            const int shared = g.layout.shared_views.size() <= 128 ? int(g.layout.shared_views.size()) : 0;
            glUniform1i(program_.uniform("u_shared_views"), shared);
            if (shared > 0) {
                std::vector<float> v;
                for (int k = 0; k < shared; ++k) v.insert(v.end(), {g.layout.shared_views[size_t(k)].x, g.layout.shared_views[size_t(k)].y, g.layout.shared_views[size_t(k)].z});
                glUniform3fv(program_.uniform("u_views"), shared, v.data());
            }
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
        glBindVertexArray(0);
    }

private:
    Program program_;
};
}  // namespace

void register_cloth_gpu(std::map<std::string, PassFactory>& out) {
    out["cloth"] = [](const Technique& t) { return std::make_unique<ClothPass>(t); };
}
}  // namespace mesolab::gpu
