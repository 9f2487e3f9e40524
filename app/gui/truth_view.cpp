#include "app/gui/truth_view.h"
#include "core/error.h"
#include "core/renderer.h"
#include "core/session.h"
#include "app/workbench.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace mesolab::gui {

// [SECTION] TruthRunner
TruthRunner::TruthRunner() : thread_([this](std::stop_token st) { loop(st); }) {}

TruthRunner::~TruthRunner() {
    cancel_ = true;
    thread_.request_stop();
    cv_.notify_all();
}

void TruthRunner::want(const Scene& s, int width, int height, const TruthSettings& settings) {
    std::string description;
    try {
        description = truth_description(s);
    } catch (const std::exception& e) {  // a technique without a truth: said in the status
        std::lock_guard<std::mutex> lock(mutex_);
        status_.error = e.what();
        wanted_.reset();
        work_ = false;
        return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (wanted_ && wanted_->description == description && wanted_->width == width && wanted_->height == height &&
        wanted_->settings.seed == settings.seed && wanted_->settings.spp == settings.spp)
        return;  // the same request (also after a cancel: asked again only when something changes)
    const bool same_truth = have_ && have_->description == description && have_->width == width && have_->height == height &&
                            have_->settings.seed == settings.seed;
    wanted_ = Job{s, description, width, height, settings};
    status_.error.clear();
    status_.cancelled = false;
    status_.target = settings.spp;
    if (!same_truth || settings.spp < have_spp_) cancel_ = true;  // the pass under way is for another truth
    work_ = !same_truth || have_spp_ < settings.spp;
    cv_.notify_all();
}

void TruthRunner::cancel() {
    std::lock_guard<std::mutex> lock(mutex_);
    cancel_ = true;
    if (work_) status_.cancelled = true;
    work_ = false;
    cv_.notify_all();
}

std::string TruthRunner::key_of(const Scene& s, int width, int height, uint64_t seed) {
    return truth_description(s) + "|" + std::to_string(width) + "x" + std::to_string(height) + "|" + std::to_string(seed);
}

std::optional<TruthRunner::Published> TruthRunner::take_frame() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::optional<Published> f = std::move(published_);
    published_.reset();
    return f;
}

TruthRunner::Status TruthRunner::status() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return status_;
}

bool TruthRunner::wait_idle(std::chrono::milliseconds timeout) const {
    std::unique_lock<std::mutex> lock(mutex_);
    return idle_cv_.wait_for(lock, timeout, [&] { return !work_ && !status_.running; });
}

void TruthRunner::loop(std::stop_token st) {
    Session session;  // its own stage cache: the window's evaluations are not disturbed
    Renderers renderers(default_renderer_setup());
    for (;;) {
        Job job;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            status_.running = false;
            idle_cv_.notify_all();
            cv_.wait(lock, st, [&] { return work_; });
            if (st.stop_requested()) return;
            job = *wanted_;
            cancel_ = false;
            status_.running = true;
            status_.fraction = 0;
        }
        const std::string key = job.description + "|" + std::to_string(job.width) + "x" + std::to_string(job.height) + "|" + std::to_string(job.settings.seed);
        try {
            RenderRequest req;
            req.renderer = truth_error_aov().reference;  // the truth the window's error view compares with
            req.width = job.width, req.height = job.height;
            req.truth = job.settings;
            req.cancel = &cancel_;
            req.progress = [&](const std::string&, double f) {
                std::lock_guard<std::mutex> lock(mutex_);
                status_.fraction = f;
            };
            req.on_pass = [&](const Frame& frame, int spp) {
                std::lock_guard<std::mutex> lock(mutex_);
                status_.spp = spp;
                status_.noise_rel = truth_noise_rel(frame);
                published_ = Published{frame, key};
                have_ = job;
                have_spp_ = spp;
            };
            renderers.get(req.renderer).render(session, job.scene, req);
        } catch (const Cancelled&) {
            // the unfinished pass is dropped; the last finished one stays (published, and kept by the renderer)
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(mutex_);
            status_.error = e.what();
            work_ = false;
        }
        std::lock_guard<std::mutex> lock(mutex_);
        if (wanted_ && wanted_->description == job.description && wanted_->width == job.width && wanted_->height == job.height &&
            wanted_->settings.seed == job.settings.seed && wanted_->settings.spp <= have_spp_ && have_ && have_->description == job.description)
            work_ = false;
    }
}

}  // namespace mesolab::gui
