#pragma once
// [SECTION] The stage graph.
// Computation is a graph of named stages ("scene.geometry", "env.irradiance", "basic.albedo",
// "microgeom.visibility"...). Each stage declares the parameters it reads (public keys,
// or "group.*"), the upstream stages whose results it reads, and the effects that need it.
//  - A stage runs only if it is upstream of what a frame needs and, when it lists effects, one
//    of them is enabled in the scene; otherwise it is reported as skipped.
//  - Its result is cached under a hash of its declared parameter values and its inputs' keys,
//    so a change recomputes exactly the stages that depend on it (moving the light recomputes
//    nothing). A few results per stage are kept, so toggling a value back is a cache hit.
//  - Stages may run off the UI thread; they report progress and can be cancelled.
#include "core/scene.h"
#include <any>
#include <atomic>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace mesolab {

// A figure from one of the papers, shown beside ours in the Timings panel (StageDecl::paper) and
// the bench tables (BenchRow::paper_ms). A technique writes each figure once (e.g.
// core/microgeom/paper.h) and both read it.
struct PaperFigure {
    double ms = 0;
    std::string source;  // e.g. "Heidrich 2000, Table 1, Bricks 128x128 (SGI Octane)"
};

class StageContext;

struct StageDecl {
    std::string name;
    std::string help;
    std::vector<std::string> params;   // public keys or "group.*"
    std::vector<std::string> inputs;   // upstream stage names
    std::vector<std::string> effects;  // empty: needed whenever downstream needs it
    // Also needed only when this holds (e.g. microgeom.shadows == ellipse); `when_text` says so.
    std::function<bool(const Scene&)> when;
    std::string when_text;
    std::optional<PaperFigure> paper;
    // Returns the result as std::shared_ptr<const T> wrapped in std::any (or an empty any).
    std::function<std::any(StageContext&)> run;
};

enum class StageStatus { Ran, Cached, Skipped, Failed, Cancelled };
const char* to_string(StageStatus s);

struct StageRun {
    std::string name;
    StageStatus status = StageStatus::Skipped;
    double ms = 0;         // time to compute (Ran) or look up (Cached)
    uint64_t key = 0;
    std::string reason;    // why skipped ("effects.environment is off") or the error
    std::vector<std::string> warnings;  // results that are valid but need the user's attention (kept with the cached result)
};

using ProgressFn = std::function<void(const std::string& stage, double fraction)>;

// Results of one evaluation.
struct Evaluation {
    std::map<std::string, std::any> results;
    std::vector<StageRun> runs;  // in execution order, skipped stages included

    template <class T>
    std::shared_ptr<const T> get(const std::string& stage) const {
        auto it = results.find(stage);
        if (it == results.end() || !it->second.has_value()) return nullptr;
        return std::any_cast<std::shared_ptr<const T>>(it->second);
    }
    const StageRun* run(const std::string& stage) const;
};

class StageContext {
public:
    StageContext(const Scene& s, const Evaluation& e, std::string name, const ProgressFn& p, const std::atomic<bool>* cancel)
        : scene(s), eval_(e), name_(std::move(name)), progress_(p), cancel_(cancel) {}
    const Scene& scene;
    template <class T>
    std::shared_ptr<const T> input(const std::string& stage) const { return eval_.get<T>(stage); }
    // Report progress in [0,1]; throws Cancelled when cancellation was requested.
    void progress(double fraction) const;
    bool cancelled() const { return cancel_ && cancel_->load(std::memory_order_relaxed); }
    // A warning shown with the stage (capture prints it, the sidecar and the GUI list it).
    void warn(std::string message) { warnings.push_back(std::move(message)); }
    std::vector<std::string> warnings;
    const std::string& name() const { return name_; }

private:
    const Evaluation& eval_;
    std::string name_;
    const ProgressFn& progress_;
    const std::atomic<bool>* cancel_;
};

template <class T>
std::any stage_result(T value) { return std::any(std::shared_ptr<const T>(std::make_shared<T>(std::move(value)))); }

class StageGraph {
public:
    // Registers a stage; throws std::logic_error on a duplicate name or an unknown input.
    void add(StageDecl d);
    const StageDecl* find(const std::string& name) const;
    const std::vector<StageDecl>& stages() const { return stages_; }

    // Evaluate `targets` and what they need. Stage errors propagate (InputError for bad input
    // files, Cancelled on cancellation) after being recorded in the profiler.
    Evaluation evaluate(const Scene& scene, const std::vector<std::string>& targets,
                        const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr);
    // Cache key of a stage for a scene (0 if the stage would be skipped).
    uint64_t key(const Scene& scene, const std::string& stage) const;
    // Whether a stage is needed by an enabled effect (or has none listed).
    bool enabled(const Scene& scene, const StageDecl& d, std::string* reason = nullptr) const;

    void clear_cache();
    // Drop the cached results of one stage (bench: time it from a cold cache).
    void invalidate(const std::string& stage);
    size_t cache_entries() const;
    size_t cache_capacity_per_stage = 4;

private:
    uint64_t key_rec(const Scene& scene, const StageDecl& d, std::map<std::string, uint64_t>& memo) const;
    std::vector<StageDecl> stages_;
    mutable std::mutex mutex_;
    struct Entry {
        uint64_t key = 0;
        std::any result;
        std::vector<std::string> warnings;
    };
    std::map<std::string, std::list<Entry>> cache_;  // most recent first
};

// Hash of the values behind a parameter pattern ("basic.kd", "geometry.*", "light.*") over
// every table of the scene it refers to.
std::string param_fingerprint(const Scene& scene, const std::string& pattern);
}  // namespace mesolab
