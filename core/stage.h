#pragma once
// [SECTION] The stage graph: declarations.
// Computation is a graph of named stages ("scene.geometry", "env.irradiance", "basic.albedo",
// "microgeom.visibility"...). Each stage declares the parameters it reads (public keys, or
// "group.*"), the upstream stages whose results it reads, and the effects that need it.
//  - A stage runs only if it is upstream of what a frame needs and, when it lists effects, one
//    of them is enabled in the scene; otherwise it is reported as skipped.
//  - A scene stage computes one result for the scene. An object stage computes one result per
//    scene object it applies to (the objects using its technique, or every object), and its key
//    hashes that object's geometry and material parameters only, plus the scene-level keys it
//    declares (light.*, env.*, ...): changing object 2 never recomputes object 1's results, and
//    objects with equal settings share one result.
//  - Results are cached under the fingerprint of their declared parameter values and their
//    inputs' fingerprints, so a change recomputes exactly the stages that depend on it (moving
//    the light recomputes nothing that does not read light.*).
// This file holds the immutable declarations; the cache, the evaluation and its history belong
// to a session (core/session.h), so two sessions in one process share nothing.
#include "core/scene.h"
#include <any>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace mesolab {

// A figure from one of the papers, shown beside ours in the Timings panel (StageDecl::paper) and
// the bench tables (BenchRow::paper_ms). A technique writes each figure once (e.g.
// core/microgeom/paper.h) and both read it.
struct PaperFigure {
    double ms = 0;
    std::string source;  // e.g. "Heidrich 2000, Table 1, Bricks 128x128 (SGI Octane)"
};

// What a stage is about to allocate, estimated before it allocates (see StageDecl::memory).
struct MemoryEstimate {
    double bytes = 0;
    std::string what;                // how the figure comes about, e.g. "S_i: 4096x4096 texels x 1024 directions x 4 bytes"
    std::vector<std::string> lower;  // the public keys that reduce it, e.g. {"microgeom.resolution", "microgeom.directions"}
};

class StageContext;
struct StageDecl;
class BlobWriter;  // core/blob.h
class BlobReader;

// How a stage's result is kept on disk between runs (core/stage_store.h): written as bytes and read
// back exactly (the same bytes as computing it). Made with stage_codec from two functions of the
// result's type.
struct StageCodec {
    std::function<void(const std::any& result, BlobWriter&)> save;
    std::function<std::any(BlobReader&)> load;  // BlobError for bytes that are not such a result
};

// [SECTION] Typed handles
// A stage's name and the type of its result, declared once, in the stages.h of the technique
// that computes it (scene-wide stages: core/scene_stages.h). The producer is registered under
// its handle (StageGraph::add) and returns its result through it (stage_result); consumers read
// results through it (StageContext::input, Evaluation::get). A misspelt stage is an unknown
// identifier and a wrong result type does not compile: no stage's name is written twice.
template <class T>
struct Stage {
    std::string_view name;
    using Result = T;
    operator std::string() const { return std::string(name); }  // NOLINT: where a name is only shown
};

// The name of a declared stage, for the untyped places that only name it (a stage's inputs, a
// frame step's stages, a bench column): made from a handle, or from a declaration (generic code
// walking the graph), never from text.
class StageName {
public:
    StageName() = default;  // no stage
    template <class T>
    StageName(const Stage<T>& s) : name_(s.name) {}  // NOLINT: implicit, so that handles can be listed
    static StageName of(const StageDecl& d);
    const std::string& str() const { return name_; }
    operator const std::string&() const { return name_; }  // NOLINT
    bool empty() const { return name_.empty(); }
    bool operator==(const StageName& o) const { return name_ == o.name_; }
    bool operator<(const StageName& o) const { return name_ < o.name_; }

private:
    std::string name_;
};
inline std::ostream& operator<<(std::ostream& os, const StageName& n) { return os << n.str(); }

// A frame step's name and the type of its CPU output (core/technique.h, FrameStepDecl), declared
// once like a stage's.
template <class T>
struct FrameStep {
    std::string_view name;  // "<technique>.<step>", e.g. "translucency.illumination"
    using Output = T;
};

// The name of a declared frame step, made from its handle only.
class FrameStepName {
public:
    FrameStepName() = default;
    template <class T>
    FrameStepName(const FrameStep<T>& s) : name_(s.name) {}  // NOLINT: implicit, so that handles can be listed
    const std::string& str() const { return name_; }
    operator const std::string&() const { return name_; }  // NOLINT
    bool operator==(const FrameStepName& o) const { return name_ == o.name_; }
    bool operator<(const FrameStepName& o) const { return name_ < o.name_; }

private:
    std::string name_;
};

enum class StageScope { Scene, Object };

struct StageDecl {
    std::string name;  // set by StageGraph::add from the stage's handle
    std::string help;
    StageScope scope = StageScope::Scene;
    // Object stages: the technique whose objects it computes for ("" = every object).
    std::string technique;
    // ...and of those, only the objects whose `<technique>.method` is one of these (empty: every
    // method). Set by the registry from the methods' frame stages, not declared.
    std::vector<std::string> methods;
    std::vector<std::string> params;   // public keys or "group.*"
    std::vector<StageName> inputs;     // upstream stages
    std::vector<std::string> effects;  // empty: needed whenever downstream needs it
    // Scene stages: also needed only when this holds. Object stages: computed only for the objects
    // for which `applies` holds (the others are reported skipped). `when_text` says when.
    std::function<bool(const Scene&)> when;
    std::function<bool(const Scene&, const SceneObject&)> applies;
    std::string when_text;
    std::optional<PaperFigure> paper;
    // The memory the stage will allocate for these settings (object stages: for that object),
    // estimated from its context (the scene, the object, its inputs' results, which are ready) and
    // checked against the session's budget before it runs (core/session.h).
    std::function<MemoryEstimate(const StageContext&)> memory;
    // Returns the result through the stage's handle: stage_result(handle, value) (or an empty any).
    std::function<std::any(StageContext&)> run;
    // Set for expensive stages (fits, visibility, atlases, tables): the result is kept on disk,
    // keyed by the program version and the stage's fingerprint with its files' contents, and a
    // later run of the same scene reads it back (core/stage_store.h).
    std::optional<StageCodec> disk;
};

// Cached: from the session's memory; Stored: read back from the disk store ("cached (disk)").
enum class StageStatus { Ran, Cached, Skipped, Failed, Cancelled, Stored };
const char* to_string(StageStatus s);

struct StageRun {
    std::string name;
    int object = -1;       // object stages: the scene object; -1 for scene stages
    StageStatus status = StageStatus::Skipped;
    double ms = 0;         // time to compute (Ran), look up (Cached) or read back (Stored)
    uint64_t key = 0;
    std::string reason;    // why skipped ("effects.environment is off") or the error
    std::vector<std::string> warnings;  // results that are valid but need the user's attention (kept with the cached result)
    // "microgeom.visibility" or, for object stages, "microgeom.visibility [object name]".
    std::string label(const Scene& s) const;
};

using ProgressFn = std::function<void(const std::string& stage, double fraction)>;

// Results of one evaluation.
struct Evaluation {
    struct Results {
        std::any scene;                // scene stages
        std::vector<std::any> objects; // object stages, by object index (empty where not computed)
    };
    std::map<std::string, Results> results;
    std::vector<StageRun> runs;  // in execution order, skipped stages included

    // A stage's result: a scene stage's (object -1), or an object stage's for `object` (null
    // when it did not run for it).
    template <class T>
    std::shared_ptr<const T> get(const Stage<T>& stage, int object = -1) const {
        return cast<T>(find(std::string(stage.name), object));
    }
    // The run of a stage (object stages: for `object`; -1 = the first object it ran for).
    const StageRun* run(const StageName& stage, int object = -1) const;
    // Every run of a stage (one per object for object stages).
    std::vector<const StageRun*> runs_of(const StageName& stage) const;
    // The raw result (an empty any when absent).
    const std::any* find(const std::string& stage, int object) const;

private:
    template <class T>
    static std::shared_ptr<const T> cast(const std::any* a) {
        if (!a || !a->has_value()) return nullptr;
        return std::any_cast<std::shared_ptr<const T>>(*a);
    }
};

class StageContext {
public:
    StageContext(const Scene& s, const Evaluation& e, std::string name, int object, const ProgressFn& p, const std::atomic<bool>* cancel)
        : scene(s), object(object), eval_(e), name_(std::move(name)), progress_(p), cancel_(cancel) {}
    const Scene& scene;
    const int object;  // object stages: the object computed for; -1 for scene stages
    // The object computed for (object stages only).
    const SceneObject& obj() const { return scene.objects.at(size_t(object)); }
    const ParamTable& material() const { return obj().material; }
    // An upstream result: a scene stage's, or an object stage's for this stage's object.
    template <class T>
    std::shared_ptr<const T> input(const Stage<T>& stage) const { return eval_.get(stage, object); }
    // An upstream object stage's result for another object (scene stages reading object stages).
    template <class T>
    std::shared_ptr<const T> input(const Stage<T>& stage, int other_object) const { return eval_.get(stage, other_object); }
    // Report progress in [0,1]; throws Cancelled when cancellation was requested.
    void progress(double fraction) const;
    bool cancelled() const { return cancel_ && cancel_->load(std::memory_order_relaxed); }
    // The cancellation flag itself (null when the evaluation cannot be cancelled), for long
    // computations that check it between their own units of work.
    const std::atomic<bool>* cancel_flag() const { return cancel_; }
    // A warning shown with the stage (capture prints it, the sidecar and the GUI list it, with
    // the object's name for object stages).
    void warn(std::string message) { warnings.push_back(std::move(message)); }
    std::vector<std::string> warnings;
    // Says that the CPU computed what the stage asked the GPU for (gpu_or_cpu): such a result is not
    // kept on disk (core/stage_store.h).
    void fell_back_to_cpu() { fell_back_ = true; }
    bool fell_back() const { return fell_back_; }
    const std::string& name() const { return name_; }

private:
    const Evaluation& eval_;
    std::string name_;
    const ProgressFn& progress_;
    const std::atomic<bool>* cancel_;
    bool fell_back_ = false;
};

// A stage's result, returned from its run() through its handle.
template <class T, class V>
std::any stage_result(const Stage<T>&, V&& value) {
    return std::any(std::shared_ptr<const T>(std::make_shared<T>(std::forward<V>(value))));
}

// The codec of a stage whose result type T is written by write(BlobWriter&, const T&) and read back
// by read(BlobReader&) -> T.
template <class T, class Write, class Read>
StageCodec stage_codec(const Stage<T>& stage, Write write, Read read) {
    return {[write](const std::any& a, BlobWriter& w) { write(w, *std::any_cast<std::shared_ptr<const T>>(a)); },
            [stage, read](BlobReader& r) { return stage_result(stage, read(r)); }};
}

// The declarations: immutable once the registry is built (tests build graphs of their own).
class StageGraph {
public:
    // Registers a stage under its handle; throws std::logic_error on a duplicate name or an
    // unknown input. Object stages read scene stages and their own object's object stages; scene
    // stages may read every object's results of an object stage (StageContext::input(stage, object)).
    template <class T>
    void add(const Stage<T>& stage, StageDecl d) {
        d.name = std::string(stage.name);
        add_decl(std::move(d));
    }
    const StageDecl* find(const std::string& name) const;
    const StageDecl& at(const std::string& name) const;  // std::logic_error when unknown
    const std::vector<StageDecl>& stages() const { return stages_; }
    // The registry's access while it builds the graph (StageDecl::methods).
    StageDecl& at_mut(const std::string& name);

    // Whether object `object` is one an object stage computes for (its technique); true for scene stages.
    bool covers(const Scene& scene, const StageDecl& d, int object) const;
    // Whether a stage is needed: its `when` / `applies` holds and an enabled effect needs it (or it
    // lists none). `object` is the object for object stages, -1 for scene stages.
    bool enabled(const Scene& scene, const StageDecl& d, int object, std::string* reason = nullptr) const;
    // The objects an object stage computes for (covers()), in order; {-1} for a scene stage.
    std::vector<int> subjects(const Scene& scene, const StageDecl& d) const;
    // f(input, its object) for each result stage `d` reads when computing for `object`: a scene
    // stage's result, the same object's result of an object stage, or, for a scene stage, every
    // object's result of an object stage.
    void for_each_input(const Scene& scene, const StageDecl& d, int object, const std::function<void(const StageDecl&, int)>& f) const;

    // Every key pattern a stage's result depends on: its own params and those of every stage
    // upstream (their fingerprints are part of its own). What the read contract lets it read.
    std::vector<std::string> params_upstream(const StageDecl& d) const;

    // The full fingerprint of a stage's inputs for a scene (object stages: for `object`): its
    // name, its declared parameter values and its inputs' fingerprints. Empty when the stage
    // would be skipped. Two inputs with equal fingerprints give equal results.
    std::string fingerprint(const Scene& scene, const std::string& stage, int object = -1) const;
    // 64-bit key of a fingerprint (FNV-1a; 0 stays for "skipped").
    static uint64_t hash(std::string_view fingerprint);
    // Cache key of a stage for a scene (0 if the stage would be skipped).
    uint64_t key(const Scene& scene, const std::string& stage, int object = -1) const;

    // Memo of fingerprints within one evaluation, keyed by "stage#object" (one memo per FileIdentity).
    // FileIdentity::Contents: the files' contents in place of their size and date (keys kept on disk).
    using Memo = std::map<std::string, std::string>;
    const std::string& fingerprint(const Scene& scene, const StageDecl& d, int object, Memo& memo, FileIdentity files = FileIdentity::Stat) const;

private:
    void add_decl(StageDecl d);
    std::vector<StageDecl> stages_;
};

// Canonical values behind a parameter pattern ("basic.kd", "geometry.*", "light.*"). `object` >= 0
// restricts geometry.* and technique keys to that object (nothing when it uses another
// technique); -1 covers every object (their indices are part of the text).
// `files` as value_canonical's.
std::string param_fingerprint(const Scene& scene, const std::string& pattern, int object = -1, FileIdentity files = FileIdentity::Stat);
}  // namespace mesolab
