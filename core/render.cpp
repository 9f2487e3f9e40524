#include "core/render.h"
#include "core/parallel.h"
#include "core/read_contract.h"
#include "core/error.h"
#include "core/profile.h"
#include "core/scene_stages.h"

#include <glm/gtc/matrix_transform.hpp>
#include <algorithm>
#include <chrono>
#include <optional>

namespace mesolab {

// [SECTION] Camera
vec3 FrameCamera::ray_dir(int x, int y) const { return ray_dir_at(float(x) + 0.5f, float(y) + 0.5f); }

vec3 FrameCamera::ray_dir_at(float px, float py) const {
    if (texture_mode) return -view_dir;
    const float nx = px / float(raster.width) * 2.f - 1.f;
    const float ny = 1.f - py / float(raster.height) * 2.f;
    vec4 a = inv_view_proj * vec4(nx, ny, -1.f, 1.f), b = inv_view_proj * vec4(nx, ny, 1.f, 1.f);
    return glm::normalize(vec3(b) / b.w - vec3(a) / a.w);
}

FrameCamera make_camera(const Scene& s, const std::vector<Bounds>& wb, int width, int height) {
    FrameCamera c;
    c.raster.width = width;
    c.raster.height = height;
    const vec2 orbit = s.camera.get_vec2("orbit");
    const vec3 dir = direction_from_degrees(orbit.x, orbit.y);
    if (s.camera.get_string("mode") == "texture") {
        c.texture_mode = true;
        c.raster.texture_space = true;
        c.view_dir = dir;
        return c;
    }
    const vec3 target = s.camera.get_vec3("target");
    const float distance = float(s.camera.get_float("distance"));
    c.eye = target + distance * dir;
    const vec3 up = std::fabs(dir.z) > 0.999f ? vec3(0.f, 1.f, 0.f) : vec3(0.f, 0.f, 1.f);
    c.raster.view = glm::lookAt(c.eye, target, up);
    // Near/far around the scene's bounding sphere, so depth precision survives any zoom.
    vec3 lo(1e30f), hi(-1e30f);
    for (const auto& b : wb) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
    float far_plane = 100.f, near_plane = 0.01f;
    if (!wb.empty()) {
        const vec3 centre = 0.5f * (lo + hi);
        const float radius = 0.5f * glm::length(hi - lo) * 1.01f + 1e-6f;
        const float d = glm::length(c.eye - centre);
        far_plane = d + radius;
        near_plane = std::max(d - radius, far_plane * 1e-4f);
    }
    c.raster.proj = glm::perspective(radians(float(s.camera.get_float("fov"))), float(width) / float(height), near_plane, far_plane);
    c.inv_view_proj = glm::inverse(c.raster.proj * c.raster.view);
    return c;
}

// [SECTION] Lights
void Light::sample(vec3 p, vec3& wi, vec3& E) const {
    if (!point) {
        wi = direction;
        E = radiance;
        return;
    }
    const vec3 d = position - p;
    const float r2 = std::max(glm::dot(d, d), 1e-12f);
    wi = d / std::sqrt(r2);
    E = radiance / r2;
}

vec3 Lighting::env_irradiance(vec3 n) const {
    if (!env_lighting) return vec3(0.f);
    if (sh) return sh9_irradiance(*sh, n) * env.intensity;
    return kPi * env.color * env.intensity;
}

Lighting make_lighting(const Scene& s, const Evaluation& ev) {
    Lighting L;
    for (const auto& t : s.lights) {
        Light l;
        l.point = t.get_string("type") == "point";
        const vec2 d = t.get_vec2("direction");
        l.direction = direction_from_degrees(d.x, d.y);
        l.position = t.get_vec3("position");
        l.radiance = t.get_vec3("color") * float(t.get_float("intensity"));
        L.lights.push_back(l);
    }
    L.env.color = s.env.get_vec3("color");
    L.env.intensity = float(s.env.get_float("intensity"));
    L.env.map = ev.get(stages::env_map);
    L.sh = ev.get(stages::env_irradiance);
    L.env_lighting = s.effect("environment");
    return L;
}

// [SECTION] Coverage
size_t Coverage::covered_count() const { return size_t(std::count_if(object.begin(), object.end(), [](int32_t o) { return o >= 0; })); }

Coverage coverage_of(const GBuffer& gb) {
    Coverage c;
    c.width = gb.width, c.height = gb.height;
    c.object = gb.object;
    c.edge.assign(gb.object.size(), 0);
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t p = gb.index(x, y);
            bool edge = false;
            for (int dy = -1; dy <= 1 && !edge; ++dy)
                for (int dx = -1; dx <= 1 && !edge; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx < 0 || ny < 0 || nx >= gb.width || ny >= gb.height) continue;
                    const size_t q = gb.index(nx, ny);
                    edge = gb.primitive[q] != gb.primitive[p] || gb.object[q] != gb.object[p];
                }
            c.edge[p] = edge;
        }
    });
    return c;
}

Coverage frame_coverage(const Scene& s, const Evaluation& ev, int width, int height) {
    const FrameCamera cam = make_camera(s, world_bounds(s, ev), width, height);
    std::vector<DrawItem> items;
    std::vector<std::shared_ptr<const TriMesh>> keep;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        keep.push_back(drawn_mesh(s, ev, int(i)));
        if (!keep.back()) throw std::logic_error("frame_coverage: scene.geometry was not evaluated for object " + std::to_string(i));
        items.push_back({keep.back().get(), object_to_world(s.objects[i]), int(i)});
    }
    GBuffer gb;
    rasterize(items, cam.raster, gb);
    return coverage_of(gb);
}

// [SECTION] Frames
Frame make_frame(const std::vector<AovDecl>& layout, int width, int height) {
    Frame f;
    f.width = width;
    f.height = height;
    f.layout = layout;
    for (const auto& a : layout) f.aovs.emplace(a.name, Image(width, height, a.channels, 0.f));
    return f;
}

TangentFrame tangent_frame(vec3 normal, vec3 tangent, vec3 wo) {
    vec3 N = normal;
    if (glm::dot(N, wo) < 0.f) N = -N;
    vec3 T = tangent - N * glm::dot(tangent, N);
    T = glm::dot(T, T) > 1e-12f ? glm::normalize(T)
        : (std::fabs(N.x) < 0.9f ? glm::normalize(glm::cross(N, vec3(1, 0, 0))) : glm::normalize(glm::cross(N, vec3(0, 1, 0))));
    return {T, glm::cross(N, T), N};
}

std::vector<AovDecl> frame_layout(const Scene& s, const std::vector<std::string>& requested) {
    const std::vector<AovDecl> all = Registry::instance().aovs(s);
    if (requested.empty()) return all;
    std::vector<AovDecl> r{all.front()};  // radiance
    for (const auto& name : requested) {
        if (std::any_of(r.begin(), r.end(), [&](const AovDecl& a) { return a.name == name; })) continue;
        auto it = std::find_if(all.begin(), all.end(), [&](const AovDecl& a) { return a.name == name; });
        if (it == all.end()) {
            std::string names;
            for (const auto& a : all) names += (names.empty() ? "" : ", ") + a.name;
            throw InputError("--aov " + name + ": the scene has no such AOV (available: " + names + ")");
        }
        r.push_back(*it);
    }
    return r;
}

// [SECTION] AOV writer
AovWriter::AovWriter(Frame& f, const Technique& t) : outputs_(t.outputs()) {
    for (const auto& o : outputs_) images_.push_back(f.has(o.name) ? &f.aov(o.name) : nullptr);
}

int AovWriter::index(std::string_view name) const {
    for (size_t k = 0; k < outputs_.size(); ++k)
        if (outputs_[k].name == name) return int(k);
    throw std::logic_error("AovWriter: the technique declares no output named " + std::string(name));
}

// [SECTION] Frame steps
std::string frame_step_fingerprint(const Scene& s, const Evaluation& ev, const FrameStepDecl& d) {
    std::string fp = d.name;
    for (const auto& p : d.params) fp += param_fingerprint(s, p);
    for (const StageName& st : d.stages)
        for (const StageRun* r : ev.runs_of(st)) fp += "<" + st.str() + "#" + std::to_string(r->object) + ":" + std::to_string(r->key) + ">";
    return fp;
}

namespace {
// What a frame step may read: its params and those its stages' results depend on.
DeclaredReads frame_step_reads(const Scene& s, const FrameStepDecl& d) {
    const StageGraph& g = Registry::instance().stages();
    std::vector<std::string> patterns = d.params;
    for (const StageName& st : d.stages)
        for (std::string& p : g.params_upstream(g.at(st))) patterns.push_back(std::move(p));
    return DeclaredReads("frame step " + d.name, s, std::move(patterns), -1,
                         "neither it nor a stage it reads declares: its output would be reused from an earlier frame when that key changes (declare it "
                         "in the step's params)");
}
}  // namespace

std::vector<FrameStepRun> FrameStepScheduler::run(const Scene& s, const Evaluation& ev, const Runner& work) {
    std::vector<FrameStepRun> runs;
    for (const Technique* t : Registry::instance().techniques()) {
        // A technique's frame steps are its paper method's: they run for the objects that use it.
        const std::vector<int> objects = method_objects(s, *t, nullptr);
        if (objects.empty()) continue;
        for (const FrameStepDecl& d : t->frame_steps()) {
            FrameStepRun run{d.name};
            const std::string fp = frame_step_fingerprint(s, ev, d);
            std::string& last = fingerprints_[d.name];
            if (last == fp) {
                run.status = StageStatus::Cached;
                runs.push_back(run);
                continue;
            }
            last.clear();  // a failure must not leave a stale "done" behind
            outputs_.erase(d.name);
            // The read contract: the step (CPU or GPU) reads only the keys in its fingerprint.
            std::optional<DeclaredReads> watch;
            if (check_reads_by_default()) watch.emplace(frame_step_reads(s, d));
            ParamReadScope reads(watch ? &*watch : nullptr);
            Work w = work(*t, d, objects);
            run.ms = w.ms;
            outputs_[d.name] = std::move(w.output);
            last = fp;
            runs.push_back(run);
        }
    }
    return runs;
}

void FrameStepScheduler::forget() {
    fingerprints_.clear();
    outputs_.clear();
}

bool ShadeContext::mine(size_t pixel) const {
    const int o = gbuffer.object[pixel];
    return o >= 0 && std::find(objects.begin(), objects.end(), o) != objects.end();
}

std::shared_ptr<const TriMesh> drawn_mesh(const Scene& s, const Evaluation& ev, int object) {
    const Technique* t = Registry::instance().technique(s.objects.at(size_t(object)).technique);
    if (t)
        if (auto m = t->object_mesh(s, ev, object)) return m;
    return ev.get(stages::geometry, object);
}

std::vector<Bounds> world_bounds(const Scene& s, const Evaluation& ev) {
    std::vector<Bounds> r;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const auto mesh = drawn_mesh(s, ev, int(i));
        if (!mesh) continue;
        const Bounds b = bounds(mesh);
        const mat4 m = object_to_world(s.objects[i]);
        Bounds w{vec3(1e30f), vec3(-1e30f)};
        for (int k = 0; k < 8; ++k) {
            const vec3 p(k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z);
            const vec3 q = vec3(m * vec4(p, 1.f));
            w.lo = glm::min(w.lo, q);
            w.hi = glm::max(w.hi, q);
        }
        r.push_back(w);
    }
    return r;
}

ivec2 frame_size(const Scene& s, const Evaluation& ev, ivec2 requested) {
    if (s.camera.get_string("mode") == "texture")
        for (const Technique* t : Registry::instance().techniques())
            if (s.uses_technique(t->name()))
                if (auto size = t->texture_size(s, ev)) return *size;
    return requested;
}

Frame render_cpu(const Scene& s, const Evaluation& ev, int width, int height, const std::vector<std::string>& aovs, FrameStepScheduler* scheduler) {
    PROFILE_SCOPE("frame.cpu");
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError("frame size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range (1..16384 per side)");
    const Registry& reg = Registry::instance();
    Frame f = make_frame(frame_layout(s, aovs), width, height);
    const FrameCamera cam = make_camera(s, world_bounds(s, ev), width, height);
    const Lighting lighting = make_lighting(s, ev);

    // Frame steps: offscreen work before shading, reused while their inputs are unchanged.
    FrameStepScheduler local;
    FrameStepScheduler& steps = scheduler ? *scheduler : local;
    f.steps = steps.run(s, ev, [&](const Technique&, const FrameStepDecl& d, const std::vector<int>& objs) {
        PROFILE_SCOPE("step." + d.name);
        const auto t0 = std::chrono::steady_clock::now();
        FrameStepScheduler::Work w;
        w.output = d.run_cpu(FrameStepContext{s, ev, cam, lighting, objs, steps.outputs()});
        w.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        return w;
    });
    const FrameStepOutputs& step_out = steps.outputs();

    // The G-buffer is reused between frames of a thread: first-touch of ~50 bytes per pixel
    // costs more than the rasterisation of a simple scene.
    thread_local GBuffer tls_gbuffer;
    GBuffer& gb = tls_gbuffer;  // lambdas on worker threads must see this thread's buffer
    {
        PROFILE_SCOPE("raster");
        std::vector<DrawItem> items;
        std::vector<std::shared_ptr<const TriMesh>> keep;
        for (size_t i = 0; i < s.objects.size(); ++i) {
            keep.push_back(drawn_mesh(s, ev, int(i)));
            if (!keep.back()) throw std::logic_error("render_cpu: scene.geometry was not evaluated for object " + std::to_string(i));
            const Technique* t = reg.technique(s.objects[i].technique);
            const Method* method = t ? t->method_of(s.objects[i]) : nullptr;
            const bool derivatives = method && !method->shares_paper_pipeline() ? method->uses_uv_derivatives() : t && t->uses_uv_derivatives();
            items.push_back({keep.back().get(), object_to_world(s.objects[i]), int(i), derivatives});
        }
        rasterize(items, cam.raster, gb);
    }
    {
        PROFILE_SCOPE("background");
        Image& rad = f.aov("radiance");
        // A constant environment (no map) needs no ray directions.
        const bool constant = lighting.env.constant();
        const vec3 L_const = lighting.env.color * lighting.env.intensity;
        if (!cam.texture_mode)
            mesolab::parallel_for(0, height, [&](int y) {
                for (int x = 0; x < width; ++x) {
                    if (gb.object[gb.index(x, y)] >= 0) continue;
                    const vec3 L = constant ? L_const : lighting.env.radiance(cam.ray_dir(x, y));
                    float* p = rad.at(x, y);
                    p[0] = L.x, p[1] = L.y, p[2] = L.z;
                }
            });
    }
    for (const Technique* t : reg.techniques()) {
        const AovWriter out(f, *t);
        // The paper's method, then each other method, on the objects that use it.
        if (const std::vector<int> objs = method_objects(s, *t, nullptr); !objs.empty()) {
            ShadeContext ctx{s, ev, gb, cam, lighting, objs, f, out, step_out};
            PROFILE_SCOPE("shade." + t->name());
            t->shade_cpu(ctx);
        }
        for (const Method* m : t->methods()) {
            const std::vector<int> objs = method_objects(s, *t, m);
            if (objs.empty()) continue;
            ShadeContext ctx{s, ev, gb, cam, lighting, objs, f, out, step_out};
            PROFILE_SCOPE("shade." + t->name() + "/" + m->name());
            m->shade_cpu(ctx);
        }
    }
    return f;
}
}  // namespace mesolab
