#pragma once
// [SECTION] Renderers: cpu, gpu and truth behind one interface
// A renderer turns a scene into a Frame: the CPU reference (render_cpu), the GPU path through a
// headless OpenGL context (gpu/headless.h) and the Monte-Carlo truth of the explicit meso-geometry
// (core/truth/renderer.h). Everything that renders (the workbench under `capture`, `sweep`, `bench`
// and Python, the window's Truth view) asks for one by name and calls it through this interface
// without knowing which one runs; what differs between them is said by their traits.
//
//  - RenderRequest: the renderer's name, the size, the AOVs, the truth's sampling (for sampled
//    renderers), progress, a per-pass callback and a cancel flag.
//  - RenderResult: the frame, the stages' evaluation, the timings and, for a sampled renderer,
//    what its samples are (SampledRun).
//  - The comparison AOV truth_error is declared once (kComparisons): asking a renderer for it
//    renders the scene on that renderer and on the reference renderer and keeps their difference
//    (render_frame).
//
// A renderer is registered once (RendererRegistry::add, e.g. from its folder's install function);
// the command line's --backend and Python's backend= list what is registered.
#include "core/render.h"
#include "core/session.h"
#include "core/truth/truth.h"

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mesolab {

// What a sampled renderer (the truth) did: the samples the frame holds, those it took from the
// cache, why it stopped, its cache key and (a partial render) its sums.
struct SampledRun {
    int spp = 0;
    int cached_spp = 0;
    TruthEnd ended = TruthEnd::Samples;
    std::string key;
    std::shared_ptr<const TruthAccumulator> sums;  // a partial render (RenderRequest::partial): always
};

struct RenderRequest {
    std::string renderer = "gpu";   // a registered renderer's name (RendererRegistry::names)
    int width = 512, height = 512;
    std::vector<std::string> aovs;  // besides radiance (frame_layout); empty = every AOV of the scene
    bool coverage = false;          // also fill Frame::coverage (untimed; any renderer)
    TruthSettings truth;            // a sampled renderer's samples per pixel, seed, noise target, time limit, sample range
    // A sampled renderer: render samples [truth.first, truth.spp) as a part of a truth (--samples
    // A:B), neither read from nor kept in its cache; SampledRun::sums holds its sums.
    bool partial = false;
    ProgressFn progress;
    // A progressive renderer: called with the frame after every finished pass (passes of 1, 2,
    // 4, ... samples per pixel, each continuing the last: the same bytes as one render of as
    // many). Without it the renderer renders in one pass.
    std::function<void(const Frame&, int spp)> on_pass;
    // Set from another thread to stop: the stages (and the truth's samples) stop at their next
    // check with Cancelled, and the session stays usable (what finished stays cached).
    const std::atomic<bool>* cancel = nullptr;
};

struct RenderResult {
    Frame frame;
    Evaluation eval;
    std::string renderer;   // the renderer's device: GL_RENDERER, "cpu" or "truth"
    double stages_ms = 0;   // evaluation of the stage graph
    double render_ms = 0;   // frame render (GPU: wall time to a finished frame, read-back excluded)
    double gpu_ms = 0;      // GPU time of the frame: the sum of its steps' and passes' timer queries (GPU; NaN without a valid answer)
    bool gpu_ms_is_wall = false;  // a software GL renderer: gpu_ms is the wall time of that work on the CPU (gpu::GpuTimeline)
    std::optional<SampledRun> sampled;  // a sampled renderer's run
    // When the request asked for a comparison AOV (truth_error): the comparison with the
    // reference renderer's frame (rendered in reference_ms), and that run.
    std::optional<TruthComparison> truth;
    std::optional<Frame> truth_frame;  // the reference's frame (radiance, normal, truth_stderr)
    std::optional<SampledRun> truth_run;
    double truth_ms = 0;
};

// What a renderer is, as the callers need to know it (never its name).
struct RendererTraits {
    // Samples a converging estimate (TruthSettings apply; --samples A:B parts; SampledRun); its
    // frames are what the comparison AOVs compare against.
    bool sampled = false;
    // Runs the technique's real-time frame (frame_layout's AOVs, frame steps, Technique::shade_*).
    bool realtime = false;
    bool needs_gl = false;  // needs an OpenGL context (made on first use)
};

// Where a renderer keeps what outlives the process.
struct RendererSetup {
    std::string version;       // the program's (part of every cache key)
    std::string truth_folder;  // where truths are kept between runs (cache_folder("truth")); "": nowhere (--no-cache)
};

class Renderer {
public:
    virtual ~Renderer() = default;
    // The frame of `s`, its stages evaluated in `session` (their cache, memory budget, store).
    // InputError for a request this renderer cannot serve (check), Cancelled when r.cancel was set.
    virtual RenderResult render(Session& session, const Scene& s, const RenderRequest& r) = 0;
    // The device it renders on, as RenderResult::renderer says it (GL_RENDERER for the GPU); may
    // make its context: std::runtime_error when it cannot.
    virtual std::string device() = 0;
    // The next frame runs every frame step again (bench times them from scratch).
    virtual void forget_frame_steps() {}
    // Time each GPU pass on its own where the renderer would not (a software GL; bench --profile).
    virtual void set_pass_timing(bool) {}
    // A short sentence on what its frame times are (bench's notes); "" when nothing to say.
    virtual std::string timing_note() { return {}; }
};

struct RendererDecl {
    std::string name;   // --backend NAME, backend="NAME"
    std::string help;   // one line for --help
    RendererTraits traits;
    std::function<std::unique_ptr<Renderer>(const RendererSetup&)> make;
    // InputError before any work: an AOV it does not write, a technique it cannot render.
    std::function<void(const Scene&, const RenderRequest&)> check;
};

class RendererRegistry {
public:
    static RendererRegistry& instance();
    // Adds (or replaces) a renderer; the built-in cpu and truth are there from the start. A
    // declaration find() or get() returned stays valid.
    void add(RendererDecl d);
    // InputError naming `what` (e.g. "--backend") and the registered names when there is none.
    const RendererDecl& find(const std::string& name, const std::string& what = "--backend") const;
    const RendererDecl* get(const std::string& name) const;
    std::vector<std::string> names() const;  // in registration order
    std::string names_text() const;          // "gpu|cpu|truth" for help texts and errors

private:
    RendererRegistry();
    std::vector<std::unique_ptr<RendererDecl>> decls_;  // stable: a reference find() gave stays valid when more are added
};

// The renderers of one session, made on first use and kept (a GL context, frame-step caches).
class Renderers {
public:
    explicit Renderers(RendererSetup setup = {}) : setup_(std::move(setup)) {}
    Renderer& get(const std::string& name);
    // The renderers made so far (for forget_frame_steps).
    void for_each(const std::function<void(Renderer&)>& f);
    const RendererSetup& setup() const { return setup_; }
    void set_setup(RendererSetup s);  // forgets the renderers made so far

private:
    RendererSetup setup_;
    std::map<std::string, std::unique_ptr<Renderer>> made_;
};

// The check of a renderer of the techniques' real-time frame (cpu, gpu): every AOV asked for
// exists in the scene (frame_layout).
void check_realtime_request(const Scene& s, const RenderRequest& r);

// [SECTION] Comparison AOVs
// An AOV that is not rendered but made by comparing two renderers' frames: the requested
// renderer's radiance minus the reference renderer's (TruthComparison). Users ask for it as any
// AOV (--aov truth_error, aovs=["truth_error"]).
struct ComparisonAov {
    const char* name;       // the AOV's name
    const char* reference;  // the renderer it compares with
    const char* help;
};
const std::vector<ComparisonAov>& comparison_aovs();
const ComparisonAov* comparison_aov(const std::string& name);
// truth_error's declaration: its reference is the renderer the window's error view and
// `sweep --metric truth` compare with.
const ComparisonAov& truth_error_aov();
// `aovs` without the comparison AOVs: what the renderer itself is asked for.
std::vector<std::string> rendered_aovs(const std::vector<std::string>& aovs);

// InputError before any work when the request cannot be served: an unknown renderer, an AOV it
// does not write, a comparison against itself or for a technique without that reference, a
// partial render of a renderer that does not sample.
void check_render_request(const Scene& s, const RenderRequest& r);

// The frame of `s` on r.renderer, with the comparison AOVs it asks for (their reference frames
// rendered at the same size and compared).
RenderResult render_frame(Session& session, Renderers& renderers, const Scene& s, const RenderRequest& r);

// [SECTION] Truth sampling as users give it
// The truth's sampling from what a user gives: samples per pixel (nullopt: 64, or unlimited with a
// noise target or time limit), a relative noise target (0: none), a time limit in seconds (0:
// none), checked by check_truth_settings with the option's name as the user wrote it (`names`).
TruthSettings truth_sampling(std::optional<int> spp, double noise, double time_limit_s, uint64_t seed, const TruthOptionNames& names = {});
}  // namespace mesolab
