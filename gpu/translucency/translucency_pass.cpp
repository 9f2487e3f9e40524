// GPU pass of technique translucency: the per-frame passes as compute shaders over storage
// buffers made once from the stage results (core/translucency/translucency.h), then one draw per
// object sampling the radiosity maps at the atlas coordinates.
#include "core/translucency/stages.h"
#include "core/error.h"
#include "core/profile.h"
#include "core/strings.h"
#include "core/scene_stages.h"
#include "core/translucency/gpu_layout.h"
#include "core/translucency/reference.h"
#include "core/translucency/translucency.h"
#include "gpu/renderer.h"
#include "gpu/translucency/shadow_maps.h"

#include <glm/gtc/type_ptr.hpp>
#include <algorithm>
#include <cstring>
#include <cmath>
#include <map>
#include <optional>
#include <vector>

namespace mesolab::gpu {
namespace {

using namespace mesolab::translucency;

// [SECTION] Helpers
template <class T>
Buffer storage(const std::vector<T>& v) {
    // At least 16 bytes: binding an empty buffer is an error on some drivers.
    if (v.empty()) {
        const float zero[4] = {0, 0, 0, 0};
        return make_storage_buffer(zero, sizeof zero);
    }
    return make_storage_buffer(v.data(), v.size() * sizeof(T));
}

std::vector<vec4> to_vec4(const std::vector<vec3>& v, float w = 0.f) {
    std::vector<vec4> out(v.size());
    for (size_t i = 0; i < v.size(); ++i) out[i] = vec4(v[i], w);
    return out;
}

// An atlas-sized RGBA32F map, sampled bilinearly at the atlas coordinates.
Texture map_texture(int size, const std::vector<vec4>* data = nullptr) {
    return make_texture({.format = GL_RGBA32F, .width = size, .height = size, .min_filter = GL_LINEAR, .mag_filter = GL_LINEAR},
                        {GL_RGBA, GL_FLOAT, data ? data->data() : nullptr});
}

// A table made once from a stage result: its buffer and a buffer texture over it (texelFetch).
struct Table {
    Buffer buffer;
    Texture texture;
};
struct ShownTables {
    Table shown, bary;
};

void bind(GLuint binding, const Buffer& b) { glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, b.get()); }
GLuint groups(size_t n) { return GLuint((n + 63) / 64); }
void barrier() { glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT); }
void clear(const Buffer& b) { glClearNamedBufferData(b.get(), GL_R32F, GL_RED, GL_FLOAT, nullptr); }

// [SECTION] The pass
class TranslucencyPass final : public TechniquePass {
public:
    explicit TranslucencyPass(const Technique& t)
        : illumination_(Program::compute("translucency/illumination.comp")),
          vertices_(Program::compute("translucency/vertices.comp")),
          local_(Program::compute("translucency/local.comp")),
          combine_radiosity_(Program::compute("translucency/combine.comp")),
          combine_parts_(Program::compute("translucency/combine.comp", {"WRITE_PARTS"})),
          reference_(Program::compute("translucency/reference.comp")),
          shadow_(Program::graphics("translucency/shadow.vert", "translucency/shadow.frag")),
          technique_(t) {}

    // More outputs than one framebuffer takes (exitance is the ninth): a display shader per batch.
    bool output_variants() const override { return true; }

    std::vector<GpuFrameStep> frame_steps() override {
        // Each step runs object by object, with a barrier between objects.
        const auto per_object = [this](auto step) {
            return [this, step](DrawContext& ctx) {
                for (int o : ctx.objects) {
                    In in(ctx, o);
                    PerObject& w = work(o, in);
                    (this->*step)(ctx, o, in, w);
                    barrier();
                }
                unbind_step_inputs();
            };
        };
        return {{steps::illumination, per_object(&TranslucencyPass::illuminate_step)},
                {steps::vertices, per_object(&TranslucencyPass::vertices_step)},
                {steps::local, per_object(&TranslucencyPass::local_step)},
                {steps::global, per_object(&TranslucencyPass::global_step)},
                {steps::combine, per_object(&TranslucencyPass::combine_step)},
                {steps::reference, per_object(&TranslucencyPass::reference_step)}};
    }

    static void unbind_step_inputs() {
        for (GLuint b = 0; b < 8; ++b) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
            glActiveTexture(GL_TEXTURE0 + b);
            glBindTexture(GL_TEXTURE_BUFFER, 0);
        }
        glActiveTexture(GL_TEXTURE0);
    }

    void draw(DrawContext& ctx) override {
        PROFILE_SCOPE("draw.translucency");
        const auto in_frame = [&](const char* aov) {
            const auto& l = ctx.renderer.layout();
            return std::any_of(l.begin(), l.end(), [&](const AovDecl& a) { return a.name == aov; });
        };
        for (int o : ctx.objects) {
            const SceneObject& obj = ctx.scene.objects[size_t(o)];
            const Settings s = Settings::from(obj);
            PerObject& w = objects_.at(o);
            const auto rho = ctx.eval.get(translucency::stages::albedo, o);
            if (shows_parts(ctx, s) && !w.parts_written) {
                // Steps reused from a frame that did not show them: the parts from the step's buffers.
                PROFILE_SCOPE("combine parts");
                combine(ctx, In(ctx, o), w, true);
                barrier();
                unbind_step_inputs();
            }
            // The variant that samples only the maps this frame shows.
            int need = 0;
            if (rho) need |= kHasRho;
            if (in_frame("irradiance")) need |= kNeedIrradiance;
            if (in_frame("local") || in_frame("global")) need |= kNeedParts;
            if (in_frame("radiosity") || in_frame("error")) need |= kNeedRadiosity;
            if (w.has_reference && (in_frame("reference") || in_frame("error"))) need |= kNeedReference | kNeedRadiosity;
            const Program& prog = draw_program(need, ctx.outputs);
            prog.use();
            ctx.renderer.set_camera_uniforms(prog, ctx.camera, object_to_world(obj));
            const Texture& B = s.response == Response::Local ? w.local_map
                               : s.response == Response::Global ? w.global_map
                               : s.response == Response::Reference ? w.reference
                                                                    : w.radiosity_map;
            prog.bind_texture(1, GL_TEXTURE_2D, B.get(), "u_B");
            if (need & kNeedIrradiance) prog.bind_texture(2, GL_TEXTURE_2D, w.irradiance.get(), "u_irradiance");
            if (need & kNeedParts) {
                prog.bind_texture(3, GL_TEXTURE_2D, w.local_map.get(), "u_local");
                prog.bind_texture(4, GL_TEXTURE_2D, w.global_map.get(), "u_global");
            }
            if (need & kNeedRadiosity) prog.bind_texture(5, GL_TEXTURE_2D, w.radiosity_map.get(), "u_radiosity");
            if (need & kNeedReference) prog.bind_texture(6, GL_TEXTURE_2D, w.reference.get(), "u_reference");
            if (rho) {
                const int size = w.size;
                const GLuint rho_tex = ctx.renderer.resources().get<Texture>(rho, "rho", [&] {
                    const std::vector<vec4> v = to_vec4(*rho, 1.f);
                    return map_texture(size, &v);
                }).get();
                prog.bind_texture(7, GL_TEXTURE_2D, rho_tex, "u_rho");
            }
            glUniform1f(prog.uniform("u_eta"), float(s.medium.eta));
            glUniform1f(prog.uniform("u_t_mean"), float(diffuse_transmittance(s.medium.eta)));
            ctx.renderer.draw_object(ctx.scene, ctx.eval, o);
        }
        glBindVertexArray(0);
    }

private:
    // The stage results an object's passes read.
    struct In {
        Settings s;
        std::shared_ptr<const PreparedMesh> mesh;
        std::shared_ptr<const AtlasStage> atlas;
        std::shared_ptr<const LocalKernels> kernels;  // raw
        std::shared_ptr<const Blended> blended;       // null when blending is off
        std::shared_ptr<const VertexFactors> factors;
        std::shared_ptr<const Gather> gather;
        In(const DrawContext& ctx, int o)
            : s(Settings::from(ctx.scene.objects[size_t(o)], Settings::Medium_ | Settings::Scale | Settings::Shadows)),
              mesh(ctx.eval.get(translucency::stages::mesh, o)),
              atlas(ctx.eval.get(translucency::stages::atlas, o)),
              kernels(ctx.eval.get(translucency::stages::kernels, o)),
              blended(ctx.eval.get(translucency::stages::blend, o)),
              factors(ctx.eval.get(translucency::stages::factors, o)),
              gather(ctx.eval.get(translucency::stages::gather, o)) {}
        const LocalKernels& K() const { return blended ? blended->kernels : *kernels; }
    };
    // Per object: the frame's buffers and maps.
    struct PerObject {
        int size = 0, vertices = 0;
        Buffer E, local, Ev, D, Bv;
        Texture E_tex, local_tex, Ev_tex, Bv_tex;  // buffer textures over E, local, Ev, Bv
        Texture irradiance, local_map, global_map, radiosity_map, reference;
        std::weak_ptr<const AtlasStage> maps_atlas;  // the atlas whose empty texels the maps hold cleared
        ShadowLayers shadow;
        bool has_reference = false;
        bool parts_written = false;  // the irradiance, local and global maps hold the last combine's values
    };

    PerObject& work(int o, const In& in) {
        PerObject& w = objects_[o];
        const int size = in.atlas->atlas.size, n = int(in.mesh->vertex_count());
        if (w.size != size) {
            const size_t texels = size_t(size) * size_t(size);
            w.E = make_storage_buffer(nullptr, texels * sizeof(vec4), GL_DYNAMIC_COPY);
            w.local = make_storage_buffer(nullptr, texels * sizeof(vec4), GL_DYNAMIC_COPY);
            w.E_tex = make_buffer_texture(w.E, GL_RGBA32F);
            w.local_tex = make_buffer_texture(w.local, GL_RGBA32F);
            w.irradiance = map_texture(size);
            w.local_map = map_texture(size);
            w.global_map = map_texture(size);
            w.radiosity_map = map_texture(size);
            w.reference = map_texture(size);
            w.size = size;
            w.maps_atlas.reset();
        }
        // Combine writes the non-empty texels only: the maps' other texels are cleared once per atlas.
        if (w.maps_atlas.owner_before(in.atlas) || in.atlas.owner_before(w.maps_atlas) || w.maps_atlas.expired()) {
            const float empty[4] = {0.f, 0.f, 0.f, 1.f};
            for (const Texture* t : {&w.irradiance, &w.local_map, &w.global_map, &w.radiosity_map}) glClearTexImage(t->get(), 0, GL_RGBA, GL_FLOAT, empty);
            w.maps_atlas = in.atlas;
        }
        if (w.vertices != n) {
            const size_t bytes = size_t(std::max(n, 1)) * sizeof(vec4);
            w.Ev = make_storage_buffer(nullptr, bytes, GL_DYNAMIC_COPY);
            w.D = make_storage_buffer(nullptr, bytes, GL_DYNAMIC_COPY);
            w.Bv = make_storage_buffer(nullptr, bytes, GL_DYNAMIC_COPY);
            w.Ev_tex = make_buffer_texture(w.Ev, GL_RGBA32F);
            w.Bv_tex = make_buffer_texture(w.Bv, GL_RGBA32F);
            w.vertices = n;
        }
        return w;
    }

    // A buffer texture made once from a stage result (texels of `format`).
    template <class T, class F>
    GLuint table(DrawContext& ctx, const std::shared_ptr<const T>& owner, const char* slot, GLenum format, F&& make) {
        return ctx.renderer.resources()
            .get<Table>(owner, slot, [&] {
                Table t;
                t.buffer = storage(make());
                t.texture = make_buffer_texture(t.buffer, format);
                return t;
            })
            .texture.get();
    }

    // [SECTION] translucency.illumination: shadow maps, then the irradiance per texel
    void illuminate_step(DrawContext& ctx, int o, const In& in, PerObject& w) {
        const SceneObject& obj = ctx.scene.objects[size_t(o)];
        const mat4 model = object_to_world(obj);
        const AtlasStage& a = *in.atlas;
        // Shadow maps: the same frame as the CPU's (shadow_frame over the drawn mesh's world bounds).
        std::vector<ShadowMap> frames;
        if (in.s.shadows) frames = draw_shadow_maps(ctx, o, *a.display, in.s.shadow_map, shadow_, w.shadow);
        illumination_.use();
        ctx.renderer.set_lighting_uniforms(illumination_, ctx.lighting, 0);
        set_shadow_uniforms(illumination_, frames, w.shadow, in.s.shadow_map, 6);
        const mat3 nm = glm::transpose(glm::inverse(mat3(model)));
        glUniformMatrix4fv(illumination_.uniform("u_model"), 1, GL_FALSE, glm::value_ptr(model));
        glUniformMatrix3fv(illumination_.uniform("u_normal_matrix"), 1, GL_FALSE, glm::value_ptr(nm));
        glUniform1f(illumination_.uniform("u_eta"), float(in.s.medium.eta));
        glUniform1f(illumination_.uniform("u_env_transmittance"), float(diffuse_transmittance(in.s.medium.eta)));
        glUniform1i(illumination_.uniform("u_count"), int(a.lit.size()));
        clear(w.E);
        // Units 1-3 (0 holds the environment map, 6-9 the shadow maps).
        illumination_.bind_texture(1, GL_TEXTURE_BUFFER, table(ctx, in.atlas, "lit", GL_R32I, [&] { return a.lit; }), "u_lit");
        illumination_.bind_texture(2, GL_TEXTURE_BUFFER, table(ctx, in.atlas, "texel_position", GL_RGBA32F, [&] {
            std::vector<vec4> v(a.lit.size());
            for (size_t k = 0; k < v.size(); ++k) v[k] = vec4(a.texel_position[size_t(a.lit[k])], 1.f);
            return v;
        }), "u_position");
        illumination_.bind_texture(3, GL_TEXTURE_BUFFER, table(ctx, in.atlas, "texel_normal", GL_RGBA32F, [&] {
            std::vector<vec4> v(a.lit.size());
            for (size_t k = 0; k < v.size(); ++k) v[k] = vec4(a.texel_normal[size_t(a.lit[k])], 0.f);
            return v;
        }), "u_normal");
        // Per lit texel, the border texels that copy it (AtlasStage::copy), written with it.
        struct Copies {
            std::vector<int32_t> start, target;
        };
        const Copies& copies = ctx.renderer.resources().get<Copies>(in.atlas, "copies", [&] {
            Copies c;
            std::vector<int32_t> lit_index(a.atlas.texel_kind.size(), -1);
            for (size_t k = 0; k < a.lit.size(); ++k) lit_index[size_t(a.lit[k])] = int32_t(k);
            c.start.assign(a.lit.size() + 1, 0);
            for (const ivec2& p : a.copy) ++c.start[size_t(lit_index[size_t(p.y)]) + 1];
            for (size_t k = 0; k < a.lit.size(); ++k) c.start[k + 1] += c.start[k];
            c.target.resize(a.copy.size());
            std::vector<int32_t> next(c.start.begin(), c.start.end() - 1);
            for (const ivec2& p : a.copy) c.target[size_t(next[size_t(lit_index[size_t(p.y)])]++)] = p.x;
            return c;
        });
        illumination_.bind_texture(4, GL_TEXTURE_BUFFER, table(ctx, in.atlas, "copy_start", GL_R32I, [&] { return copies.start; }), "u_copy_start");
        illumination_.bind_texture(5, GL_TEXTURE_BUFFER, table(ctx, in.atlas, "copy_target", GL_R32I, [&] { return copies.target; }), "u_copy_target");
        bind(3, w.E);
        glDispatchCompute(groups(a.lit.size()), 1, 1);
    }

    // [SECTION] translucency.vertices
    void vertices_step(DrawContext& ctx, int /*o*/, const In& in, PerObject& w) {
        const Gather& g = *in.gather;
        vertices_.use();
        glUniform1i(vertices_.uniform("u_count"), g.n);
        vertices_.bind_texture(0, GL_TEXTURE_BUFFER, table(ctx, in.gather, "start", GL_R32I, [&] { return g.start; }), "u_start");
        vertices_.bind_texture(1, GL_TEXTURE_BUFFER, table(ctx, in.gather, "texel", GL_R32I, [&] { return g.texel; }), "u_texel");
        vertices_.bind_texture(2, GL_TEXTURE_BUFFER, table(ctx, in.gather, "w", GL_RGBA32F, [&] { return g.w; }), "u_w");
        vertices_.bind_texture(3, GL_TEXTURE_BUFFER, w.E_tex.get(), "u_E");
        vertices_.bind_texture(4, GL_TEXTURE_BUFFER, factors(ctx, in).weight_tex.get(), "u_weight");
        bind(4, w.Ev);
        bind(5, w.D);
        glDispatchCompute(groups(size_t(g.n)), 1, 1);
    }

    // [SECTION] translucency.local
    void local_step(DrawContext& ctx, int /*o*/, const In& in, PerObject& w) {
        const LocalKernels& K = in.K();
        // One buffer texture holds every weight (K² per inner texel): beyond what this GL's buffer
        // textures address the shader would read past it (llvmpipe crashes, others read zeros).
        {
            GLint64 max_texels = 0;
            glGetInteger64v(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
            const double weights = double(K.texel.size()) * double(K.K) * double(K.K);
            if (weights > double(max_texels) || weights * 16.0 > 2147483647.0)
                throw InputError("translucency.kernel = " + std::to_string(K.K) + " with translucency.atlas_size = " + std::to_string(K.size) +
                                 ": the GPU's local kernels would hold " + std::to_string(int64_t(weights)) + " weights (" +
                                 format_bytes(weights * 16.0) + "), more than this GL's buffer textures address (GL_MAX_TEXTURE_BUFFER_SIZE = " +
                                 std::to_string(max_texels) + ", and 2 GiB); lower the kernel or the atlas size, or render on the CPU");
        }
        // The weights kernel by kernel on llvmpipe, tap by tap on a hardware GPU (local.comp).
        const bool tap_major = tuned_for_hardware();
        if (tap_major && !local_tap_major_) local_tap_major_.emplace(Program::compute("translucency/local.comp", {"TAP_MAJOR"}));
        Program& prog = tap_major ? *local_tap_major_ : local_;
        prog.use();
        glUniform1i(prog.uniform("u_count"), int(K.texel.size()));
        glUniform1i(prog.uniform("u_K"), K.K);
        glUniform1i(prog.uniform("u_size"), K.size);
        auto weights = [&] {
            // K² taps per kernel, row-major in (dy, dx), one vec4 (RGB) each: [texel][tap] or [tap][texel].
            const int h = (K.K - 1) / 2;
            const size_t n = K.texel.size(), taps = size_t(K.K) * size_t(K.K);
            std::vector<vec4> v(n * taps);
            for (size_t k = 0; k < n; ++k) {
                size_t tap = 0;
                for (int dy = -h; dy <= h; ++dy)
                    for (int dx = -h; dx <= h; ++dx, ++tap) {
                        const float* wk = K.w.data() + K.at(k, dx, dy);
                        v[tap_major ? tap * n + k : k * taps + tap] = vec4(wk[0], wk[1], wk[2], 0.f);
                    }
            }
            return v;
        };
        const char* weights_key = tap_major ? "kernel_w_tap_major" : "kernel_w";
        if (in.blended) {
            prog.bind_texture(0, GL_TEXTURE_BUFFER, table(ctx, in.blended, "kernel_texel", GL_R32I, [&] { return K.texel; }), "u_texel");
            prog.bind_texture(1, GL_TEXTURE_BUFFER, table(ctx, in.blended, weights_key, GL_RGBA32F, weights), "u_w");
        } else {
            prog.bind_texture(0, GL_TEXTURE_BUFFER, table(ctx, in.kernels, "kernel_texel", GL_R32I, [&] { return K.texel; }), "u_texel");
            prog.bind_texture(1, GL_TEXTURE_BUFFER, table(ctx, in.kernels, weights_key, GL_RGBA32F, weights), "u_w");
        }
        prog.bind_texture(2, GL_TEXTURE_BUFFER, w.E_tex.get(), "u_E");
        clear(w.local);
        bind(3, w.local);
        glDispatchCompute(groups(K.texel.size()), 1, 1);
    }

    // [SECTION] translucency.global: the factors' rows, padded and in pieces (core/translucency/gpu_layout.h)
    struct GpuFactors {
        // Rows [r0, r1) read through buffer textures over their pairs of entries from pair `base` on.
        struct Piece {
            FactorPiece rows;
            Texture entry, col_hi;
        };
        Buffer outer, entry, col_hi, weight;
        Texture weight_tex;
        std::vector<Piece> pieces;
        bool wide = false;
    };
    GpuFactors& factors(DrawContext& ctx, const In& in) {
        return ctx.renderer.resources().get<GpuFactors>(in.factors, "directed", [&] {
            PROFILE_SCOPE("upload factors");
            const VertexFactors& F = *in.factors;
            const PaddedFactors P = pad_factor_rows(F);
            GpuFactors g;
            g.outer = storage(P.outer);
            g.entry = storage(P.entry);
            g.wide = P.wide();
            g.col_hi = storage(P.col_hi);
            std::vector<vec4> weight(size_t(F.n));
            for (int j = 0; j < F.n; ++j) weight[size_t(j)] = vec4(F.weight(j), 0.f);
            g.weight = storage(weight);
            g.weight_tex = make_buffer_texture(g.weight, GL_RGBA32F);
            GLint64 max_texels = 0;
            GLint align = 16;
            glGetInteger64v(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
            glGetIntegerv(GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT, &align);
            for (const FactorPiece& r : factor_pieces(P, max_texels, (align + 3) / 4)) {
                GpuFactors::Piece p{r, {}, {}};
                p.entry = make_buffer_texture(g.entry, GL_RGBA32UI, GLintptr(r.base * 16), GLsizeiptr(r.count * 16));
                if (g.wide) p.col_hi = make_buffer_texture(g.col_hi, GL_R32UI, GLintptr(r.base * 4), GLsizeiptr(r.count * 4));
                g.pieces.push_back(std::move(p));
            }
            return g;
        });
    }

    // The product's program: columns of 16 or 32 bits, and the layout for this renderer (global.comp:
    // 8 lanes x 8 rows on llvmpipe, 32 x 2 on a hardware GPU), compiled when first used.
    struct GlobalLayout {
        int lanes, rows;
    };
    static GlobalLayout global_layout() { return tuned_for_hardware() ? GlobalLayout{32, 2} : GlobalLayout{8, 8}; }
    Program& global_program(bool wide, GlobalLayout l) {
        std::optional<Program>& p = global_[wide ? 1 : 0][l.lanes == 8 ? 0 : 1];
        if (!p) {
            std::vector<std::string> defines = {"LANES=" + std::to_string(l.lanes), "ROWS=" + std::to_string(l.rows)};
            if (wide) defines.push_back("WIDE_COLUMNS");
            p.emplace(Program::compute("translucency/global.comp", defines));
        }
        return *p;
    }

    void global_step(DrawContext& ctx, int /*o*/, const In& in, PerObject& w) {
        const GpuFactors& F = factors(ctx, in);
        const GlobalLayout layout = global_layout();
        Program& prog = global_program(F.wide, layout);
        prog.use();
        bind(0, F.outer);
        bind(6, w.D);
        bind(7, w.Bv);
        glBindImageTexture(1, w.Ev_tex.get(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        for (const GpuFactors::Piece& p : F.pieces) {
            glBindImageTexture(0, p.entry.get(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32UI);
            if (F.wide) prog.bind_texture(1, GL_TEXTURE_BUFFER, p.col_hi.get(), "u_col_hi");
            glUniform1i(prog.uniform("u_row0"), p.rows.r0);
            glUniform1i(prog.uniform("u_row1"), p.rows.r1);
            glUniform1i(prog.uniform("u_base"), int(p.rows.base));
            glDispatchCompute(GLuint((p.rows.r1 - p.rows.r0 + layout.rows - 1) / layout.rows), 1, 1);
        }
    }

    // [SECTION] translucency.combine
    // The irradiance, local and global maps are written when the frame shows one of them (as an
    // AOV, or as the displayed response); else by the first frame that does, from the step's buffers.
    // Whether the frame's layout asks for the parts (the AOVs irradiance, local, global).
    static bool layout_shows_parts(const DrawContext& ctx) {
        const auto& l = ctx.renderer.layout();
        return std::any_of(l.begin(), l.end(), [](const AovDecl& a) { return a.name == "irradiance" || a.name == "local" || a.name == "global"; });
    }
    // Whether the frame shows the parts: the layout, or a response that draws one of them.
    static bool shows_parts(const DrawContext& ctx, const Settings& s) {
        return layout_shows_parts(ctx) || s.response == Response::Local || s.response == Response::Global;
    }

    void combine_step(DrawContext& ctx, int /*o*/, const In& in, PerObject& w) {
        // The step reads no key of what the frame shows (translucency.response): a response that
        // draws a part has draw() combine the parts from the step's buffers, so the step is reused.
        combine(ctx, in, w, layout_shows_parts(ctx));
    }

    void combine(DrawContext& ctx, const In& in, PerObject& w, bool parts) {
        const Atlas& a = in.atlas->atlas;
        const AtlasStage& A = *in.atlas;
        Program& prog = parts ? combine_parts_ : combine_radiosity_;
        prog.use();
        glUniform1i(prog.uniform("u_size"), a.size);
        glUniform1i(prog.uniform("u_count"), int(A.nonempty.size()));
        // The shown texels (core/translucency/gpu_layout.h), made once per atlas.
        const auto& T = ctx.renderer.resources().get<ShownTables>(in.atlas, "shown", [&] {
            const ShownTexels st = shown_texels(A, in.mesh->index);
            ShownTables t;
            t.shown.buffer = storage(st.shown);
            t.shown.texture = make_buffer_texture(t.shown.buffer, GL_RGBA32I);
            t.bary.buffer = storage(st.bary);
            t.bary.texture = make_buffer_texture(t.bary.buffer, GL_RGBA32F);
            return t;
        });
        prog.bind_texture(0, GL_TEXTURE_BUFFER, T.shown.texture.get(), "u_shown");
        prog.bind_texture(1, GL_TEXTURE_BUFFER, T.bary.texture.get(), "u_bary");
        prog.bind_texture(3, GL_TEXTURE_BUFFER, w.Bv_tex.get(), "u_Bv");
        prog.bind_texture(4, GL_TEXTURE_BUFFER, w.E_tex.get(), "u_E");
        prog.bind_texture(5, GL_TEXTURE_BUFFER, w.local_tex.get(), "u_L");
        if (parts) {
            glBindImageTexture(0, w.irradiance.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
            glBindImageTexture(1, w.local_map.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
            glBindImageTexture(2, w.global_map.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        }
        glBindImageTexture(3, w.radiosity_map.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glDispatchCompute(groups(A.nonempty.size()), 1, 1);
        w.parts_written = parts;
    }

    // [SECTION] translucency.reference: every lit inner texel to every inner texel (O(n²))
    void reference_step(DrawContext& ctx, int o, const In& in, PerObject& w) {
        w.has_reference = false;
        if (!Settings::from(ctx.scene.objects[size_t(o)], Settings::Show).needs_reference()) return;
        const Atlas& a = in.atlas->atlas;
        const double mm = in.s.mm_per_unit;
        // Positions (mm), the table and the disk term depend on the material and the atlas: made
        // with the kernels (keyed by both).
        struct RefData {
            std::vector<vec4> x, self, sources_x;  // per texel; per inner texel: position, area
            std::vector<int32_t> sources_t;
            std::vector<vec4> table;
            float inv_r_max = 0.f, r_max2 = 0.f;
        };
        auto make = [&] {
            RefData r;
            const std::vector<vec3> x = texel_positions_mm(a, in.mesh->position, in.mesh->index, mm);
            const std::unique_ptr<Profile> d = Settings::from(ctx.scene.objects[size_t(o)], Settings::Medium_ | Settings::ProfilePart).profile();
            vec3 lo(INFINITY), hi(-INFINITY);
            r.x.assign(x.size(), vec4(0.f));
            r.self.assign(x.size(), vec4(0.f));
            for (size_t t = 0; t < x.size(); ++t)
                if (a.texel_kind[t] == Atlas::kInner) lo = glm::min(lo, x[t]), hi = glm::max(hi, x[t]);
            const RdTable Rd(*d, std::max(1e-6, double(glm::length(hi - lo))) * 1.0001);
            const float s2 = float(mm * mm);
            for (size_t t = 0; t < x.size(); ++t) {
                if (a.texel_kind[t] != Atlas::kInner) continue;
                const float area = a.texel_area[t] * s2;
                r.x[t] = vec4(x[t], 1.f);
                r.self[t] = vec4(reference_self_weight(*d, Rd, area), 0.f);
                r.sources_x.push_back(vec4(x[t], area));
                r.sources_t.push_back(int32_t(t));
            }
            r.table = to_vec4(Rd.samples());
            r.inv_r_max = float(1.0 / Rd.r_max());
            r.r_max2 = float(Rd.r_max() * Rd.r_max());
            return r;
        };
        auto& data = ctx.renderer.resources().get<std::shared_ptr<RefData>>(in.kernels, "reference_data", [&] { return std::make_shared<RefData>(make()); });
        const RefData& r = *data;
        // Sources: position and power E A of the lit inner texels, this frame (E read back once).
        std::vector<vec4> E(size_t(a.size) * size_t(a.size));
        glGetNamedBufferSubData(w.E.get(), 0, GLsizeiptr(E.size() * sizeof(vec4)), E.data());
        std::vector<vec4> src;
        for (size_t k = 0; k < r.sources_t.size(); ++k) {
            const vec3 e = vec3(E[size_t(r.sources_t[k])]);
            if (e == vec3(0.f)) continue;
            src.push_back(vec4(vec3(r.sources_x[k]), texel_disk_r2(r.sources_x[k].w)));
            src.push_back(vec4(e * r.sources_x[k].w, 0.f));
        }
        const Buffer sources = storage(src);
        reference_.use();
        glUniform1i(reference_.uniform("u_size"), a.size);
        glUniform1i(reference_.uniform("u_sources"), int(src.size() / 2));
        glUniform1i(reference_.uniform("u_table_n"), int(r.table.size()));
        glUniform1f(reference_.uniform("u_inv_r_max"), r.inv_r_max);
        glUniform1f(reference_.uniform("u_r_max2"), r.r_max2);
        bind(0, ctx.renderer.resources().get<Buffer>(in.atlas, "fill", [&] { return storage(in.atlas->fill); }));
        bind(1, sources);
        bind(2, ctx.renderer.resources().get<Buffer>(in.kernels, "reference_x", [&] { return storage(r.x); }));
        bind(3, ctx.renderer.resources().get<Buffer>(in.kernels, "reference_self", [&] { return storage(r.self); }));
        bind(4, w.E);
        bind(5, ctx.renderer.resources().get<Buffer>(in.kernels, "reference_table", [&] { return storage(r.table); }));
        glBindImageTexture(0, w.reference.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glDispatchCompute(groups(size_t(a.size) * size_t(a.size)), 1, 1);
        w.has_reference = true;
    }

    // [SECTION] Display variants, made on first use
    enum : int { kHasRho = 1, kNeedIrradiance = 2, kNeedParts = 4, kNeedRadiosity = 8, kNeedReference = 16 };
    const Program& draw_program(int need, const std::vector<std::string>& outputs) {
        std::string key = std::to_string(need);
        for (const std::string& o : outputs) key += " " + o;
        auto it = draw_.find(key);
        if (it != draw_.end()) return it->second;
        std::vector<std::string> defines{"MESOLAB_SNAP_VERTICES"};  // the CPU rasteriser's window positions (mesh.vert)
        if (need & kHasRho) defines.push_back("HAS_RHO");
        if (need & kNeedIrradiance) defines.push_back("NEED_IRRADIANCE");
        if (need & kNeedParts) defines.push_back("NEED_PARTS");
        if (need & kNeedRadiosity) defines.push_back("NEED_RADIOSITY");
        if (need & kNeedReference) defines.push_back("NEED_REFERENCE");
        return draw_.emplace(key, Program::graphics("shaders/mesh.vert", "translucency/translucency.frag", defines, fragment_outputs(technique_, outputs)))
            .first->second;
    }

    Program illumination_, vertices_, local_, combine_radiosity_, combine_parts_, reference_, shadow_;
    std::optional<Program> local_tap_major_;  // compiled when first used
    std::optional<Program> global_[2][2];  // [wide columns][hardware layout]
    const Technique& technique_;
    std::map<std::string, Program> draw_;  // by need and the batch's outputs
    std::map<int, PerObject> objects_;
};
}  // namespace

void register_translucency_gpu(std::map<std::string, PassFactory>& out) {
    out["translucency"] = [](const Technique& t) { return std::make_unique<TranslucencyPass>(t); };
}
}  // namespace mesolab::gpu
