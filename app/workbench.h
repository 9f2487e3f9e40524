#pragma once
// Headless rendering shared by capture, sweep, bench, export, info and the Python module. A
// Workbench is one evaluation session (core/session.h: the stage cache, the timings, the memory
// budget) with its renderers (core/renderer.h: cpu, gpu with its EGL context made on first use,
// truth with its cache), so two workbenches in one process share nothing.
#include "core/render.h"
#include "core/renderer.h"
#include "core/session.h"
#include "core/stage.h"
#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mesolab::gpu {
class Renderer;
}  // namespace mesolab::gpu

namespace mesolab {

const char* version_string();

// Where this program keeps what outlives the process: its version and the cache root's truth/
// folder (core/stage_store.h).
RendererSetup default_renderer_setup();

class Workbench {
public:
    explicit Workbench(RendererSetup setup = default_renderer_setup());
    ~Workbench();
    // A frame of `s` on the renderer r.renderer (core/renderer.h, render_frame): asking for a
    // comparison AOV (truth_error) renders the reference too and fills RenderResult::truth.
    RenderResult render(const Scene& s, const RenderRequest& r);
    // A registered renderer of this workbench (made on first use; the GPU's context with it).
    Renderer& renderer(const std::string& name) { return renderers_.get(name); }
    // The GPU renderer's render path (its headless context current): tests look inside it.
    gpu::Renderer& gpu();
    std::string gl_renderer() { return renderer("gpu").device(); }
    Session& session() { return session_; }
    // Where truths are kept between runs ("": nowhere); forgets the renderers made so far.
    void set_truth_cache(std::string folder);
    // The next frame runs every frame step again (bench times them from scratch).
    void forget_frame_steps();
    Evaluation evaluate(const Scene& s, const std::vector<StageName>& targets, const ProgressFn& progress = {}) {
        return session_.evaluate(s, targets, progress);
    }

private:
    Session session_;
    Renderers renderers_;
};

// What `mesolab capture` writes for one rendered scene, into `out_dir`: NAME.png (8-bit sRGB
// radiance), NAME.<aov>.exr for each of `aovs` (32-bit float), with truth_error NAME.truth.png and
// NAME.truth_error.png, and the sidecar NAME.json (capture_sidecar: parameters, renderer, timings,
// stages, version; `file` is the preset it came from). Returns the paths written, the PNG first.
json capture_sidecar(const Scene& s, const std::string& file, const RenderResult& r, const std::vector<std::string>& written, const TruthSettings& truth);
std::vector<std::string> write_capture(const std::string& out_dir, const Scene& s, const std::string& file, const RenderResult& r,
                                       const std::vector<std::string>& aovs, const TruthSettings& truth);

// Progress printer for the CLI: a single updating line on a TTY (stderr), nothing otherwise.
ProgressFn tty_progress();
void tty_progress_done();
}  // namespace mesolab
