#include "core/profile.h"

#include <algorithm>

namespace mesolab {
namespace {
thread_local std::vector<std::string> t_stack;
thread_local Profiler* t_bound = nullptr;
}  // namespace

double median_of(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// [SECTION] Profiler
Profiler& Profiler::fallback() {
    static Profiler p;
    return p;
}

Profiler& Profiler::current() { return t_bound ? *t_bound : fallback(); }

ProfilerBinding::ProfilerBinding(Profiler& p) : previous_(t_bound) { t_bound = &p; }
ProfilerBinding::~ProfilerBinding() { t_bound = previous_; }

void Profiler::record(const std::string& path, double ms, Device device) {
    std::lock_guard lock(mutex_);
    Entry& e = entries_[path];
    e.device = device;
    e.samples.push_back(ms);
    while (e.samples.size() > history) e.samples.pop_front();
}

std::vector<TimingStat> Profiler::stats() const {
    std::lock_guard lock(mutex_);
    std::vector<TimingStat> r;
    for (const auto& [path, e] : entries_) {
        if (e.samples.empty()) continue;
        TimingStat s{path, e.device};
        s.last = e.samples.back();
        s.min = *std::min_element(e.samples.begin(), e.samples.end());
        s.max = *std::max_element(e.samples.begin(), e.samples.end());
        s.median = median_of({e.samples.begin(), e.samples.end()});
        s.count = e.samples.size();
        r.push_back(std::move(s));
    }
    return r;
}

bool Profiler::find(const std::string& path, TimingStat& out) const {
    for (auto& s : stats())
        if (s.path == path) {
            out = s;
            return true;
        }
    return false;
}

void Profiler::clear() {
    std::lock_guard lock(mutex_);
    entries_.clear();
}

// [SECTION] Scopes
ProfileScope::ProfileScope(std::string name) : profiler_(&Profiler::current()), t0_(std::chrono::steady_clock::now()) {
    path_ = t_stack.empty() ? std::move(name) : t_stack.back() + "/" + name;
    t_stack.push_back(path_);
}

ProfileScope::~ProfileScope() {
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
    t_stack.pop_back();
    profiler_->record(path_, ms, Device::Cpu);
}

std::string ProfileScope::current_path() { return t_stack.empty() ? std::string() : t_stack.back(); }
}  // namespace mesolab
