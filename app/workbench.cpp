#include "app/workbench.h"
#include "core/error.h"
#include "core/stage_store.h"
#include "gpu/headless.h"
#include "gpu/renderer.h"

#include <cstdio>
#include <unistd.h>

namespace mesolab {

RendererSetup default_renderer_setup() { return {version_string(), cache_folder("truth")}; }

Workbench::Workbench(RendererSetup setup) : renderers_(std::move(setup)) {
    gpu::install_gpu_compute();
    gpu::install_headless_renderer();
}
Workbench::~Workbench() = default;

gpu::Renderer& Workbench::gpu() { return gpu::headless_internals(renderer("gpu")); }

void Workbench::set_truth_cache(std::string folder) {
    RendererSetup s = renderers_.setup();
    s.truth_folder = std::move(folder);
    renderers_.set_setup(std::move(s));
}

void Workbench::forget_frame_steps() {
    renderers_.for_each([](Renderer& r) { r.forget_frame_steps(); });
}

RenderResult Workbench::render(const Scene& s, const RenderRequest& req) { return render_frame(session_, renderers_, s, req); }

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
