// The test method `microgeom/flat-probe`, registered in this test executable only, as a newcomer
// would add a method: one class (its key, the stages it reads, its CPU shading), one GPU pass and
// one registration call each. It shades the macro surface with Lambert, albedo = probe_gain times
// the heightfield's first texel's albedo (tests/passes/method_test.cpp uses it).
#include "core/heightfield/heightfield.h"
#include "core/microgeom/stages.h"
#include "core/parallel.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/technique.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>

namespace mesolab::test {
namespace {

vec3 probe_albedo(const Scene& s, const Evaluation& ev, int object) {
    const auto hf = ev.get(microgeom::stages::heightfield, object);
    if (!hf) throw std::logic_error("flat-probe: the heightfield was not evaluated");
    return float(s.objects[size_t(object)].material.get_float("probe_gain")) * hf->albedo.front();
}

class FlatProbeMethod final : public Method {
public:
    FlatProbeMethod() : Method("microgeom", "flat-probe", "Flat probe (tests what a method gets from its registration)") {}
    void declare_params(ParamGroup& p) const override {
        p.add_float("probe_gain", 1.0).used_when("method", {"flat-probe"}).range(0.0, 4.0).doc("Multiplies the albedo");
    }
    std::vector<StageName> frame_stages() const override { return {microgeom::stages::heightfield}; }
    void shade_cpu(const ShadeContext& ctx) const override {
        std::map<int, vec3> albedo;
        for (int i : ctx.objects) albedo[i] = probe_albedo(ctx.scene, ctx.eval, i);
        const GBuffer& gb = ctx.gbuffer;
        const int direct = ctx.out.index("direct"), shadow = ctx.out.index("shadow");
        mesolab::parallel_for(0, gb.height, [&](int y) {
            for (int x = 0; x < gb.width; ++x) {
                const size_t px = gb.index(x, y);
                if (!ctx.mine(px)) continue;
                const vec3 p = gb.position[px];
                vec3 n = gb.normal[px];
                if (glm::dot(n, ctx.camera.wo(p)) < 0.f) n = -n;
                vec3 L(0.f);
                for (const Light& l : ctx.lighting.lights) {
                    vec3 wi, E;
                    l.sample(p, wi, E);
                    L += albedo.at(gb.object[px]) * kInvPi * E * std::max(glm::dot(n, wi), 0.f);
                }
                ctx.out.put(AovWriter::kRadiance, x, y, L);
                ctx.out.put(AovWriter::kNormal, x, y, n);
                ctx.out.put(direct, x, y, L);
                ctx.out.put(shadow, x, y, 1.f);
            }
        });
    }
};

class FlatProbePass final : public gpu::TechniquePass {
public:
    explicit FlatProbePass(const Technique& t) : program_(gpu::Program::graphics("shaders/mesh.vert", "shaders/test/probe_method.frag", {}, gpu::fragment_outputs(t))) {}
    void draw(gpu::DrawContext& ctx) override {
        program_.use();
        ctx.renderer.set_lighting_uniforms(program_, ctx.lighting, 0);
        for (int i : ctx.objects) {
            ctx.renderer.set_camera_uniforms(program_, ctx.camera, object_to_world(ctx.scene.objects[size_t(i)]));
            const vec3 a = probe_albedo(ctx.scene, ctx.eval, i);
            glUniform3fv(program_.uniform("u_albedo"), 1, glm::value_ptr(a));
            ctx.renderer.draw_object(ctx.scene, ctx.eval, i);
        }
        glBindVertexArray(0);
    }

private:
    gpu::Program program_;
};

bool register_flat_probe() {
    register_extra_method([] { return std::make_unique<FlatProbeMethod>(); });
    gpu::register_extra_pass("microgeom/flat-probe", [](const Technique& t) { return std::make_unique<FlatProbePass>(t); });
    return true;
}
}  // namespace

// Registered before main(): the registry is built on first use, inside the tests.
const bool kFlatProbeRegistered = register_flat_probe();
}  // namespace mesolab::test
