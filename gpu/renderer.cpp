#include "gpu/renderer.h"
#include "core/error.h"
#include "core/profile.h"
#include "core/scene_stages.h"

#include <chrono>
#include <limits>
#include <memory>
#include <glm/gtc/type_ptr.hpp>
#include <algorithm>
#include <cmath>

namespace mesolab::gpu {

struct Renderer::Impl {
    Program background;
    std::map<std::string, std::unique_ptr<TechniquePass>> passes;
    std::map<std::string, std::function<void(DrawContext&)>> steps;  // each frame step's GPU work, by step name
    FrameStepScheduler scheduler;
    std::unique_ptr<GpuTimeline> timeline;  // made with the renderer: software or hardware timing
    uint64_t frame = 0;                     // frames rendered so far
    // Each step's latest GPU time and the frame it came from: a frame's steps show their own
    // answers once in, and the previous ones until then (the window reads them a frame late).
    std::map<std::string, std::pair<uint64_t, double>> latest_steps;
    VertexArray empty_vao;  // attribute-less draws (the full-screen triangle)

    void draw_fullscreen_triangle() const {
        glBindVertexArray(empty_vao.get());
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindVertexArray(0);
    }
};

namespace {
std::map<std::string, PassFactory>& extra_passes() {
    static std::map<std::string, PassFactory> m;
    return m;
}
}  // namespace

void register_extra_pass(const std::string& technique, PassFactory make) { extra_passes()[technique] = std::move(make); }

std::string fragment_outputs(const Technique& t) {
    std::string s;
    const auto outs = t.outputs();
    for (size_t k = 0; k < outs.size(); ++k) s += "layout(location = " + std::to_string(k) + ") out vec4 o_" + outs[k].name + ";\n";
    return s;
}

std::string fragment_outputs(const Technique& t, const std::vector<std::string>& bound) {
    std::string s;
    for (const AovDecl& o : t.outputs()) {
        const auto at = std::find(bound.begin(), bound.end(), o.name);
        if (at != bound.end()) s += "layout(location = " + std::to_string(at - bound.begin()) + ") out vec4 o_" + o.name + ";\n";
        else s += "vec4 o_" + o.name + ";\n";
    }
    return s;
}

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {
    impl_->background = Program::graphics("shaders/fullscreen.vert", "shaders/background.frag");
    std::map<std::string, PassFactory> factories;
    register_gpu_passes(factories);
    for (const auto& [name, make] : extra_passes()) factories[name] = make;
    for (const Technique* t : Registry::instance().techniques()) {
        auto f = factories.find(t->name());
        if (f == factories.end()) throw std::logic_error("technique " + t->name() + " has no GPU pass");
        impl_->passes[t->name()] = f->second(*t);
        if (int(t->outputs().size()) > max_attachments() && !impl_->passes[t->name()]->output_variants())
            throw std::runtime_error("technique " + t->name() + " declares " + std::to_string(t->outputs().size()) + " outputs; this GL draws at most " +
                                     std::to_string(max_attachments()) + " at once");
        // The pass implements exactly the technique's frame steps, in their order.
        const std::vector<FrameStepDecl> declared = t->frame_steps();
        const std::vector<GpuFrameStep> bound = impl_->passes[t->name()]->frame_steps();
        for (size_t i = 0; i < std::max(declared.size(), bound.size()); ++i) {
            if (i >= bound.size() || i >= declared.size() || bound[i].step.str() != declared[i].name)
                throw std::logic_error("technique " + t->name() + ": its GPU pass implements frame step " +
                                       (i < bound.size() ? bound[i].step.str() : std::string("none")) + " where it declares " +
                                       (i < declared.size() ? declared[i].name : std::string("none")));
            impl_->steps[declared[i].name] = bound[i].run;
        }
        // Each other method's pass: the technique's outputs, no frame steps of its own.
        for (const Method* m : t->methods()) {
            if (m->shares_paper_pipeline()) continue;  // its objects are drawn by the technique's pass
            const std::string key = t->name() + "/" + m->name();
            auto mf = factories.find(key);
            if (mf == factories.end()) throw std::logic_error("method " + key + " has no GPU pass");
            impl_->passes[key] = mf->second(*t);
            if (!impl_->passes[key]->frame_steps().empty()) throw std::logic_error("method " + key + ": a method's pass has no frame steps");
            if (int(t->outputs().size()) > max_attachments() && !impl_->passes[key]->output_variants())
                throw std::runtime_error("method " + key + " draws " + std::to_string(t->outputs().size()) + " outputs; this GL draws at most " +
                                         std::to_string(max_attachments()) + " at once");
        }
    }
    GLuint vao = 0;
    glGenVertexArrays(1, &vao);
    impl_->empty_vao = VertexArray(vao);
    // Warm-up draw: Mesa's llvmpipe answers a GL_TIME_ELAPSED query begun before a context's
    // first draw with the system uptime, which would poison the first frame's GPU timing.
    RenderTarget warm;
    warm.resize(1, 1, 1);
    warm.bind();
    impl_->background.use();
    impl_->draw_fullscreen_triangle();
    glFinish();
    impl_->timeline = std::make_unique<GpuTimeline>(current_renderer_is_software());
}

bool Renderer::software() const { return impl_->timeline->software(); }
void Renderer::poll_timings() { impl_->timeline->poll(); }

void Renderer::show_step_times() {
    for (FrameStepRun& run : last_steps_) {
        if (run.status != StageStatus::Ran) continue;
        const auto it = impl_->latest_steps.find(run.name);
        if (it == impl_->latest_steps.end()) continue;
        if (it->second.first == impl_->frame || !std::isfinite(run.ms)) run.ms = it->second.second;
    }
}
void Renderer::wait_timings() { impl_->timeline->wait(); }

Renderer::~Renderer() = default;

void Renderer::forget_frame_steps() { impl_->scheduler.forget(); }

int Renderer::max_attachments() const {
    GLint draw = 0, color = 0;
    glGetIntegerv(GL_MAX_DRAW_BUFFERS, &draw);
    glGetIntegerv(GL_MAX_COLOR_ATTACHMENTS, &color);
    const int gl = std::max(1, std::min(draw, color));
    return max_attachments_override_ > 0 ? std::min(gl, max_attachments_override_) : gl;
}

// [SECTION] Resources
namespace {
GpuMesh upload_mesh(const TriMesh& m) {
    GpuMesh g;
    std::vector<float> interleaved;
    interleaved.reserve(m.vertex_count() * 11);
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const vec3 t = v < m.tangent.size() ? m.tangent[v] : vec3(0.f);
        const vec2 uv = v < m.uv.size() ? m.uv[v] : vec2(0.f);
        for (float x : {m.position[v].x, m.position[v].y, m.position[v].z, m.normal[v].x, m.normal[v].y, m.normal[v].z, t.x, t.y, t.z, uv.x, uv.y})
            interleaved.push_back(x);
    }
    GLuint ids[3];
    glGenVertexArrays(1, &ids[0]);
    glGenBuffers(2, &ids[1]);
    g.vao = VertexArray(ids[0]);
    g.vbo = Buffer(ids[1]);
    g.ibo = Buffer(ids[2]);
    glBindVertexArray(g.vao.get());
    glBindBuffer(GL_ARRAY_BUFFER, g.vbo.get());
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(interleaved.size() * sizeof(float)), interleaved.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ibo.get());
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(m.index.size() * sizeof(uint32_t)), m.index.data(), GL_STATIC_DRAW);
    const GLsizei stride = 11 * sizeof(float);
    const int sizes[4] = {3, 3, 3, 2}, offsets[4] = {0, 3, 6, 9};
    for (GLuint a = 0; a < 4; ++a) {
        glEnableVertexAttribArray(a);
        glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(size_t(offsets[a]) * sizeof(float)));
    }
    glBindVertexArray(0);
    g.index_count = GLsizei(m.index.size());
    return g;
}
}  // namespace

void Renderer::draw_object(const Scene& s, const Evaluation& ev, int object) {
    const GpuMesh& m = mesh(s, ev, object);
    glBindVertexArray(m.vao.get());
    glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
}

const GpuMesh& Renderer::mesh(const Scene& s, const Evaluation& ev, int object) {
    // One upload per drawn mesh (a tessellation or a level of detail), kept while it is cached.
    const std::shared_ptr<const TriMesh> m = drawn_mesh(s, ev, object);
    if (!m) throw std::logic_error("gpu::Renderer: scene.geometry was not evaluated");
    return resources_.get<GpuMesh>(m, "mesh", [&] {
        PROFILE_SCOPE("upload.meshes");
        GpuMesh g = upload_mesh(*m);
        check_gl("mesh upload");
        return g;
    });
}

GLuint Renderer::texture(const std::shared_ptr<const Image>& img, bool repeat) {
    return resources_
        .get<Texture>(img, repeat ? "texture.repeat" : "texture.clamp",
                      [&] {
                          PROFILE_SCOPE("upload.texture");
                          std::vector<float> rgba(size_t(img->width) * size_t(img->height) * 4, 1.f);
                          for (size_t i = 0; i < size_t(img->width) * size_t(img->height); ++i)
                              for (int c = 0; c < 4; ++c) {
                                  const int src = img->channels >= 3 ? std::min(c, img->channels - 1) : 0;
                                  if (c < 3 || img->channels == 4) rgba[i * 4 + size_t(c)] = img->data[i * size_t(img->channels) + size_t(src)];
                              }
                          Texture t = make_texture({.format = GL_RGBA32F, .width = img->width, .height = img->height, .min_filter = GL_LINEAR,
                                                    .mag_filter = GL_LINEAR, .wrap_s = GL_REPEAT, .wrap_t = repeat ? GLenum(GL_REPEAT) : GLenum(GL_CLAMP_TO_EDGE)},
                                                   {GL_RGBA, GL_FLOAT, rgba.data()});
                          check_gl("texture upload");
                          return t;
                      })
        .get();
}

void Renderer::bind_outputs(const std::vector<AovDecl>& outputs, size_t batch) const {
    // Fragment output location k writes the attachment of the AOV outputs[k] in this batch.
    std::vector<GLenum> bufs(outputs.size(), GL_NONE);
    const auto& b = batches_[batch];
    for (size_t k = 0; k < outputs.size(); ++k)
        for (size_t i = 0; i < b.size(); ++i)
            if (b[i].name == outputs[k].name) bufs[k] = GLenum(GL_COLOR_ATTACHMENT0 + i);
    glDrawBuffers(GLsizei(bufs.size()), bufs.data());
}

void Renderer::set_camera_uniforms(const Program& p, const FrameCamera& cam, const mat4& model) const {
    const mat3 nm = glm::transpose(glm::inverse(mat3(model)));
    const mat4 vp = cam.raster.proj * cam.raster.view;
    glUniformMatrix4fv(p.uniform("u_model"), 1, GL_FALSE, glm::value_ptr(model));
    glUniformMatrix3fv(p.uniform("u_normal_matrix"), 1, GL_FALSE, glm::value_ptr(nm));
    glUniformMatrix4fv(p.uniform("u_view_proj"), 1, GL_FALSE, glm::value_ptr(vp));
    glUniform1i(p.uniform("u_texture_mode"), cam.texture_mode ? 1 : 0);
    glUniform3fv(p.uniform("u_eye"), 1, glm::value_ptr(cam.eye));
    glUniform3fv(p.uniform("u_view_dir"), 1, glm::value_ptr(cam.view_dir));
    // mesh.vert with MESOLAB_SNAP_VERTICES: the CPU rasteriser's clip transform and frame size.
    const mat4 clip_from_object = cam.raster.proj * cam.raster.view * model;
    glUniformMatrix4fv(p.uniform("u_clip_from_object"), 1, GL_FALSE, glm::value_ptr(clip_from_object));
    glUniform2f(p.uniform("u_viewport_size"), float(cam.raster.width), float(cam.raster.height));
}

void Renderer::set_lighting_uniforms(const Program& p, const Lighting& L, int env_unit) {
    constexpr int kMaxLights = 8;
    if (L.lights.size() > size_t(kMaxLights))
        throw InputError("the GPU path supports up to " + std::to_string(kMaxLights) + " lights, the scene has " + std::to_string(L.lights.size()) +
                         " (use --backend cpu)");
    const int n = int(L.lights.size());
    glUniform1i(p.uniform("u_light_count"), n);
    for (int i = 0; i < n; ++i) {
        const Light& l = L.lights[size_t(i)];
        auto at = [i](const char* array) { return std::string(array).append("[").append(std::to_string(i)).append("]"); };
        glUniform1i(p.uniform(at("u_light_point").c_str()), l.point ? 1 : 0);
        glUniform3fv(p.uniform(at("u_light_dir").c_str()), 1, glm::value_ptr(l.direction));
        glUniform3fv(p.uniform(at("u_light_pos").c_str()), 1, glm::value_ptr(l.position));
        glUniform3fv(p.uniform(at("u_light_radiance").c_str()), 1, glm::value_ptr(l.radiance));
    }
    glUniform3fv(p.uniform("u_env_color"), 1, glm::value_ptr(L.env.color));
    glUniform1f(p.uniform("u_env_intensity"), L.env.intensity);
    glUniform1i(p.uniform("u_env_lighting"), L.env_lighting ? 1 : 0);
    glUniform1i(p.uniform("u_env_has_sh"), L.sh ? 1 : 0);
    if (L.sh) glUniform3fv(p.uniform("u_env_sh"), 9, glm::value_ptr(L.sh->c[0]));
    glUniform1i(p.uniform("u_env_has_map"), L.env.map ? 1 : 0);
    glActiveTexture(GLenum(GL_TEXTURE0 + env_unit));
    glBindTexture(GL_TEXTURE_2D, L.env.map ? texture(L.env.map, false) : 0);
    glUniform1i(p.uniform("u_env_map"), env_unit);
}

GLuint Renderer::aov_texture(const std::string& name) const {
    for (size_t b = 0; b < batches_.size(); ++b)
        for (size_t i = 0; i < batches_[b].size(); ++i)
            if (batches_[b][i].name == name) return targets_[b].color(int(i));
    return 0;
}

// [SECTION] Frame
void Renderer::render(const Scene& s, const Evaluation& ev, int width, int height, const std::vector<std::string>& aovs) {
    PROFILE_SCOPE("frame.gpu");
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError("frame size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range (1..16384 per side)");
    resources_.collect();  // GL objects of results that are gone
    layout_ = frame_layout(s, aovs);
    width_ = width, height_ = height;
    // Batches of attachments: radiance first; more AOVs than one framebuffer takes go in further batches.
    const size_t per_batch = size_t(max_attachments());
    batches_.clear();
    for (size_t i = 0; i < layout_.size(); i += per_batch)
        batches_.emplace_back(layout_.begin() + long(i), layout_.begin() + long(std::min(layout_.size(), i + per_batch)));
    targets_.resize(batches_.size());
    for (size_t b = 0; b < batches_.size(); ++b) targets_[b].resize(width, height, int(batches_[b].size()));

    const FrameCamera cam = make_camera(s, world_bounds(s, ev), width, height);
    const Lighting lighting = make_lighting(s, ev);
    // The objects of technique t that use method m (null: the paper's, whose pass runs the frame steps).
    const auto context_for = [&](const Technique& t, const Method* m = nullptr) {
        DrawContext ctx{s, ev, cam, lighting, {}, *this, cam.raster.proj * cam.raster.view};
        ctx.objects = method_objects(s, t, m);
        return ctx;
    };

    // [SECTION] GPU timings of this frame
    // Every frame step and pass is one range of the timeline (GpuTimeline); their answers arrive
    // when the GPU has them (at once on a software renderer), each into the profiler, and the
    // frame's total once all are in. Nothing here waits for the GPU.
    impl_->timeline->poll();  // earlier frames' answers that are ready
    struct FrameTimes {
        uint64_t frame = 0;
        Profiler* profiler = nullptr;
        int begun = 0, answered = 0;
        bool closed = false, valid = true;
        double sum = 0;
        std::map<std::string, double> steps;  // step name -> GPU ms
    };
    auto ft = std::make_shared<FrameTimes>();
    ft->frame = ++impl_->frame;
    ft->profiler = &Profiler::current();
    last_gpu_ms_ = std::numeric_limits<double>::quiet_NaN();
    const auto complete = [this](FrameTimes& f) {
        if (!f.closed || f.answered < f.begun) return;
        if (f.valid) f.profiler->record("frame.gpu/gpu", f.sum, Device::Gpu);
        if (f.frame == impl_->frame) last_gpu_ms_ = f.valid ? f.sum : std::numeric_limits<double>::quiet_NaN();
        last_complete_gpu_ms_ = f.valid ? f.sum : last_complete_gpu_ms_;
    };
    // A range recorded under `path` (and, for a step, under its name).
    const auto range_done = [this, ft, complete](std::string path, std::string step) {
        return [this, ft, complete, path = std::move(path), step = std::move(step)](double ms) {
            ++ft->answered;
            if (std::isfinite(ms)) {
                ft->profiler->record(path, ms, Device::Gpu);
                ft->sum += ms;
            } else {
                ft->valid = false;
            }
            if (!step.empty()) {
                ft->steps[step] = ms;
                auto& latest = impl_->latest_steps[step];
                if (ft->frame >= latest.first) latest = {ft->frame, ms};
                show_step_times();
            }
            complete(*ft);
        };
    };
    const auto begin_range = [&] {
        ++ft->begun;
        impl_->timeline->begin();
    };
    // A pass that throws (bad input) leaves no range open behind it: the next frame starts clean.
    struct CloseOnThrow {
        GpuTimeline& t;
        ~CloseOnThrow() { t.abandon(); }
    } close_on_throw{*impl_->timeline};
    // Passes get ranges of their own on hardware, and on a software renderer when asked
    // (set_pass_timing): there each range finishes the GPU's queue, which splits the frame's work.
    const bool per_pass = !impl_->timeline->software() || pass_timing_;

    // Frame steps: offscreen work before the frame, each timed on its own, reused while its inputs hold.
    last_steps_ = impl_->scheduler.run(s, ev, [&](const Technique& t, const FrameStepDecl& d, const std::vector<int>&) {
        PROFILE_SCOPE("step." + d.name);
        DrawContext ctx = context_for(t);
        begin_range();
        impl_->steps.at(d.name)(ctx);
        impl_->timeline->end(range_done("frame.gpu/step." + d.name + "/gpu", d.name));
        check_gl(("frame step " + d.name).c_str());
        FrameStepScheduler::Work w;
        const auto it = ft->steps.find(d.name);
        w.ms = it != ft->steps.end() ? it->second : std::numeric_limits<double>::quiet_NaN();  // NaN until the GPU answers
        return w;
    });

    // Every technique's paper method, then its other methods.
    std::vector<std::pair<const Technique*, const Method*>> drawn;
    for (const Technique* t : Registry::instance().techniques()) {
        drawn.emplace_back(t, nullptr);
        for (const Method* m : t->methods())
            if (!m->shares_paper_pipeline()) drawn.emplace_back(t, m);
    }
    if (!per_pass) begin_range();
    for (size_t b = 0; b < batches_.size(); ++b) {
        if (per_pass) begin_range();
        targets_[b].bind();
        glDisable(GL_BLEND);
        glDisable(GL_CULL_FACE);
        glDisable(GL_SCISSOR_TEST);
        glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
        glClearColor(0.f, 0.f, 0.f, 0.f);
        glClearDepth(1.0);
        glDepthMask(GL_TRUE);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        const bool has_radiance = std::any_of(batches_[b].begin(), batches_[b].end(), [](const AovDecl& a) { return a.name == "radiance"; });
        if (!cam.texture_mode && has_radiance) {
            // Background: the environment through each pixel; objects overwrite it.
            glDisable(GL_DEPTH_TEST);
            bind_outputs({common_aovs().front()}, b);
            if (!lighting.env.map) {
                // A constant environment is the radiance's clear colour: no pass over every pixel.
                const vec3 c = lighting.env.color * lighting.env.intensity;
                const float rgba[4] = {c.r, c.g, c.b, 1.f};
                glClearBufferfv(GL_COLOR, 0, rgba);
            } else {
                impl_->background.use();
                glUniformMatrix4fv(impl_->background.uniform("u_inv_view_proj"), 1, GL_FALSE, glm::value_ptr(cam.inv_view_proj));
                set_lighting_uniforms(impl_->background, lighting, 0);
                impl_->draw_fullscreen_triangle();
            }
        }
        if (per_pass) impl_->timeline->end(range_done("frame.gpu/clear/gpu", ""));
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        for (const auto& [t, m] : drawn) {
            DrawContext ctx = context_for(*t, m);
            if (ctx.objects.empty()) continue;
            const std::string key = m ? t->name() + "/" + m->name() : t->name();
            TechniquePass& pass = *impl_->passes.at(key);
            // The outputs bound: all the technique's, or with output variants those of this batch.
            std::vector<AovDecl> bound;
            for (const AovDecl& o : t->outputs())
                if (!pass.output_variants() || std::any_of(batches_[b].begin(), batches_[b].end(), [&](const AovDecl& a) { return a.name == o.name; }))
                    bound.push_back(o);
            for (const AovDecl& o : bound) ctx.outputs.push_back(o.name);
            bind_outputs(bound, b);
            if (per_pass) begin_range();
            pass.draw(ctx);
            if (per_pass) impl_->timeline->end(range_done("frame.gpu/draw." + key + "/gpu", ""));
        }
    }
    if (!per_pass) impl_->timeline->end(range_done("frame.gpu/draw/gpu", ""));
    ft->closed = true;
    show_step_times();
    complete(*ft);
    check_gl("Renderer::render");
}

Frame Renderer::read_frame() const {
    PROFILE_SCOPE("frame.gpu.readback");
    Frame f = make_frame(layout_, width_, height_);
    f.steps = last_steps_;
    for (size_t b = 0; b < batches_.size(); ++b)
        for (size_t i = 0; i < batches_[b].size(); ++i) {
            const std::vector<float> rgba = targets_[b].read_rgba(int(i));
            Image& img = f.aov(batches_[b][i].name);
            for (size_t p = 0; p < size_t(f.width) * size_t(f.height); ++p)
                for (int c = 0; c < img.channels; ++c) img.data[p * size_t(img.channels) + size_t(c)] = rgba[p * 4 + size_t(c)];
        }
    return f;
}
}  // namespace mesolab::gpu
