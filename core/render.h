#pragma once
// [SECTION] Frames: camera, lights and the CPU render path.
// A frame is a set of AOV images (radiance, normal, technique AOVs) of one scene at one size.
// The CPU path rasterises every object into a G-buffer (core/raster.h), then each technique
// shades the pixels of its objects. The GPU path (gpu/renderer.h) draws the same triangles
// with the same camera and the same lighting maths, so the two agree within stated tolerances.
#include "core/env.h"
#include "core/image.h"
#include "core/raster.h"
#include "core/scene.h"
#include "core/stage.h"
#include "core/technique.h"
#include <any>
#include <functional>
#include <map>
#include <stdexcept>
#include <string_view>
#include <memory>
#include <string>
#include <vector>

namespace mesolab {

// Camera of a frame: orbit (perspective) or texture space (orthographic over (u,v)).
struct FrameCamera {
    RasterCamera raster;
    bool texture_mode = false;
    vec3 eye{0.f};        // orbit: eye position (world)
    vec3 view_dir{0.f};   // texture mode: unit direction towards the viewer
    mat4 inv_view_proj{1.f};
    // Unit direction from a world point towards the viewer.
    vec3 wo(vec3 p) const { return texture_mode ? view_dir : glm::normalize(eye - p); }
    // World direction of the primary ray through the centre of pixel (x, y), image row 0 at the top.
    vec3 ray_dir(int x, int y) const;
    // The same through any point (px, py) of the image, in pixels from its top-left corner.
    vec3 ray_dir_at(float px, float py) const;
};

// Near and far planes come from the scene's bounds so that any zoom (1e-3..1e6) keeps depth precision.
FrameCamera make_camera(const Scene& s, const std::vector<Bounds>& world_bounds, int width, int height);

struct Light {
    bool point = false;
    vec3 direction{0.f, 0.f, 1.f};  // directional: unit vector towards the light
    vec3 position{0.f};             // point light
    vec3 radiance{1.f};             // colour * intensity
    // Direction towards the light from p and the irradiance at normal incidence there.
    void sample(vec3 p, vec3& wi, vec3& E) const;
};

struct Lighting {
    std::vector<Light> lights;
    Environment env;                    // constant colour, intensity and the map
    std::shared_ptr<const SH9> sh;      // env.irradiance (null: constant colour, or effect off)
    bool env_lighting = true;           // effects.environment
    // Diffuse irradiance from the environment for normal n (0 when the effect is off).
    vec3 env_irradiance(vec3 n) const;
};
Lighting make_lighting(const Scene& s, const Evaluation& ev);

// A frame step's run in one frame (Technique::frame_steps), for the timing rows.
struct FrameStepRun {
    std::string name;
    StageStatus status = StageStatus::Ran;  // Ran, or Cached when its inputs were unchanged
    double ms = 0;                          // CPU: wall time; GPU: the step's GL timer query (NaN: no valid answer)
};

// Which object each pixel of a frame shows, from the CPU rasteriser's G-buffer (the GPU covers the
// same pixels, both following GL's rules, but for sub-pixel differences on silhouettes).
struct Coverage {
    int width = 0, height = 0;
    std::vector<int32_t> object;  // object index, -1 for the background
    // 1 where a pixel lies on an edge: a pixel of its 3x3 neighbourhood shows another triangle,
    // another object or the background (silhouettes, triangle edges, texture-space seams).
    std::vector<uint8_t> edge;
    bool empty() const { return object.empty(); }
    bool covered(size_t pixel) const { return object[pixel] >= 0; }
    size_t covered_count() const;
};
Coverage coverage_of(const GBuffer& gb);
// The coverage of a frame of `s` at width x height (rasterises without shading).
Coverage frame_coverage(const Scene& s, const Evaluation& ev, int width, int height);

// AOV images of one frame, all width x height, row 0 at the top.
struct Frame {
    int width = 0, height = 0;
    std::vector<AovDecl> layout;
    std::map<std::string, Image> aovs;
    std::vector<FrameStepRun> steps;  // the frame steps that ran before shading, in order
    Coverage coverage;                // filled on request (frame_coverage): tests, error statistics over object pixels
    Image& aov(const std::string& name) { return aovs.at(name); }
    const Image& aov(const std::string& name) const { return aovs.at(name); }
    bool has(const std::string& name) const { return aovs.count(name) != 0; }
};
Frame make_frame(const std::vector<AovDecl>& layout, int width, int height);

// The AOVs a frame holds: radiance, then the requested ones, in request order without duplicates.
// An empty request means every AOV of the scene (Registry::aovs). A name no technique of the scene
// writes is an InputError listing the scene's AOVs.
std::vector<AovDecl> frame_layout(const Scene& s, const std::vector<std::string>& requested);

// Writes one technique's outputs (Technique::outputs, declared once) into a frame: output k goes
// to the frame's image of that name, or nowhere when the frame does not hold it (not requested),
// so shading can skip the work of AOVs nobody asked for (wanted()).
class AovWriter {
public:
    AovWriter(Frame& f, const Technique& t);
    static constexpr int kRadiance = 0, kNormal = 1;  // the first two outputs of every technique
    // Position of a declared output (std::logic_error when the technique does not declare it).
    int index(std::string_view name) const;
    bool wanted(int output) const { return images_[size_t(output)] != nullptr; }
    void put(int output, int x, int y, vec3 v) const {
        if (Image* img = images_[size_t(output)]) {
            float* p = img->at(x, y);
            for (int c = 0; c < img->channels && c < 3; ++c) p[c] = v[c];
        }
    }
    void put(int output, int x, int y, float v) const {
        if (Image* img = images_[size_t(output)]) img->at(x, y)[0] = v;
    }

private:
    std::vector<AovDecl> outputs_;
    std::vector<Image*> images_;
};

// The outputs of a frame's steps, by step name (each a std::shared_ptr<const T> in a std::any).
using FrameStepOutputs = std::map<std::string, std::any>;

// A frame step's output through its handle (std::logic_error when the step has none this frame).
template <class T>
const T& step_output(const FrameStepOutputs& steps, const FrameStep<T>& step) {
    auto it = steps.find(std::string(step.name));
    if (it == steps.end() || !it->second.has_value()) throw std::logic_error("frame step " + std::string(step.name) + " has no output");
    return *std::any_cast<std::shared_ptr<const T>>(it->second);
}

// Everything a technique's frame step needs (FrameStepDecl::run_cpu).
struct FrameStepContext {
    const Scene& scene;
    const Evaluation& eval;
    const FrameCamera& camera;
    const Lighting& lighting;
    std::vector<int> objects;        // indices of the scene objects that use this technique
    const FrameStepOutputs& steps;   // outputs of the steps that ran before
    // An earlier step's output (std::logic_error when it has none).
    template <class T>
    const T& step(const FrameStep<T>& s) const { return step_output(steps, s); }
};

// The fingerprint of a frame step's declared inputs for a scene and an evaluation.
std::string frame_step_fingerprint(const Scene& s, const Evaluation& ev, const FrameStepDecl& d);

// The one scheduler of frame steps, for both backends: it walks the scene's techniques' steps in
// their declared order and runs each, or reuses its output while the fingerprint of its declared
// inputs (frame_step_fingerprint) is the one of the last frame that ran it. The work itself is the
// caller's (`Runner`): the CPU path calls FrameStepDecl::run_cpu and keeps the output here; the
// GPU path dispatches its pass's step, whose output stays in GL objects. Owned by whoever renders
// frames one after another (a Workbench, the window, a GPU renderer).
class FrameStepScheduler {
public:
    struct Work {
        std::any output;  // kept for later steps and frames (empty where the output lives elsewhere)
        double ms = 0;    // the step's time (CPU: wall; GPU: its timer query, NaN without a valid answer)
    };
    // Does one step for `objects` (the objects of its technique); outputs() holds the earlier steps'.
    using Runner = std::function<Work(const Technique&, const FrameStepDecl&, const std::vector<int>& objects)>;
    // Runs or reuses every step of the scene's techniques; returns their runs, in order.
    std::vector<FrameStepRun> run(const Scene& s, const Evaluation& ev, const Runner& work);
    const FrameStepOutputs& outputs() const { return outputs_; }
    // The next frame runs every step again, whatever its inputs.
    void forget();

private:
    std::map<std::string, std::string> fingerprints_;  // step -> inputs of the last frame that ran it
    FrameStepOutputs outputs_;
};

// Everything a technique's shade_cpu needs.
struct ShadeContext {
    const Scene& scene;
    const Evaluation& eval;
    const GBuffer& gbuffer;
    const FrameCamera& camera;
    const Lighting& lighting;
    std::vector<int> objects;  // indices of the scene objects that use this technique
    Frame& frame;
    const AovWriter& out;      // the technique's outputs into `frame`
    const FrameStepOutputs& steps;  // this frame's step outputs, by step name
    // Whether a pixel shows one of `objects`.
    bool mine(size_t pixel) const;
    // A frame step's output (std::logic_error when the step did not run).
    template <class T>
    const T& step(const FrameStep<T>& s) const { return step_output(steps, s); }
};

// The shading frame at a pixel: N the interpolated normal turned towards the viewer (surfaces are
// two-sided), T the tangent made orthogonal to it (any perpendicular when the mesh has none), B = N × T.
struct TangentFrame {
    vec3 T, B, N;
    vec3 to_local(vec3 w) const { return {glm::dot(w, T), glm::dot(w, B), glm::dot(w, N)}; }
    vec3 to_world(vec3 v) const { return T * v.x + B * v.y + N * v.z; }
};
TangentFrame tangent_frame(vec3 normal, vec3 tangent, vec3 wo);

// Frame size for a scene: texture mode asks the techniques for a native texture size first.
ivec2 frame_size(const Scene& s, const Evaluation& ev, ivec2 requested);

// The CPU render path: the techniques' frame steps, the G-buffer, the background, then each
// technique's shade_cpu. `aovs`: see frame_layout. `steps`: the scheduler that keeps frame steps'
// outputs from the previous frame (null: every step runs). Times itself under "frame.cpu/..." in
// the profiler.
Frame render_cpu(const Scene& s, const Evaluation& ev, int width, int height, const std::vector<std::string>& aovs = {},
                 FrameStepScheduler* steps = nullptr);

// The mesh drawn for an object (object space): its technique's object_mesh() if any, else the
// scene.geometry tessellation. Both render paths and the camera bounds use this.
std::shared_ptr<const TriMesh> drawn_mesh(const Scene& s, const Evaluation& ev, int object);

// World-space bounds of the scene's objects (for camera planes).
std::vector<Bounds> world_bounds(const Scene& s, const Evaluation& ev);
}  // namespace mesolab
