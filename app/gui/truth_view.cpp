#include "app/gui/truth_view.h"
#include "app/plot.h"
#include "core/error.h"
#include "core/session.h"

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
    if (!same_truth || settings.spp < acc_.spp) cancel_ = true;  // the pass under way is for another truth
    work_ = !same_truth || acc_.spp < settings.spp;
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
    for (;;) {
        Job job;
        TruthAccumulator from;
        bool fresh = false;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            status_.running = false;
            idle_cv_.notify_all();
            cv_.wait(lock, st, [&] { return work_; });
            if (st.stop_requested()) return;
            job = *wanted_;
            cancel_ = false;
            fresh = !(have_ && have_->description == job.description && have_->width == job.width && have_->height == job.height &&
                      have_->settings.seed == job.settings.seed && acc_.spp <= job.settings.spp);
            if (!fresh) from = acc_;
            status_.running = true;
            status_.fraction = 0;
        }
        try {
            const Evaluation ev = session.evaluate(job.scene, truth_stages(job.scene));
            // Passes of 1, 2, 4, ... samples: each doubles what the frame holds, up to the target.
            int spp = fresh ? 0 : from.spp;
            while (spp < job.settings.spp) {
                TruthSettings pass = job.settings;
                pass.spp = std::min(job.settings.spp, std::max(1, 2 * spp));
                auto progress = [&](const std::string&, double f) {
                    std::lock_guard<std::mutex> lock(mutex_);
                    status_.fraction = f;
                };
                TruthAccumulator next = accumulate_truth(job.scene, ev, job.width, job.height, pass, spp > 0 ? &from : nullptr, progress, &cancel_);
                if (cancel_) break;  // the unfinished pass is dropped; the last finished one stays
                from = std::move(next);
                spp = from.spp;
                Frame frame = truth_frame(from);
                std::lock_guard<std::mutex> lock(mutex_);
                status_.spp = spp;
                status_.noise_rel = truth_noise_rel(frame);
                published_ = Published{std::move(frame), job.description + "|" + std::to_string(job.width) + "x" + std::to_string(job.height) + "|" +
                                                             std::to_string(job.settings.seed)};
                acc_ = from;
                have_ = job;
            }
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(mutex_);
            status_.error = e.what();
            work_ = false;
        }
        std::lock_guard<std::mutex> lock(mutex_);
        if (wanted_ && wanted_->description == job.description && wanted_->width == job.width && wanted_->height == job.height &&
            wanted_->settings.seed == job.settings.seed && wanted_->settings.spp <= acc_.spp && have_ && have_->description == job.description)
            work_ = false;
    }
}

// [SECTION] Error colours
namespace {
float mean_abs(const float* e) { return (std::fabs(e[0]) + std::fabs(e[1]) + std::fabs(e[2])) / 3.f; }
bool object_pixel(const Frame& truth, int x, int y) {
    const float* n = truth.aov("normal").at(x, y);
    return n[0] != 0.f || n[1] != 0.f || n[2] != 0.f;
}
}  // namespace

Image error_colors(const Image& error, const Frame& truth, float scale) {
    Image out(error.width, error.height, 3);
    for (int y = 0; y < error.height; ++y)
        for (int x = 0; x < error.width; ++x) {
            float* o = out.at(x, y);
            if (!object_pixel(truth, x, y)) {
                o[0] = o[1] = o[2] = 0.01f;
                continue;
            }
            const float* e = error.at(x, y);
            const float t = std::clamp((e[0] + e[1] + e[2]) / (3.f * scale), -1.f, 1.f);
            // White at 0; towards blue (0.05, 0.25, 1) below the truth, red (1, 0.1, 0.05) above.
            const vec3 end = t < 0.f ? vec3(0.05f, 0.25f, 1.f) : vec3(1.f, 0.1f, 0.05f);
            const vec3 c = glm::mix(vec3(1.f), end, std::fabs(t));
            o[0] = c.x, o[1] = c.y, o[2] = c.z;
        }
    return out;
}

Image error_figure(const Image& error, const Frame& truth) {
    const float scale = error_scale(error, truth);
    const Image colours = error_colors(error, truth, scale);
    const int text = text_height(1), strip = 3 * text + 16;
    Image out(error.width, error.height + strip, 3);
    for (int y = 0; y < error.height; ++y)
        for (int x = 0; x < error.width; ++x)
            for (int c = 0; c < 3; ++c) out.at(x, y)[c] = colours.at(x, y)[c];
    for (int y = error.height; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) out.at(x, y)[0] = 0.005f, out.at(x, y)[1] = 0.0055f, out.at(x, y)[2] = 0.0065f;
    // The ramp, as error_colors draws it, across the middle of the strip's width.
    const int w = std::max(16, std::min(out.width - 16, 200)), x0 = (out.width - w) / 2, y0 = error.height + text + 8, h = std::max(4, text / 2);
    for (int x = 0; x < w; ++x) {
        const float t = 2.f * (float(x) + 0.5f) / float(w) - 1.f;
        const vec3 end = t < 0.f ? vec3(0.05f, 0.25f, 1.f) : vec3(1.f, 0.1f, 0.05f);
        const vec3 c = glm::mix(vec3(1.f), end, std::fabs(t));
        for (int y = y0; y < y0 + h; ++y)
            for (int k = 0; k < 3; ++k) out.at(x0 + x, y)[k] = c[k];
    }
    const float grey = 0.6f;
    // The longest caption that fits the width.
    std::string caption;
    for (const char* c : {"real-time - truth (radiance, mean of RGB)", "real-time - truth", "rt - truth"}) {
        caption = c;
        if (text_width(caption) <= out.width - 4) break;
    }
    draw_text(out, std::max(2, (out.width - text_width(caption)) / 2), error.height + 4, caption, grey, grey, grey);
    char lo[32], hi[32];
    std::snprintf(lo, sizeof lo, "%+.3g", -double(scale));
    std::snprintf(hi, sizeof hi, "%+.3g", double(scale));
    draw_text(out, x0, y0 + h + 3, lo, grey, grey, grey);
    draw_text(out, x0 + w / 2 - text_width("0") / 2, y0 + h + 3, "0", grey, grey, grey);
    draw_text(out, x0 + w - text_width(hi), y0 + h + 3, hi, grey, grey, grey);
    return out;
}

float error_scale(const Image& error, const Frame& truth) {
    std::vector<float> v;
    for (int y = 0; y < error.height; ++y)
        for (int x = 0; x < error.width; ++x)
            if (object_pixel(truth, x, y)) v.push_back(mean_abs(error.at(x, y)));
    if (v.empty()) return 1.f;
    const size_t k = std::min(v.size() - 1, size_t(0.99 * double(v.size())));
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
    const double p = std::max(1e-6, double(v[k]));
    const double decade = std::pow(10.0, std::floor(std::log10(p)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * decade >= p) return float(m * decade);
    return float(10.0 * decade);
}
}  // namespace mesolab::gui
