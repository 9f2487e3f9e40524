#include "app/workbench.h"
#include "core/error.h"
#include "gpu/context.h"
#include "gpu/renderer.h"

#include <epoxy/gl.h>
#include <chrono>
#include <cstdio>
#include <unistd.h>

namespace mesolab {

Backend parse_backend(const std::string& s) {
    if (s == "cpu") return Backend::Cpu;
    if (s == "gpu") return Backend::Gpu;
    throw InputError("--backend: '" + s + "' is not one of gpu|cpu");
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
    using clock = std::chrono::steady_clock;
    RenderResult r;
    auto t0 = clock::now();
    r.eval = session_.evaluate_frame(s, req.progress);
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
        glFinish();
        r.render_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
        r.gpu_ms = g.last_gpu_ms();
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
