#pragma once
// [SECTION] Scoped profiling (after Falcor's PROFILE_SCOPE).
// CPU scopes nest per thread into a path ("frame/raster"); GPU passes record their
// GL_TIME_ELAPSED results under the same kind of path with device = Gpu. Each path keeps a
// history of its last samples, from which the Timings panel and the capture sidecar show
// last / median / min / max.
// Each session (core/session.h) owns a Profiler and binds it to the thread that evaluates or
// renders for it (ProfilerBinding), so two sessions in one process never mix their timings.
// Scopes opened on a thread with no binding record into Profiler::fallback().
#include <chrono>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace mesolab {

enum class Device { Cpu, Gpu };

struct TimingStat {
    std::string path;
    Device device = Device::Cpu;
    double last = 0, median = 0, min = 0, max = 0;  // milliseconds
    size_t count = 0;
};

class Profiler {
public:
    // The profiler bound to this thread (ProfilerBinding), else fallback().
    static Profiler& current();
    // Where timings go on threads that no session has bound (tools, tests, worker threads).
    static Profiler& fallback();
    void record(const std::string& path, double ms, Device device = Device::Cpu);
    std::vector<TimingStat> stats() const;  // sorted by path
    bool find(const std::string& path, TimingStat& out) const;
    void clear();
    size_t history = 64;

private:
    struct Entry {
        Device device = Device::Cpu;
        std::deque<double> samples;
    };
    mutable std::mutex mutex_;
    std::map<std::string, Entry> entries_;
};

// Binds a profiler to the calling thread for the binding's lifetime (nests; restores the previous).
class ProfilerBinding {
public:
    explicit ProfilerBinding(Profiler& p);
    ~ProfilerBinding();
    ProfilerBinding(const ProfilerBinding&) = delete;
    ProfilerBinding& operator=(const ProfilerBinding&) = delete;

private:
    Profiler* previous_;
};

// Median of a set of samples (mean of the middle two for an even count).
double median_of(std::vector<double> v);

class ProfileScope {
public:
    explicit ProfileScope(std::string name);
    ~ProfileScope();
    ProfileScope(const ProfileScope&) = delete;
    ProfileScope& operator=(const ProfileScope&) = delete;
    // Path of the innermost open scope on this thread ("" if none).
    static std::string current_path();

private:
    std::string path_;
    Profiler* profiler_;
    std::chrono::steady_clock::time_point t0_;
};

#define MESOLAB_CONCAT2(a, b) a##b
#define MESOLAB_CONCAT(a, b) MESOLAB_CONCAT2(a, b)
#define PROFILE_SCOPE(name) ::mesolab::ProfileScope MESOLAB_CONCAT(profile_scope_, __LINE__)(name)
}  // namespace mesolab
