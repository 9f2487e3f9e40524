#include "app/gui/frontier_view.h"
#include "core/error.h"

namespace mesolab::gui {

FrontierRunner::FrontierRunner() : thread_([this](std::stop_token st) { loop(st); }) {}

FrontierRunner::~FrontierRunner() {
    cancel_ = true;
    thread_.request_stop();
    cv_.notify_all();
}

void FrontierRunner::start(const Scene& s, const FrontierOptions& o) {
    std::lock_guard<std::mutex> lock(mutex_);
    cancel_ = true;  // the run under way, if any, stops at its next check
    job_ = Job{s, o};
    points_.clear();  // the new run's points replace the last's
    status_.running = true;  // queued
    status_.error.clear();
    status_.cancelled = false;
    status_.fraction = 0;
    status_.stage = "starting";
    cv_.notify_all();
}

void FrontierRunner::cancel() {
    std::lock_guard<std::mutex> lock(mutex_);
    cancel_ = true;
    if (job_) {
        job_.reset();  // a queued run does not start
        status_.running = false;
        status_.cancelled = true;
        idle_cv_.notify_all();
    }
}

FrontierRunner::Status FrontierRunner::status() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return status_;
}

std::vector<FrontierPoint> FrontierRunner::points() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return points_;
}

bool FrontierRunner::wait_idle(std::chrono::milliseconds timeout) const {
    std::unique_lock<std::mutex> lock(mutex_);
    return idle_cv_.wait_for(lock, timeout, [&] { return !status_.running; });
}

void FrontierRunner::loop(std::stop_token st) {
    for (;;) {
        Job job;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            cv_.wait(lock, st, [&] { return job_.has_value(); });
            if (st.stop_requested()) return;
            job = std::move(*job_);
            job_.reset();
            cancel_ = false;
            points_.clear();
            status_.running = true;
            status_.scene = job.scene.name;
            status_.budget_reached = false;
        }
        FrontierOptions o = job.options;
        o.quiet = true;
        o.cancel = &cancel_;
        o.progress = [&](const std::string& stage, double f) {
            std::lock_guard<std::mutex> lock(mutex_);
            status_.stage = stage, status_.fraction = f;
        };
        o.on_point = [&](const FrontierPoint& p) {
            std::lock_guard<std::mutex> lock(mutex_);
            points_.push_back(p);
            mark_frontier(points_);
        };
        try {
            const FrontierResult r = frontier_scene(job.scene, o, false);
            std::lock_guard<std::mutex> lock(mutex_);
            points_ = r.points;
            status_.budget_reached = r.budget_reached;
            status_.truth_noise = r.truth_noise.empty() ? 0.0 : r.truth_noise.front();
            status_.fraction = 1;
            status_.stage = "done";
        } catch (const Cancelled&) {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!job_) status_.cancelled = true;  // not replaced by a newer run
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(mutex_);
            status_.error = e.what();
        }
        std::lock_guard<std::mutex> lock(mutex_);
        if (!job_) {
            status_.running = false;
            idle_cv_.notify_all();
        }
    }
}

}  // namespace mesolab::gui
