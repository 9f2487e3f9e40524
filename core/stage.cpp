#include "core/stage.h"
#include "core/error.h"
#include "core/profile.h"

#include <chrono>
#include <set>

namespace mesolab {
namespace {

uint64_t fnv1a(std::string_view s, uint64_t h = 1469598103934665603ull) {
    for (unsigned char c : s) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}

void append_table(std::string& out, const Scene& s, const ParamTable& t, const std::string& param) {
    for (const auto& d : t.group().decls()) {
        if (param != "*" && d.name != param) continue;
        out += value_canonical(d, t.get(d.name), s.base_dir);
        out += ';';
    }
}
}  // namespace

const char* to_string(StageStatus s) {
    switch (s) {
        case StageStatus::Ran: return "ran";
        case StageStatus::Cached: return "cached";
        case StageStatus::Skipped: return "skipped";
        case StageStatus::Failed: return "failed";
        case StageStatus::Cancelled: return "cancelled";
    }
    return "?";
}

const StageRun* Evaluation::run(const std::string& stage) const {
    for (const auto& r : runs)
        if (r.name == stage) return &r;
    return nullptr;
}

void StageContext::progress(double fraction) const {
    if (cancelled()) throw Cancelled();
    if (progress_) progress_(name_, fraction);
}

// [SECTION] Fingerprints of parameter values
std::string param_fingerprint(const Scene& s, const std::string& pattern) {
    const auto dot = pattern.find('.');
    const std::string group = pattern.substr(0, dot), param = dot == std::string::npos ? "*" : pattern.substr(dot + 1);
    std::string out = pattern + "{";
    if (group == "camera") append_table(out, s, s.camera, param);
    else if (group == "env") append_table(out, s, s.env, param);
    else if (group == "effects") append_table(out, s, s.effects, param);
    else if (group == "light") {
        out.append(std::to_string(s.lights.size())).append(":");
        for (const auto& l : s.lights) append_table(out, s, l, param);
    } else if (group == "geometry") {
        out.append(std::to_string(s.objects.size())).append(":");
        for (const auto& o : s.objects) append_table(out, s, o.geometry, param);
    } else {
        // A technique: every object using it, in order (the object index is part of the key).
        for (size_t i = 0; i < s.objects.size(); ++i)
            if (s.objects[i].technique == group) {
                out.append("#").append(std::to_string(i)).append(":");
                append_table(out, s, s.objects[i].material, param);
            }
    }
    return out + "}";
}

// [SECTION] Graph
void StageGraph::add(StageDecl d) {
    if (find(d.name)) throw std::logic_error("stage declared twice: " + d.name);
    for (const auto& in : d.inputs)
        if (!find(in)) throw std::logic_error("stage " + d.name + " reads unknown stage " + in + " (declare upstream stages first)");
    stages_.push_back(std::move(d));
}

const StageDecl* StageGraph::find(const std::string& name) const {
    for (const auto& s : stages_)
        if (s.name == name) return &s;
    return nullptr;
}

bool StageGraph::enabled(const Scene& scene, const StageDecl& d, std::string* reason) const {
    if (d.when && !d.when(scene)) {
        if (reason) *reason = "not needed unless " + d.when_text;
        return false;
    }
    if (d.effects.empty()) return true;
    for (const auto& e : d.effects)
        if (scene.effects.group().find(e) && scene.effect(e)) return true;
    if (reason) {
        *reason = "no enabled effect needs it (";
        for (size_t i = 0; i < d.effects.size(); ++i) *reason += (i ? ", effects." : "effects.") + d.effects[i];
        *reason += d.effects.size() == 1 ? " is off)" : " are off)";
    }
    return false;
}

uint64_t StageGraph::key_rec(const Scene& scene, const StageDecl& d, std::map<std::string, uint64_t>& memo) const {
    if (auto it = memo.find(d.name); it != memo.end()) return it->second;
    uint64_t h = 0;
    if (enabled(scene, d)) {
        h = fnv1a(d.name);
        for (const auto& p : d.params) h = fnv1a(param_fingerprint(scene, p), h);
        for (const auto& in : d.inputs) {
            const uint64_t k = key_rec(scene, *find(in), memo);
            h = fnv1a(std::string_view(reinterpret_cast<const char*>(&k), sizeof k), h);
        }
        if (h == 0) h = 1;
    }
    memo[d.name] = h;
    return h;
}

uint64_t StageGraph::key(const Scene& scene, const std::string& stage) const {
    const StageDecl* d = find(stage);
    if (!d) throw std::logic_error("unknown stage " + stage);
    std::map<std::string, uint64_t> memo;
    return key_rec(scene, *d, memo);
}

Evaluation StageGraph::evaluate(const Scene& scene, const std::vector<std::string>& targets, const ProgressFn& progress,
                                const std::atomic<bool>* cancel) {
    Evaluation ev;
    std::map<std::string, uint64_t> memo;
    std::set<std::string> visited;

    std::function<void(const StageDecl&)> visit = [&](const StageDecl& d) {
        if (!visited.insert(d.name).second) return;
        StageRun run{d.name};
        std::string reason;
        if (!enabled(scene, d, &reason)) {
            run.reason = reason;
            ev.results[d.name] = std::any();
            ev.runs.push_back(run);
            return;
        }
        for (const auto& in : d.inputs) visit(*find(in));
        run.key = key_rec(scene, d, memo);
        const auto t0 = std::chrono::steady_clock::now();
        auto ms_since = [&] { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(); };
        {
            std::lock_guard lock(mutex_);
            auto& entries = cache_[d.name];
            for (auto it = entries.begin(); it != entries.end(); ++it)
                if (it->key == run.key) {
                    entries.splice(entries.begin(), entries, it);  // most recently used first
                    ev.results[d.name] = entries.front().result;
                    run.warnings = entries.front().warnings;
                    run.status = StageStatus::Cached;
                    run.ms = ms_since();
                    ev.runs.push_back(run);
                    return;
                }
        }
        StageContext ctx(scene, ev, d.name, progress, cancel);
        if (progress) progress(d.name, 0.0);  // lets a UI name the stage that is running
        std::any result;
        try {
            if (cancel && cancel->load()) throw Cancelled();
            ProfileScope scope("stage/" + d.name);
            result = d.run(ctx);
        } catch (const Cancelled&) {
            run.status = StageStatus::Cancelled;
            run.ms = ms_since();
            ev.runs.push_back(run);
            throw;
        } catch (const InputError& e) {
            run.status = StageStatus::Failed;
            run.reason = e.what();
            throw InputError("stage " + d.name + ": " + e.what());  // bad input stays exit status 2
        } catch (const std::exception& e) {
            run.status = StageStatus::Failed;
            run.reason = e.what();
            throw std::runtime_error("stage " + d.name + ": " + e.what());
        }
        run.status = StageStatus::Ran;
        run.ms = ms_since();
        run.warnings = ctx.warnings;
        if (progress) progress(d.name, 1.0);
        {
            std::lock_guard lock(mutex_);
            auto& entries = cache_[d.name];
            entries.push_front({run.key, result, run.warnings});
            while (entries.size() > cache_capacity_per_stage) entries.pop_back();
        }
        ev.results[d.name] = std::move(result);
        ev.runs.push_back(run);
    };

    for (const auto& t : targets) {
        const StageDecl* d = find(t);
        if (!d) throw std::logic_error("unknown stage " + t);
        visit(*d);
    }
    return ev;
}

void StageGraph::clear_cache() {
    std::lock_guard lock(mutex_);
    cache_.clear();
}

void StageGraph::invalidate(const std::string& stage) {
    std::lock_guard lock(mutex_);
    cache_.erase(stage);
}

size_t StageGraph::cache_entries() const {
    std::lock_guard lock(mutex_);
    size_t n = 0;
    for (const auto& [k, v] : cache_) n += v.size();
    return n;
}
}  // namespace mesolab
