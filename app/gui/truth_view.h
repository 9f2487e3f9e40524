#pragma once
// [SECTION] The window's Truth view
//  - TruthRunner: one worker thread that asks the truth renderer (core/renderer.h, the same one
//    `capture --backend truth` and Python use, with its disk cache) for the truth of the scene on
//    screen progressively (RenderRequest::on_pass: passes of 1, 2, 4, ... samples per pixel up to
//    the target, each continuing the last) and publishes a frame after every pass. A scene whose
//    truth reads other values (truth_description), another size or seed starts over; a higher
//    target continues. Cancel stops the pass under way and keeps the last finished one. It has its
//    own Session, so the window's stage cache is not touched.
// The error's colours and figure (error_colors, error_figure) are app/truth_figures.h's.
// Nothing here needs a window (no GLFW, ImGui or GL), so tests drive it directly.
#include "core/image.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/truth/truth.h"

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>

namespace mesolab::gui {

class TruthRunner {
public:
    struct Status {
        bool running = false;   // a pass is under way or queued
        int spp = 0;            // samples of the frame published last
        int target = 0;
        double noise_rel = 0;   // of the frame published last
        double fraction = 0;    // of the pass under way
        bool cancelled = false; // stopped by cancel(): the frame has fewer samples than the target
        std::string error;      // the last job failed (an InputError's message: a technique without a truth, ...)
    };

    TruthRunner();
    ~TruthRunner();  // cancels and joins
    TruthRunner(const TruthRunner&) = delete;
    TruthRunner& operator=(const TruthRunner&) = delete;

    // The truth wanted: `s` at width x height with `settings` (spp is the target). Continues the
    // current truth when only the target grew; otherwise starts over (the old frame stays until
    // the first pass of the new one). The same request again does nothing, also after a cancel.
    void want(const Scene& s, int width, int height, const TruthSettings& settings);
    // Stops the pass under way; the last finished pass stays.
    void cancel();
    // The newest frame published since the last call (radiance, normal, truth_stderr, exitance) and the
    // key of the request it answers (key_of).
    struct Published {
        Frame frame;
        std::string key;
    };
    std::optional<Published> take_frame();
    // What identifies a truth: what it reads (truth_description), its size and seed. InputError
    // as truth_description.
    static std::string key_of(const Scene& s, int width, int height, uint64_t seed);
    Status status() const;
    // Blocks until no pass is under way or `timeout` passed; true when idle.
    bool wait_idle(std::chrono::milliseconds timeout) const;

private:
    struct Job {
        Scene scene;
        std::string description;
        int width = 0, height = 0;
        TruthSettings settings;
    };
    void loop(std::stop_token st);

    mutable std::mutex mutex_;
    std::condition_variable_any cv_;
    mutable std::condition_variable idle_cv_;
    std::optional<Job> wanted_;      // the latest request
    std::optional<Job> have_;        // what the frame published last is of (description, size, seed)
    int have_spp_ = 0;               // and its samples
    bool work_ = false;              // wanted_ is more than have_ holds and was not cancelled
    Status status_;
    std::optional<Published> published_;
    std::atomic<bool> cancel_{false};
    std::jthread thread_;
};

}  // namespace mesolab::gui
