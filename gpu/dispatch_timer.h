#pragma once
// GPU time of a precomputation's dispatches, per dispatch: one GpuTimeline range each (timer
// queries on a hardware GPU, read without waiting; the wall time between glFinish calls on a
// software renderer, whose compute dispatches run on the CPU at once). Each answer is recorded in
// the profiler under "<the scope open when the timer was made>/<name>/gpu", so that
// `capture --profile` and `bench --profile` list a stage's GPU time beside its CPU scopes
// (uploads, read-backs, the host's preparation). finish() (or the destructor) takes the answers;
// call it once the stage has read its results back, when they are in anyway.
#include "core/profile.h"
#include "gpu/gl.h"

#include <string>

namespace mesolab::gpu {

class DispatchTimer {
public:
    explicit DispatchTimer(const std::string& name);
    ~DispatchTimer();
    DispatchTimer(const DispatchTimer&) = delete;
    DispatchTimer& operator=(const DispatchTimer&) = delete;
    void begin() { timeline_.begin(); }
    void end();
    void finish() { timeline_.wait(); }

private:
    GpuTimeline timeline_;
    std::string path_;
    Profiler* profiler_;
};
}  // namespace mesolab::gpu
