#include "core/session.h"
#include "core/blob.h"
#include "core/error.h"
#include "core/read_contract.h"
#include "core/strings.h"
#include "core/technique.h"

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <fstream>
#include <set>

namespace mesolab {

// [SECTION] Memory sizes
uint64_t parse_memory_size(const std::string& text) {
    const auto bad = [&] {
        return InputError("--memory-limit: '" + text + "' is not a size (expected e.g. 512M, 4G, 1.5GiB or a number of bytes)");
    };
    size_t used = 0;
    double v = 0;
    try {
        v = std::stod(text, &used);
    } catch (const std::exception&) {
        throw bad();
    }
    std::string unit = text.substr(used);
    for (auto& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
    double scale = 1;
    if (unit.empty() || unit == "B") scale = 1;
    else if (unit == "K" || unit == "KB" || unit == "KIB") scale = 1024.0;
    else if (unit == "M" || unit == "MB" || unit == "MIB") scale = 1024.0 * 1024.0;
    else if (unit == "G" || unit == "GB" || unit == "GIB") scale = 1024.0 * 1024.0 * 1024.0;
    else if (unit == "T" || unit == "TB" || unit == "TIB") scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    else throw bad();
    if (!(v > 0) || !std::isfinite(v * scale) || v * scale > 1.8e19) throw bad();
    return uint64_t(v * scale);
}

uint64_t available_memory() {
    std::ifstream in("/proc/meminfo");
    std::string name;
    uint64_t kb = 0;
    std::string unit;
    while (in >> name >> kb >> unit)
        if (name == "MemAvailable:") return kb * 1024;
    return 0;
}

// [SECTION] Cache
uint64_t StageCache::key(std::string_view fingerprint) const { return hash_(fingerprint); }

const StageCache::Entry* StageCache::find(const std::string& stage, uint64_t key, const std::string& fingerprint) {
    std::lock_guard lock(mutex_);
    auto s = entries_.find(stage);
    if (s == entries_.end()) return nullptr;
    auto& list = s->second;
    for (auto it = list.begin(); it != list.end(); ++it)
        if (it->key == key && it->fingerprint == fingerprint) {  // the key alone could collide
            list.splice(list.begin(), list, it);                  // most recently used first
            return &list.front();
        }
    return nullptr;
}

void StageCache::put(const std::string& stage, Entry e, size_t capacity) {
    std::lock_guard lock(mutex_);
    auto& list = entries_[stage];
    list.push_front(std::move(e));
    while (list.size() > std::max<size_t>(capacity, 1)) list.pop_back();
}

void StageCache::clear() {
    std::lock_guard lock(mutex_);
    entries_.clear();
}

void StageCache::invalidate(const std::string& stage) {
    std::lock_guard lock(mutex_);
    entries_.erase(stage);
}

size_t StageCache::entries() const {
    std::lock_guard lock(mutex_);
    size_t n = 0;
    for (const auto& [k, v] : entries_) n += v.size();
    return n;
}

// [SECTION] The cache contract
namespace {
// A stage may read the keys it and the stages upstream declare (StageGraph::params_upstream).
DeclaredReads stage_reads(const StageGraph& g, const Scene& s, const StageDecl& d, int object) {
    return DeclaredReads("stage " + d.name, s, g.params_upstream(d), d.scope == StageScope::Object ? object : -1,
                         "neither it nor a stage upstream declares: its cached result would not follow that key (declare it in the stage's params)");
}
}  // namespace

bool Session::default_check_stage_reads() { return check_reads_by_default(); }

// [SECTION] Session
Session::Session() : Session(Registry::instance().stages()) {}
Session::Session(const StageGraph& graph, StageCache::HashFn hash) : graph_(graph), cache_(std::move(hash)) {}

void Session::check_memory(const std::string& what, const MemoryEstimate& e) const {
    const bool limited = memory_limit_ > 0;
    const double budget = limited ? double(memory_limit_) : double(available_memory());
    if (budget <= 0 || e.bytes <= budget) return;
    std::string lower;
    for (size_t i = 0; i < e.lower.size(); ++i) lower += (i ? (i + 1 == e.lower.size() ? " or " : ", ") : "") + e.lower[i];
    throw MemoryBudgetError(what + " would allocate about " + format_bytes(e.bytes) + (e.what.empty() ? "" : " (" + e.what + ")") + ", more than " +
                     (limited ? "the --memory-limit of " + format_bytes(budget) : "the " + format_bytes(budget) + " of memory available") +
                     (lower.empty() ? std::string() : "; lower " + lower));
}

Evaluation Session::evaluate_frame(const Scene& scene, const ProgressFn& progress, const std::atomic<bool>* cancel) {
    return evaluate(scene, Registry::instance().frame_stages(scene), progress, cancel);
}

StageKeys Session::frame_keys(const Scene& scene) const { return keys(scene, Registry::instance().frame_stages(scene)); }

uint64_t Session::key(const Scene& scene, const StageName& stage, int object) const {
    const std::string fp = graph_.fingerprint(scene, stage, object);
    return fp.empty() ? 0 : cache_.key(fp);
}

StageKeys Session::keys(const Scene& scene, const std::vector<StageName>& targets) const {
    StageKeys out;
    StageGraph::Memo memo;
    std::set<std::pair<std::string, int>> visited;
    std::function<void(const StageDecl&, int)> visit = [&](const StageDecl& d, int object) {
        if (!visited.insert({d.name, object}).second) return;
        if (!graph_.enabled(scene, d, object)) {
            if (graph_.covers(scene, d, object)) out.push_back({d.name, object, 0});
            return;
        }
        graph_.for_each_input(scene, d, object, visit);
        const std::string& fp = graph_.fingerprint(scene, d, object, memo);
        out.push_back({d.name, object, fp.empty() ? 0 : cache_.key(fp)});
    };
    for (const auto& t : targets) {
        const StageDecl& d = graph_.at(t);
        for (int o : graph_.subjects(scene, d)) visit(d, o);
    }
    return out;
}

Evaluation Session::evaluate(const Scene& scene, const std::vector<StageName>& targets, const ProgressFn& progress, const std::atomic<bool>* cancel) {
    ProfilerBinding bind(profiler_);
    Evaluation ev;
    StageGraph::Memo memo, memo_contents;
    std::set<std::pair<std::string, int>> visited;
    const size_t capacity = cache_capacity_per_stage + (scene.objects.size() > 1 ? scene.objects.size() - 1 : 0);

    const auto store = [&](const StageDecl& d, int object, std::any result) {
        Evaluation::Results& r = ev.results[d.name];
        if (object < 0) {
            r.scene = std::move(result);
        } else {
            if (r.objects.size() < scene.objects.size()) r.objects.resize(scene.objects.size());
            r.objects[size_t(object)] = std::move(result);
        }
    };

    std::function<void(const StageDecl&, int)> visit = [&](const StageDecl& d, int object) {
        if (!visited.insert({d.name, object}).second) return;
        StageRun run{d.name, object};
        std::string reason;
        if (!graph_.enabled(scene, d, object, &reason)) {
            if (!graph_.covers(scene, d, object)) return;  // another technique's object: nothing to report
            run.reason = reason;
            store(d, object, std::any());
            ev.runs.push_back(run);
            return;
        }
        graph_.for_each_input(scene, d, object, visit);
        const std::string& fp = graph_.fingerprint(scene, d, object, memo);
        run.key = cache_.key(fp);
        const auto t0 = std::chrono::steady_clock::now();
        auto ms_since = [&] { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(); };
        if (const StageCache::Entry* hit = cache_.find(d.name, run.key, fp)) {
            store(d, object, hit->result);
            run.warnings = hit->warnings;
            run.status = StageStatus::Cached;
            run.ms = ms_since();
            ev.runs.push_back(run);
            return;
        }
        // The disk store: the fingerprint with the files' contents (never their dates) is the key.
        const std::string* disk_fp = d.disk && store_ ? &graph_.fingerprint(scene, d, object, memo_contents, FileIdentity::Contents) : nullptr;
        if (disk_fp) {
            ProfileScope scope("stage/" + d.name + "/disk read");
            if (std::optional<StageStore::Entry> e = store_->load(d.name, *disk_fp)) {
                try {
                    BlobReader r(e->payload);
                    std::any result = d.disk->load(r);
                    if (!r.done()) throw BlobError("bytes left over");
                    run.status = StageStatus::Stored;
                    run.warnings = std::move(e->warnings);
                    run.ms = ms_since();
                    cache_.put(d.name, {run.key, fp, result, run.warnings}, capacity);
                    store(d, object, std::move(result));
                    ev.runs.push_back(run);
                    return;
                } catch (const BlobError&) {
                    // Not such a result (another layout of the type): computed again, and overwritten.
                }
            }
        }
        StageContext ctx(scene, ev, d.name, object, progress, cancel);
        if (progress) progress(d.name, 0.0);  // lets a UI name the stage that is running
        std::any result;
        try {
            if (cancel && cancel->load()) throw Cancelled();
            // The estimate and the work read keys under the same contract.
            std::optional<DeclaredReads> watch;
            if (check_stage_reads) watch.emplace(stage_reads(graph_, scene, d, object));
            ParamReadScope reads(watch ? &*watch : nullptr);
            if (d.memory) check_memory("stage " + run.label(scene), d.memory(ctx));
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
            ev.runs.push_back(run);
            const std::string msg = e.what();
            // Bad input stays exit status 2; a message that already names the stage keeps its words.
            if (msg.rfind("stage " + d.name, 0) == 0) throw;
            if (dynamic_cast<const MemoryBudgetError*>(&e)) throw MemoryBudgetError("stage " + run.label(scene) + ": " + msg);
            throw InputError("stage " + run.label(scene) + ": " + msg);
        } catch (const std::exception& e) {
            run.status = StageStatus::Failed;
            run.reason = e.what();
            ev.runs.push_back(run);
            throw std::runtime_error("stage " + run.label(scene) + ": " + e.what());
        }
        run.status = StageStatus::Ran;
        run.ms = ms_since();
        run.warnings = ctx.warnings;
        if (progress) progress(d.name, 1.0);
        // Kept on disk, but a result the CPU computed because the GPU could not: an entry of a stage
        // asked to run on the GPU holds the GPU's result.
        if (disk_fp && result.has_value() && !ctx.fell_back()) {
            ProfileScope scope("stage/" + d.name + "/disk write");
            BlobWriter w;
            d.disk->save(result, w);
            store_->save(d.name, *disk_fp, {w.take(), run.warnings});
        }
        cache_.put(d.name, {run.key, fp, result, run.warnings}, capacity);
        store(d, object, std::move(result));
        ev.runs.push_back(run);
    };

    for (const auto& t : targets) {
        const StageDecl& d = graph_.at(t);
        for (int o : graph_.subjects(scene, d)) visit(d, o);
    }
    return ev;
}
}  // namespace mesolab
