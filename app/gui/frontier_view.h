#pragma once
// [SECTION] The window's Frontier view
//  - FrontierRunner: one worker thread that measures the accuracy-time frontier of a scene
//    (frontier_scene, app/api.h: the same code as `mesolab frontier`) in its own workbench, and
//    hands out the points as they are measured, the frontier marked among them. Starting again
//    cancels the run under way; cancel keeps the points measured so far.
// Nothing here needs a window (no GLFW, ImGui or GL), so tests drive it directly; the window's
// plot and its clicks are in app/gui/frontier_panel.cpp.
#include "app/api.h"
#include "core/scene.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

namespace mesolab::gui {

class FrontierRunner {
public:
    struct Status {
        bool running = false;
        double fraction = 0;       // of the settings of the run under way
        std::string stage;         // what it measures now
        std::string error;         // the last run failed (an InputError's message)
        bool cancelled = false;
        bool budget_reached = false;
        double truth_noise = 0;    // of the truth of the last run (its first distance)
        std::string scene;         // the scene measured
    };

    FrontierRunner();
    ~FrontierRunner();  // cancels and joins
    FrontierRunner(const FrontierRunner&) = delete;
    FrontierRunner& operator=(const FrontierRunner&) = delete;

    // Measures the frontier of `s` with `o` (its progress, on_point and cancel are the runner's);
    // a run under way is cancelled first. Its points replace the last run's.
    void start(const Scene& s, const FrontierOptions& o);
    void cancel();
    Status status() const;
    // The points measured so far, the frontier marked among them.
    std::vector<FrontierPoint> points() const;
    // Blocks until no run is under way or `timeout` passed; true when idle.
    bool wait_idle(std::chrono::milliseconds timeout) const;

private:
    struct Job {
        Scene scene;
        FrontierOptions options;
    };
    void loop(std::stop_token st);

    mutable std::mutex mutex_;
    std::condition_variable_any cv_;
    mutable std::condition_variable idle_cv_;
    std::optional<Job> job_;
    std::vector<FrontierPoint> points_;
    Status status_;
    std::atomic<bool> cancel_{false};
    std::jthread thread_;
};

}  // namespace mesolab::gui
