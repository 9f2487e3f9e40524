#pragma once
// Headless rendering shared by capture, sweep, bench, export and info. A Workbench is one
// evaluation session (core/session.h: the stage cache, the timings, the memory budget) with its
// GPU resources (an EGL context made on first use and its renderer), so two workbenches in one
// process share nothing. It evaluates the stage graph, renders on the CPU or the GPU, and
// reports what ran.
#include "app/truth_cache.h"
#include "core/render.h"
#include "core/session.h"
#include "core/stage.h"
#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mesolab::gpu {
class HeadlessContext;
class Renderer;
}  // namespace mesolab::gpu

namespace mesolab {

const char* version_string();

enum class Backend { Cpu, Gpu, Truth };
Backend parse_backend(const std::string& s);  // "cpu" | "gpu", InputError otherwise

struct RenderRequest {
    Backend backend = Backend::Gpu;
    int width = 512, height = 512;
    std::vector<std::string> aovs;  // besides radiance (frame_layout); empty = every AOV of the scene
    bool coverage = false;          // also fill Frame::coverage (untimed; either backend)
    TruthSettings truth;            // Backend::Truth: samples per pixel, seed, noise target, time limit, sample range
    // Backend::Truth: render samples [truth.first, truth.spp) as a part of a truth (--samples A:B):
    // neither read from nor kept in the truth cache; RenderResult::truth_sums holds its sums.
    bool truth_part = false;
    ProgressFn progress;
    // Set from another thread to stop: the stages (and the truth's samples) stop at their next
    // check with Cancelled, and the session stays usable (what finished stays cached).
    const std::atomic<bool>* cancel = nullptr;
};

struct RenderResult {
    Frame frame;
    Evaluation eval;
    std::string renderer;   // GL_RENDERER or "cpu"
    double stages_ms = 0;   // evaluation of the stage graph
    double render_ms = 0;   // frame render (GPU: wall time to a finished frame, read-back excluded)
    double gpu_ms = 0;      // GPU time of the frame: the sum of its steps' and passes' timer queries (GPU backend; NaN without a valid answer)
    bool gpu_ms_is_wall = false;  // a software GL renderer: gpu_ms is the wall time of that work on the CPU (gpu::GpuTimeline)
    // When the request asked for the AOV truth_error: the comparison with the truth (whose
    // render time is truth_ms); the frame then holds truth_error.
    std::optional<TruthComparison> truth;
    std::optional<Frame> truth_frame;  // that truth (radiance, normal, truth_stderr)
    double truth_ms = 0;
    int truth_cached_spp = 0;  // Backend::Truth: samples read from the truth cache (continued to the rest, or all reused)
    // Backend::Truth: the samples the truth holds, why it stopped, its sums (a part: always; else
    // when kept) and its cache key.
    int truth_spp = 0;
    TruthEnd truth_ended = TruthEnd::Samples;
    std::shared_ptr<const TruthAccumulator> truth_sums;
    std::string truth_key;
};

class Workbench {
public:
    Workbench();
    ~Workbench();
    // A frame of `s` on the requested backend. Asking for the AOV truth_error renders the truth
    // too (r.truth settings) and fills RenderResult::truth.
    RenderResult render(const Scene& s, const RenderRequest& r);
    // The headless GL context, created on first use; throws with an explanation when none can be made.
    gpu::Renderer& gpu();
    std::string gl_renderer();
    Session& session() { return session_; }
    // Where truths are kept between runs (default: TruthCache's folder from the environment).
    void set_truth_cache(TruthCache c) { truth_cache_ = std::move(c); }
    // The next frame runs every frame step again (bench times them from scratch).
    void forget_frame_steps();
    Evaluation evaluate(const Scene& s, const std::vector<StageName>& targets, const ProgressFn& progress = {}) {
        return session_.evaluate(s, targets, progress);
    }

private:
    RenderResult render_one(const Scene& s, const RenderRequest& r);
    Session session_;
    TruthCache truth_cache_;
    FrameStepScheduler cpu_steps_;
    std::unique_ptr<gpu::HeadlessContext> context_;
    std::unique_ptr<gpu::Renderer> renderer_;
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
