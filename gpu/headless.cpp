#include "gpu/headless.h"
#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/renderer.h"

#include <chrono>
#include <stdexcept>

namespace mesolab::gpu {
namespace {
using Clock = std::chrono::steady_clock;

class HeadlessRenderer final : public mesolab::Renderer {
public:
    ~HeadlessRenderer() override {
        if (context_) context_->make_current();
        renderer_.reset();  // GL objects go before their context
        context_.reset();
    }
    // The context and the GPU path, made on first use; current on the calling thread.
    gpu::Renderer& gpu() {
        if (!context_) {
            try {
                context_ = HeadlessContext::create();
            } catch (const std::exception& e) {
                throw std::runtime_error(std::string("no OpenGL context for the GPU renderer: ") + e.what());
            }
        }
        context_->make_current();
        if (!renderer_) renderer_ = std::make_unique<gpu::Renderer>();
        return *renderer_;
    }

    RenderResult render(Session& session, const Scene& s, const RenderRequest& req) override {
        RenderResult r;
        auto t0 = Clock::now();
        r.eval = session.evaluate_frame(s, req.progress, req.cancel);
        ProfilerBinding bind(session.profiler());
        r.stages_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        const ivec2 size = frame_size(s, r.eval, {req.width, req.height});
        // The frame's images: the render targets and their read-back, 16 bytes a channel of 4.
        const auto layout = frame_layout(s, req.aovs);
        double per_pixel = 4.0 * sizeof(float);
        for (const auto& a : layout) per_pixel += double(a.channels) * sizeof(float) + 4.0 * sizeof(float);
        session.check_memory("a " + std::to_string(size.x) + "x" + std::to_string(size.y) + " frame",
                             {double(size.x) * double(size.y) * per_pixel, std::to_string(layout.size()) + " AOVs", {"--size", "the AOVs requested (--aov)"}});
        gpu::Renderer& g = gpu();
        r.renderer = context_->info().renderer;
        t0 = Clock::now();
        g.render(s, r.eval, size.x, size.y, req.aovs);
        wait_for_gpu();  // the frame finished (a fence): its wall time
        r.render_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        g.wait_timings();  // answered by now: taking them waits no longer
        r.gpu_ms = g.last_gpu_ms();
        r.gpu_ms_is_wall = g.software();
        r.frame = g.read_frame();
        if (req.coverage) r.frame.coverage = frame_coverage(s, r.eval, size.x, size.y);
        return r;
    }
    std::string device() override {
        gpu();
        return context_->info().renderer;
    }
    void forget_frame_steps() override {
        if (renderer_) {
            context_->make_current();
            renderer_->forget_frame_steps();
        }
    }
    void set_pass_timing(bool on) override { gpu().set_pass_timing(on); }
    std::string timing_note() override {
        return gpu().software() ? "GPU frames: wall time to a finished frame (this GL renders on the CPU; its timer queries do not see that work)."
                                : "GPU frames: wall time to a finished frame (a fence), and the GPU time of its steps and passes (timer queries).";
    }

private:
    std::unique_ptr<HeadlessContext> context_;
    std::unique_ptr<gpu::Renderer> renderer_;
};
}  // namespace

void install_headless_renderer() {
    static const bool once = [] {
        RendererRegistry::instance().add({"gpu", "each technique's real-time frame on the GPU (OpenGL 4.3, a headless EGL context)", {false, true, true},
                                          [](const RendererSetup&) { return std::make_unique<HeadlessRenderer>(); }, check_realtime_request});
        return true;
    }();
    (void)once;
}

Renderer& headless_internals(mesolab::Renderer& r) {
    auto* h = dynamic_cast<HeadlessRenderer*>(&r);
    if (!h) throw std::logic_error("headless_internals: not the GPU renderer");
    return h->gpu();
}
}  // namespace mesolab::gpu
