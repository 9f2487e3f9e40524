// The test technique `probe` (see probe.h): core declarations, CPU steps and shading, GPU pass.
#include "passes/probe.h"
#include "core/raster.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/parallel.h"
#include "gpu/renderer.h"

#include <glm/gtc/type_ptr.hpp>
#include <algorithm>
#include <chrono>
#include <map>
#include <thread>

namespace mesolab::test {
std::atomic<Sneak> g_sneak{Sneak::None};

namespace {

// Per object: an N x N RGB map, image row 0 at v = 1 (as the CPU rasteriser's texture mode).
struct Maps {
    std::map<int, Image> by_object;
};

int atlas_size(const Scene& s, int object) { return int(s.objects[size_t(object)].material.get_int("atlas_size")); }

// The frame steps' handles.
constexpr FrameStep<Maps> kIllumination{"probe.illumination"};
constexpr FrameStep<Maps> kBlur{"probe.blurred"};

// [SECTION] Core side
class ProbeTechnique final : public Technique {
public:
    ProbeTechnique() : Technique("probe", "Probe (tests the frame-step contract)") {
        params_.add_color("kd", {0.8, 0.8, 0.8}).doc("Diffuse albedo");
        params_.add_int("atlas_size", 64).range(4, 1024).doc("Texels per side of the illumination map");
        params_.add_int("blur", 1).range(0, 8).doc("Box filter radius in texels");
        aovs_ = {{"texel", 3, "The illumination map's texel at the pixel (x, y)"}};
    }
    // A frame-time table, so that `mesolab bench probe` shows the frame steps' own rows.
    std::vector<BenchTable> bench_tables() const override {
        BenchTable t;
        t.name = "probe";
        t.title = "probe: frame with two frame steps";
        t.columns = {{"frame 64x64", {}, 64, 64, true, true}};
        t.rows = {{"sphere", [] { return default_scene("probe"); }, {}}};
        return {t};
    }
    std::vector<FrameStepDecl> frame_steps() const override {
        return {frame_step(kIllumination, "Irradiance per texel of the (u,v) square", {"light.*", "geometry.*", "probe.atlas_size"}, {mesolab::stages::geometry},
                           [](const FrameStepContext& ctx) {
                               Maps out;
                               for (int obj : ctx.objects) {
                                   const ParamTable& m = ctx.scene.objects[size_t(obj)].material;
                                   if (g_sneak == Sneak::InStep) (void)m.get_int("blur");
                                   if (g_sneak == Sneak::InStepWorkers) {
                                       // Only tasks that run on another thread than the step's read it.
                                       const std::thread::id step_thread = std::this_thread::get_id();
                                       mesolab::parallel_for(0, 256, [&](int) {
                                           std::this_thread::sleep_for(std::chrono::microseconds(200));
                                           if (std::this_thread::get_id() != step_thread) (void)m.get_int("blur");
                                       });
                                   }
                                   const int N = atlas_size(ctx.scene, obj);
                                   RasterCamera cam;
                                   cam.width = cam.height = N;
                                   cam.texture_space = true;
                                   const auto mesh = drawn_mesh(ctx.scene, ctx.eval, obj);
                                   GBuffer gb;
                                   rasterize({{mesh.get(), object_to_world(ctx.scene.objects[size_t(obj)]), obj}}, cam, gb);
                                   Image img(N, N, 3, 0.f);
                                   for (int y = 0; y < N; ++y)
                                       for (int x = 0; x < N; ++x) {
                                           const size_t px = gb.index(x, y);
                                           if (gb.object[px] < 0) continue;
                                           vec3 E(0.f);
                                           for (const Light& l : ctx.lighting.lights) {
                                               vec3 wi, El;
                                               l.sample(gb.position[px], wi, El);
                                               E += El * std::max(0.f, glm::dot(gb.normal[px], wi));
                                           }
                                           float* p = img.at(x, y);
                                           p[0] = E.x, p[1] = E.y, p[2] = E.z;
                                       }
                                   out.by_object.emplace(obj, std::move(img));
                               }
                               return out;
                           }),
                frame_step(kBlur, "Box filter of the illumination map", {"light.*", "geometry.*", "probe.atlas_size", "probe.blur"}, {mesolab::stages::geometry},
                           [](const FrameStepContext& ctx) {
                               Maps out;
                               for (int obj : ctx.objects) {
                                   const int N = atlas_size(ctx.scene, obj);
                                   const Image& in = ctx.step(kIllumination).by_object.at(obj);
                                   const int r = int(ctx.scene.objects[size_t(obj)].material.get_int("blur"));
                                   Image img(N, N, 3, 0.f);
                                   for (int y = 0; y < N; ++y)
                                       for (int x = 0; x < N; ++x) {
                                           vec3 sum(0.f);
                                           for (int dy = -r; dy <= r; ++dy)
                                               for (int dx = -r; dx <= r; ++dx) {
                                                   const float* q = in.at(std::clamp(x + dx, 0, N - 1), std::clamp(y + dy, 0, N - 1));
                                                   sum += vec3(q[0], q[1], q[2]);
                                               }
                                           const vec3 v = sum / float((2 * r + 1) * (2 * r + 1));
                                           float* p = img.at(x, y);
                                           p[0] = v.x, p[1] = v.y, p[2] = v.z;
                                       }
                                   out.by_object.emplace(obj, std::move(img));
                               }
                               return out;
                           })};
    }

    // A truth: the drawn mesh, Lambertian with kd.
    std::optional<TruthDecl> truth() const override {
        return TruthDecl{.params = {"probe.kd"},
                         .stages = {},
                         .object = [](const Scene& s, const Evaluation& ev, int object) {
                             class Lambert final : public TruthMaterial {
                             public:
                                 explicit Lambert(vec3 kd) : kd_(kd) {}
                                 vec3 f(const TruthHit&, vec3, vec3) const override { return kd_ * kInvPi; }

                             private:
                                 vec3 kd_;
                             };
                             const ParamTable& m = s.objects[size_t(object)].material;
                             if (g_sneak == Sneak::InTruth) (void)m.get_int("blur");
                             TruthObject t;
                             t.mesh = drawn_mesh(s, ev, object);
                             t.to_world = object_to_world(s.objects[size_t(object)]);
                             t.material = std::make_shared<Lambert>(m.get_vec3("kd"));
                             return t;
                         }};
    }

    void shade_cpu(const ShadeContext& ctx) const override {
        const Maps& maps = ctx.step(kBlur);
        const int texel_out = ctx.out.index("texel");
        std::map<int, vec3> kd;  // the material, read once per frame
        for (int obj : ctx.objects) kd[obj] = ctx.scene.objects[size_t(obj)].material.get_vec3("kd");
        const GBuffer& gb = ctx.gbuffer;
        mesolab::parallel_for(0, gb.height, [&](int y) {
            for (int x = 0; x < gb.width; ++x) {
                const size_t px = gb.index(x, y);
                if (!ctx.mine(px)) continue;
                const int obj = gb.object[px];
                const Image& map = maps.by_object.at(obj);
                const int N = map.width;
                const int tx = std::clamp(int(std::floor(gb.uv[px].x * float(N))), 0, N - 1);
                const int ty = std::clamp(int(std::floor(gb.uv[px].y * float(N))), 0, N - 1);
                const float* e = map.at(tx, N - 1 - ty);  // image row 0 holds v near 1
                vec3 n = gb.normal[px];
                if (glm::dot(n, ctx.camera.wo(gb.position[px])) < 0.f) n = -n;
                ctx.out.put(AovWriter::kRadiance, x, y, kd.at(obj) * kInvPi * vec3(e[0], e[1], e[2]));
                ctx.out.put(AovWriter::kNormal, x, y, n);
                ctx.out.put(texel_out, x, y, vec3(float(tx), float(ty), 0.f));
            }
        });
    }
};

// [SECTION] GPU side
class ProbePass final : public gpu::TechniquePass {
public:
    explicit ProbePass(const Technique& t)
        : illumination_(gpu::Program::graphics("shaders/mesh.vert", "shaders/test/probe_illumination.frag")),
          blur_(gpu::Program::compute("shaders/test/probe_blur.comp")),
          shade_(gpu::Program::graphics("shaders/mesh.vert", "shaders/test/probe.frag", {}, gpu::fragment_outputs(t))) {}

    std::vector<gpu::GpuFrameStep> frame_steps() override {
        return {{kIllumination, [this](gpu::DrawContext& ctx) { illuminate(ctx); }}, {kBlur, [this](gpu::DrawContext& ctx) { blur(ctx); }}};
    }

    void illuminate(gpu::DrawContext& ctx) {
        for (int obj : ctx.objects) {
            if (g_sneak == Sneak::InStep) (void)ctx.scene.objects[size_t(obj)].material.get_int("blur");
            const int N = atlas_size(ctx.scene, obj);
            PerObject& o = objects_[obj];
            o.illumination.resize(N, N, 1);
            o.illumination.bind();
            glClearColor(0.f, 0.f, 0.f, 0.f);
            glClearDepth(1.0);
            glDepthMask(GL_TRUE);
            glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
            glEnable(GL_DEPTH_TEST);  // as the CPU rasteriser: at equal depth the first triangle drawn stays
            glDepthFunc(GL_LESS);
            FrameCamera texture_space;
            texture_space.texture_mode = true;
            illumination_.use();
            ctx.renderer.set_camera_uniforms(illumination_, texture_space, object_to_world(ctx.scene.objects[size_t(obj)]));
            ctx.renderer.set_lighting_uniforms(illumination_, ctx.lighting, 0);
            ctx.renderer.draw_object(ctx.scene, ctx.eval, obj);
            glBindVertexArray(0);
        }
    }

    void blur(gpu::DrawContext& ctx) {
        for (int obj : ctx.objects) {
            const int N = atlas_size(ctx.scene, obj);
            PerObject& o = objects_[obj];
            if (o.size != N) {
                o.blurred = gpu::make_texture({.format = GL_RGBA32F, .width = N, .height = N});
                o.size = N;
            }
            blur_.use();
            glUniform1i(blur_.uniform("u_radius"), int(ctx.scene.objects[size_t(obj)].material.get_int("blur")));
            glBindImageTexture(0, o.illumination.color(0), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
            glBindImageTexture(1, o.blurred.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
            glDispatchCompute(GLuint((N + 7) / 8), GLuint((N + 7) / 8), 1);
            glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
        }
    }

    void draw(gpu::DrawContext& ctx) override {
        shade_.use();
        for (int obj : ctx.objects) {
            const SceneObject& o = ctx.scene.objects[size_t(obj)];
            ctx.renderer.set_camera_uniforms(shade_, ctx.camera, object_to_world(o));
            shade_.bind_texture(1, GL_TEXTURE_2D, objects_.at(obj).blurred.get(), "u_map");
            glUniform3fv(shade_.uniform("u_kd"), 1, glm::value_ptr(o.material.get_vec3("kd")));
            ctx.renderer.draw_object(ctx.scene, ctx.eval, obj);
        }
        glBindVertexArray(0);
    }

private:
    struct PerObject {
        gpu::RenderTarget illumination;
        gpu::Texture blurred;
        int size = 0;
    };
    gpu::Program illumination_, blur_, shade_;
    std::map<int, PerObject> objects_;
};
}  // namespace

bool register_probe() {
    register_extra_technique([] { return std::make_unique<ProbeTechnique>(); });
    gpu::register_extra_pass("probe", [](const Technique& t) { return std::make_unique<ProbePass>(t); });
    return true;
}

// Registered before main(): the registry is built on first use, inside the tests.
const bool kProbeRegistered = register_probe();
}  // namespace mesolab::test
