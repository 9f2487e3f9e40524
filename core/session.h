#pragma once
// [SECTION] Evaluation sessions.
// The registry (core/technique.h) holds only immutable declarations. Everything that changes
// while mesolab runs belongs to a Session: the stage cache, the timing history (its Profiler)
// and the memory budget. The app's Workbench (headless) and the window each own one, together
// with their GPU resources (gpu/renderer.h). Two sessions in one process share nothing and may
// evaluate on two threads at once.
//
// The cache keeps a few results per stage (most recently used first), each under its 64-bit key
// *and* the full fingerprint it was computed from (StageGraph::fingerprint): a look-up compares
// both, so a hash collision can never hand back another input's result.
//
// Memory: before a stage runs, its declared estimate (StageDecl::memory) is compared with the
// budget, the available memory of the machine (MemAvailable) or the limit set with
// set_memory_limit (`--memory-limit`). Above it the stage does not start: an InputError names
// the stage, the figure and the parameters to lower.
#include "core/profile.h"
#include "core/stage.h"
#include "core/stage_store.h"
#include <atomic>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mesolab {

class StageCache {
public:
    using HashFn = std::function<uint64_t(std::string_view fingerprint)>;
    explicit StageCache(HashFn hash = &StageGraph::hash) : hash_(std::move(hash)) {}

    struct Entry {
        uint64_t key = 0;
        std::string fingerprint;
        std::any result;
        std::vector<std::string> warnings;
    };
    uint64_t key(std::string_view fingerprint) const;
    // The entry of `stage` with this fingerprint (moved to the front), or null.
    const Entry* find(const std::string& stage, uint64_t key, const std::string& fingerprint);
    // Keeps at most `capacity` entries of the stage, most recent first.
    void put(const std::string& stage, Entry e, size_t capacity);
    void clear();
    // Drop the cached results of one stage (bench: time it from a cold cache).
    void invalidate(const std::string& stage);
    size_t entries() const;

private:
    HashFn hash_;
    mutable std::mutex mutex_;
    std::map<std::string, std::list<Entry>> entries_;
};

// Stage keys of a scene: (stage, object, key), in the order evaluate() visits them.
struct StageKey {
    std::string stage;
    int object = -1;
    uint64_t key = 0;
    bool operator==(const StageKey&) const = default;
};
using StageKeys = std::vector<StageKey>;

// Parse "512M", "4G", "1.5GiB", "800MB", "123456" (bytes) for --memory-limit; InputError otherwise.
uint64_t parse_memory_size(const std::string& text);
// The machine's available memory (MemAvailable of /proc/meminfo), 0 when unknown.
uint64_t available_memory();

class Session {
public:
    // A session over the registry's stages, or over a graph of one's own (tests).
    Session();
    explicit Session(const StageGraph& graph, StageCache::HashFn hash = &StageGraph::hash);
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

    const StageGraph& graph() const { return graph_; }

    // Evaluate `targets` and what they need. Stage errors propagate (InputError for bad input
    // files or a stage above the memory budget, Cancelled on cancellation).
    Evaluation evaluate(const Scene& scene, const std::vector<StageName>& targets, const ProgressFn& progress = {},
                        const std::atomic<bool>* cancel = nullptr);
    // The stages a frame of the scene needs (Registry::frame_stages).
    Evaluation evaluate_frame(const Scene& scene, const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr);

    // Keys of `targets` and everything upstream (skipped stages have key 0); frame_keys: of a frame.
    StageKeys keys(const Scene& scene, const std::vector<StageName>& targets) const;
    StageKeys frame_keys(const Scene& scene) const;
    uint64_t key(const Scene& scene, const StageName& stage, int object = -1) const;

    StageCache& cache() { return cache_; }
    size_t cache_capacity_per_stage = 4;  // plus one per further object of the scene

    // Timings of this session's work (stages, frames, GUI), bound to the evaluating thread.
    Profiler& profiler() { return profiler_; }

    // The cache contract, checked: while on, a stage's run() may read only the parameters it or a
    // stage upstream of it declares (StageDecl::params: those are in its cache key; an object
    // stage: only its own object's material and geometry),
    // and a read of any other key is a std::logic_error naming the stage and the key, instead of a
    // cached result that would silently go stale when that key changes. Reads are watched on the
    // thread that runs the stage (core/param.h, ParamReadWatch). Off by default; on where the
    // environment has MESOLAB_CHECK_STAGE_READS=1 (every test run sets it).
    bool check_stage_reads = default_check_stage_reads();
    static bool default_check_stage_reads();

    // The disk store of expensive stages (core/stage_store.h): null (the default) keeps results in
    // memory only. capture, the window and Python use the environment's store (--no-cache: none);
    // bench and sweep, which time the stages, never do.
    void set_store(std::shared_ptr<const StageStore> store) { store_ = std::move(store); }
    const StageStore* store() const { return store_.get(); }

    // Memory budget for one stage's allocation: 0 = the machine's available memory.
    void set_memory_limit(uint64_t bytes) { memory_limit_ = bytes; }
    uint64_t memory_limit() const { return memory_limit_; }
    // Throws InputError when `e` is above the budget: "<what> would allocate about ...; lower ...".
    void check_memory(const std::string& what, const MemoryEstimate& e) const;

private:
    const StageGraph& graph_;
    StageCache cache_;
    std::shared_ptr<const StageStore> store_;
    Profiler profiler_;
    uint64_t memory_limit_ = 0;
};
}  // namespace mesolab
