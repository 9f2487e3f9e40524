#include "app/workbench.h"
#include "core/error.h"
#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/renderer.h"

#include <epoxy/gl.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <unistd.h>

namespace mesolab {

Backend parse_backend(const std::string& s) {
    if (s == "cpu") return Backend::Cpu;
    if (s == "gpu") return Backend::Gpu;
    if (s == "truth") return Backend::Truth;
    throw InputError("--backend: '" + s + "' is not one of gpu|cpu|truth");
}

Workbench::Workbench() { gpu::install_gpu_compute(); }
Workbench::~Workbench() {
    renderer_.reset();  // GL objects go before their context
    context_.reset();
}

gpu::Renderer& Workbench::gpu() {
    if (!context_) context_ = gpu::HeadlessContext::create();
    context_->make_current();
    if (!renderer_) renderer_ = std::make_unique<gpu::Renderer>();
    return *renderer_;
}

void Workbench::forget_frame_steps() {
    cpu_steps_.forget();
    if (renderer_) renderer_->forget_frame_steps();
}

std::string Workbench::gl_renderer() {
    gpu();
    return context_->info().renderer;
}

RenderResult Workbench::render(const Scene& s, const RenderRequest& req) {
    // truth_error: the real-time frame without it, the truth at the same size, their difference.
    const auto te = std::find(req.aovs.begin(), req.aovs.end(), "truth_error");
    if (te == req.aovs.end() || req.backend == Backend::Truth) return render_one(s, req);
    RenderRequest rt = req;
    rt.aovs.erase(rt.aovs.begin() + (te - req.aovs.begin()));
    if (rt.aovs.empty()) rt.aovs = {"radiance"};
    RenderResult r = render_one(s, rt);
    RenderRequest tr = req;
    tr.backend = Backend::Truth;
    tr.width = r.frame.width, tr.height = r.frame.height;
    tr.aovs = {"truth_stderr"};
    tr.coverage = false;
    const RenderResult t = render_one(s, tr);
    r.truth = compare_to_truth(r.frame, t.frame, req.truth);
    r.truth->spp = t.truth_spp;
    r.truth_frame = t.frame;
    r.truth_ms = t.render_ms;
    r.truth_spp = t.truth_spp, r.truth_ended = t.truth_ended, r.truth_cached_spp = t.truth_cached_spp, r.truth_key = t.truth_key;
    r.frame.layout.push_back({"truth_error", 3, "Real-time radiance minus the truth's"});
    r.frame.aovs["truth_error"] = r.truth->error;
    return r;
}

RenderResult Workbench::render_one(const Scene& s, const RenderRequest& req) {
    using clock = std::chrono::steady_clock;
    RenderResult r;
    auto t0 = clock::now();
    if (req.backend == Backend::Truth) {  // only the physical description's stages
        r.eval = session_.evaluate(s, truth_stages(s), req.progress, req.cancel);
        r.stages_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
        const ivec2 size = frame_size(s, r.eval, {req.width, req.height});  // texture mode: the techniques' native size, as the real-time frame
        // The exact sums (radiance, its square, exitance, irradiance: 16 bytes a channel), the
        // normals and the frame's five AOVs.
        session_.check_memory("a " + std::to_string(size.x) + "x" + std::to_string(size.y) + " truth",
                              {double(size.x) * double(size.y) * (4.0 * 3.0 * 16.0 + 3.0 * sizeof(float) + 15.0 * sizeof(float)), "its sums and 5 AOVs", {"--size"}});
        t0 = clock::now();
        check_truth_request(s, size.x, size.y, req.truth, req.aovs);
        r.truth_key = truth_cache_.key(s, size.x, size.y, req.truth.seed);
        std::optional<TruthAccumulator> cached;
        if (!req.truth_part) cached = truth_cache_.load(r.truth_key);
        const bool keep_file = cached && cached->spp > req.truth.spp;  // a truth of more samples than asked stays on disk
        if (cached && !cached->continues(size.x, size.y, req.truth.seed, req.truth.first, req.truth.spp)) cached.reset();
        r.truth_cached_spp = cached ? cached->spp : 0;
        TruthAccumulator a = accumulate_truth(s, r.eval, size.x, size.y, req.truth, cached ? &*cached : nullptr, req.progress, req.cancel);
        if (a.ended == TruthEnd::Cancelled) throw Cancelled();
        if (!req.truth_part && a.spp != r.truth_cached_spp && !keep_file) truth_cache_.store(r.truth_key, a);
        r.frame = truth_frame(a);
        r.render_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
        r.renderer = "truth";
        r.truth_spp = a.samples();
        r.truth_ended = a.ended;
        if (req.truth_part) r.truth_sums = std::make_shared<const TruthAccumulator>(std::move(a));
        if (req.coverage) r.frame.coverage = frame_coverage(s, r.eval, size.x, size.y);
        return r;
    }
    r.eval = session_.evaluate_frame(s, req.progress, req.cancel);
    ProfilerBinding bind(session_.profiler());
    r.stages_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
    const ivec2 size = frame_size(s, r.eval, {req.width, req.height});
    // The frame's images (and the CPU's G-buffer, about 52 bytes a pixel) before allocating them.
    double per_pixel = req.backend == Backend::Cpu ? 52.0 : 4.0 * sizeof(float);
    const auto layout = frame_layout(s, req.aovs);
    for (const auto& a : layout) per_pixel += double(a.channels) * sizeof(float) + (req.backend == Backend::Gpu ? 4.0 * sizeof(float) : 0.0);
    session_.check_memory("a " + std::to_string(size.x) + "x" + std::to_string(size.y) + " frame",
                          {double(size.x) * double(size.y) * per_pixel, std::to_string(layout.size()) + " AOVs", {"--size", "the AOVs requested (--aov)"}});
    if (req.backend == Backend::Cpu) {
        t0 = clock::now();
        r.frame = render_cpu(s, r.eval, size.x, size.y, req.aovs, &cpu_steps_);
        r.render_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
        r.renderer = "cpu";
    } else {
        gpu::Renderer& g = gpu();
        r.renderer = context_->info().renderer;
        t0 = clock::now();
        g.render(s, r.eval, size.x, size.y, req.aovs);
        gpu::wait_for_gpu();  // the frame finished (a fence): its wall time
        r.render_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
        g.wait_timings();  // answered by now: taking them waits no longer
        r.gpu_ms = g.last_gpu_ms();
        r.gpu_ms_is_wall = g.software();
        r.frame = g.read_frame();
    }
    if (req.coverage) r.frame.coverage = frame_coverage(s, r.eval, size.x, size.y);
    return r;
}

// [SECTION] Progress on a terminal
namespace {
bool g_progress_shown = false;
}

ProgressFn tty_progress() {
    if (!::isatty(2)) return {};
    return [](const std::string& stage, double f) {
        std::fprintf(stderr, "\r  %-32s %5.1f%%", stage.c_str(), 100.0 * f);
        std::fflush(stderr);
        g_progress_shown = true;
    };
}

void tty_progress_done() {
    if (g_progress_shown) std::fprintf(stderr, "\r%60s\r", "");
    g_progress_shown = false;
}
}  // namespace mesolab
