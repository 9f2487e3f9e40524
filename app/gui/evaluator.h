#pragma once
// [SECTION] Background evaluation of the edited scene
//  - Stage keys: a scene's frame stages (per object for object stages) and their cache keys, as
//    the session computes them. Two scenes with equal keys share every stage result, so going
//    from one to the other only costs a redraw.
//  - Evaluator: one worker thread evaluates the latest submitted snapshot. Submitting while a job
//    runs sets its cancel flag (StageContext::progress then throws Cancelled) and queues the new
//    snapshot; outcomes are collected by polling from the UI thread. The evaluation and the keys
//    are functions given to the constructor, normally those of the window's Session.
//  - EvalState: the evaluation part of the GUI's state (idle / evaluating / failed / cancelled,
//    the last good Evaluation and its keys), changed only by the transitions below it:
//    scene_changed decides between redraw and re-evaluation, reevaluate, cancel_evaluation and
//    poll_evaluation follow the user's buttons and the worker.
// Nothing here needs a window (no GLFW, ImGui or GL), so tests drive it directly.
#include "app/gui/clock.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/stage.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace mesolab::gui {

// [SECTION] Evaluator
// Evaluates the frame stages of a scene; reports progress through `progress` and throws
// Cancelled once `*cancel` becomes true (both may be checked only now and then).
using EvaluateFn = std::function<Evaluation(const Scene& scene, const ProgressFn& progress, const std::atomic<bool>* cancel)>;
// The keys of a scene's frame stages (Session::frame_keys).
using KeysFn = std::function<StageKeys(const Scene& scene)>;
// The registry's frame-stage keys with the default hash (what a Session with the default hash computes).
StageKeys registry_frame_keys(const Scene& scene);

class Evaluator {
public:
    struct Outcome {
        enum class Kind { Done, Failed, Cancelled } kind = Kind::Done;
        uint64_t id = 0;  // as returned by submit()
        Evaluation eval;  // Done
        Scene scene;      // the snapshot evaluated: what the evaluation holds for, once the document moved on
        StageKeys keys;   // as given to submit()
        std::string error, stage;  // Failed: the message; the last stage that reported progress
        bool input_error = false;  // Failed with an InputError (bad input rather than a bug)
        double ms = 0;
    };
    struct Progress {
        std::string stage;
        double fraction = 0, seconds = 0;
        bool running = false;  // a job is running or pending
    };

    explicit Evaluator(EvaluateFn evaluate, KeysFn keys = registry_frame_keys);
    // Evaluates with `session` (its cache, profiler and memory budget) and its keys.
    explicit Evaluator(Session& session);
    ~Evaluator();  // cancels the running job and joins the worker
    Evaluator(const Evaluator&) = delete;
    Evaluator& operator=(const Evaluator&) = delete;

    // Queues `s` (replacing a queued one) and cancels the running job; returns the job's id.
    uint64_t submit(Scene s, StageKeys keys);
    // Drops the queued job and cancels the running one (its Cancelled outcome still arrives).
    void cancel();
    // No job pending or running and every outcome collected.
    bool idle() const;
    // A job pending or running.
    bool busy() const;
    // The oldest outcome not collected yet.
    std::optional<Outcome> poll();
    // Blocks until an outcome is ready to poll, or `timeout` passed (false then).
    bool wait_outcome(std::chrono::milliseconds timeout) const;
    Progress progress() const;
    // The stage keys of a scene, as this evaluator's session computes them.
    StageKeys keys(const Scene& s) const { return keys_(s); }

private:
    struct Job {
        uint64_t id = 0;
        Scene scene;  // a snapshot: the document goes on being edited on the UI thread meanwhile
        StageKeys keys;
    };
    void loop(std::stop_token st);
    void request_cancel();  // with mutex_ held

    EvaluateFn evaluate_;
    KeysFn keys_;
    mutable std::mutex mutex_;
    std::condition_variable_any cv_;
    mutable std::condition_variable outcome_cv_;
    std::optional<Job> pending_;
    bool running_ = false, stopping_ = false;
    uint64_t next_id_ = 0;
    std::atomic<bool> cancel_{false};
    std::string stage_;
    double fraction_ = 0;
    Clock::time_point started_{};
    std::deque<Outcome> outcomes_;
    std::jthread thread_;  // last: starts after, and stops before, the members it uses
};

// [SECTION] The evaluation state
struct EvalState {
    enum class Phase {
        Idle,        // nothing wanted from the worker: frames are drawn from `last` (if any)
        Evaluating,  // job `job` computes `job_keys`; `last` stays on screen meanwhile
        Failed,      // the evaluation of `failed_keys` failed with `error`; not submitted again
                     // until the keys change or the user asks to re-evaluate
        Cancelled,   // the user cancelled: the frame is older than the scene until the next edit
    };
    Phase phase = Phase::Idle;

    // In every phase: the last completed evaluation (none before the first), its keys and time.
    std::optional<Evaluation> last;
    StageKeys last_keys;
    double last_ms = 0;

    // Evaluating: the job whose outcome is wanted (older ones are superseded) and its keys.
    uint64_t job = 0;
    StageKeys job_keys;

    // Failed: the keys that failed, the message and whether it was bad input.
    StageKeys failed_keys;
    std::string error;
    bool input_error = false;

    // Shown above the Timings tables: why the stage runs listed are not the scene's (the last
    // failure or cancellation). Kept while a new evaluation runs, cleared once one completes.
    std::string note;

    bool failed() const { return phase == Phase::Failed; }
    bool cancelled() const { return phase == Phase::Cancelled; }
};

// [SECTION] Transitions
enum class SceneChange {
    Redraw,        // every key matches the last evaluation: draw again from it, nothing runs
    Evaluate,      // submitted to the worker
    InFlight,      // the running job computes exactly these keys already
    KnownFailure,  // these keys have just failed; the error is shown
};
// The scene was edited (or loaded): redraw or evaluate, by comparing its stage keys with those
// of the last evaluation, the running job and the last failure. A redraw cancels a running job,
// whose result is not needed any more.
SceneChange scene_changed(EvalState& s, Evaluator& ev, const Scene& scene);

// The user's Re-evaluate: forgets a failure and evaluates again when any key differs from the
// last evaluation (e.g. an input file changed on disk). False when every key matches it.
bool reevaluate(EvalState& s, Evaluator& ev, const Scene& scene);

// The user's Cancel: the running job stops; the last completed frame stays.
void cancel_evaluation(EvalState& s, Evaluator& ev);

// What became of the wanted job.
struct Polled {
    enum class Kind { Done, Failed, Cancelled } kind = Kind::Done;
    // Done: the scene to draw with the new evaluation: `current` when the edits made meanwhile
    // only cost a redraw, the evaluated snapshot otherwise (a newer job then computes `current`).
    Scene scene;
    std::string error;  // Failed
    bool input_error = false;
};
// Collects the worker's outcomes, dropping superseded ones, until the wanted job's arrives.
std::optional<Polled> poll_evaluation(EvalState& s, Evaluator& ev, const Scene& current);
}  // namespace mesolab::gui
