// Background evaluation of the edited scene: the worker and the redraw-or-evaluate decisions.
#include "app/gui/evaluator.h"
#include "core/error.h"
#include "core/technique.h"

namespace mesolab::gui {

// [SECTION] Stage keys
StageKeys registry_frame_keys(const Scene& s) {
    const Registry& reg = Registry::instance();
    StageKeys keys;
    for (const auto& name : reg.frame_stages(s)) {
        const StageDecl& d = reg.stages().at(name);
        for (int o : reg.stages().subjects(s, d)) keys.push_back({name, o, reg.stages().key(s, name, o)});
    }
    return keys;
}

// [SECTION] Evaluator
Evaluator::Evaluator(EvaluateFn evaluate, KeysFn keys)
    : evaluate_(std::move(evaluate)), keys_(std::move(keys)), thread_([this](std::stop_token st) { loop(st); }) {}

Evaluator::Evaluator(Session& session)
    : Evaluator([&session](const Scene& s, const ProgressFn& p, const std::atomic<bool>* cancel) { return session.evaluate_frame(s, p, cancel); },
                [&session](const Scene& s) { return session.frame_keys(s); }) {}

Evaluator::~Evaluator() {  // then the jthread member (declared last) stops and joins, first of all members
    std::lock_guard lock(mutex_);
    pending_.reset();
    stopping_ = true;
    request_cancel();
}

void Evaluator::request_cancel() {
    cancel_.store(true);
    cancel_.notify_all();  // an evaluation may wait on the flag itself
}

uint64_t Evaluator::submit(Scene s, StageKeys keys) {
    std::lock_guard lock(mutex_);
    pending_ = Job{++next_id_, std::move(s), std::move(keys)};
    request_cancel();  // the running job, if any, gives way
    cv_.notify_one();
    return next_id_;
}

void Evaluator::cancel() {
    std::lock_guard lock(mutex_);
    pending_.reset();
    request_cancel();
}

bool Evaluator::idle() const {
    std::lock_guard lock(mutex_);
    return !pending_ && !running_ && outcomes_.empty();
}

bool Evaluator::busy() const {
    std::lock_guard lock(mutex_);
    return pending_.has_value() || running_;
}

std::optional<Evaluator::Outcome> Evaluator::poll() {
    std::lock_guard lock(mutex_);
    if (outcomes_.empty()) return std::nullopt;
    Outcome o = std::move(outcomes_.front());
    outcomes_.pop_front();
    return o;
}

bool Evaluator::wait_outcome(std::chrono::milliseconds timeout) const {
    std::unique_lock lock(mutex_);
    return outcome_cv_.wait_for(lock, timeout, [&] { return !outcomes_.empty(); });
}

Evaluator::Progress Evaluator::progress() const {
    std::lock_guard lock(mutex_);
    return {stage_, fraction_, running_ ? seconds_since(started_) : 0.0, running_ || pending_.has_value()};
}

void Evaluator::loop(std::stop_token st) {
    for (;;) {
        Job job;
        {
            std::unique_lock lock(mutex_);
            if (!cv_.wait(lock, st, [&] { return pending_.has_value(); })) return;  // stop requested
            job = std::move(*pending_);
            pending_.reset();
            running_ = true;
            cancel_.store(stopping_);
            stage_.clear();
            fraction_ = 0;
            started_ = Clock::now();
        }
        Outcome out;
        out.id = job.id;
        out.keys = std::move(job.keys);
        const auto t0 = Clock::now();
        const ProgressFn progress = [this](const std::string& stage, double f) {
            std::lock_guard lock(mutex_);
            stage_ = stage;
            fraction_ = f;
        };
        try {
            out.eval = evaluate_(job.scene, progress, &cancel_);
        } catch (const Cancelled&) {
            out.kind = Outcome::Kind::Cancelled;
        } catch (const InputError& e) {
            out.kind = Outcome::Kind::Failed;
            out.input_error = true;
            out.error = e.what();
        } catch (const std::exception& e) {
            out.kind = Outcome::Kind::Failed;
            out.error = e.what();
        }
        out.ms = ms_since(t0);
        out.scene = std::move(job.scene);
        std::lock_guard lock(mutex_);
        out.stage = stage_;
        running_ = false;
        outcomes_.push_back(std::move(out));
        outcome_cv_.notify_all();
    }
}

// [SECTION] Transitions
namespace {
void submit(EvalState& s, Evaluator& ev, const Scene& scene, StageKeys keys) {
    s.phase = EvalState::Phase::Evaluating;
    s.job_keys = keys;
    s.job = ev.submit(scene, std::move(keys));
    s.failed_keys.clear();
    s.error.clear();
    s.input_error = false;
}

void become_idle(EvalState& s) {
    s.phase = EvalState::Phase::Idle;
    s.job = 0;
    s.job_keys.clear();
    s.failed_keys.clear();
    s.error.clear();
    s.input_error = false;
}

constexpr const char* kCancelledNote = "Evaluation cancelled; showing the last completed frame. Edit a parameter or use Re-evaluate to start again.";
}  // namespace

SceneChange scene_changed(EvalState& s, Evaluator& ev, const Scene& scene) {
    StageKeys keys = ev.keys(scene);
    if (s.last && keys == s.last_keys) {
        // Only redraw-cost edits since the last completed evaluation: no stage runs. An older
        // edit's evaluation is not needed any more, and its outcome is ignored.
        if (ev.busy()) ev.cancel();
        become_idle(s);
        s.note.clear();
        return SceneChange::Redraw;
    }
    if (s.phase == EvalState::Phase::Evaluating && keys == s.job_keys) return SceneChange::InFlight;
    if (s.phase == EvalState::Phase::Failed && keys == s.failed_keys) return SceneChange::KnownFailure;
    submit(s, ev, scene, std::move(keys));
    return SceneChange::Evaluate;
}

bool reevaluate(EvalState& s, Evaluator& ev, const Scene& scene) {
    StageKeys keys = ev.keys(scene);
    if (s.last && keys == s.last_keys) {
        if (s.phase != EvalState::Phase::Evaluating) become_idle(s);
        return false;
    }
    submit(s, ev, scene, std::move(keys));
    return true;
}

void cancel_evaluation(EvalState& s, Evaluator& ev) {
    ev.cancel();
    become_idle(s);
    s.phase = EvalState::Phase::Cancelled;
    s.note = kCancelledNote;
}

std::optional<Polled> poll_evaluation(EvalState& s, Evaluator& ev, const Scene& current) {
    while (auto o = ev.poll()) {
        if (s.phase != EvalState::Phase::Evaluating || o->id != s.job) continue;  // superseded by a newer edit
        using K = Evaluator::Outcome::Kind;
        Polled r;
        if (o->kind == K::Done) {
            r.kind = Polled::Kind::Done;
            // Edits made meanwhile that only cost a redraw are shown at once.
            r.scene = ev.keys(current) == o->keys ? current : std::move(o->scene);
            become_idle(s);
            s.last = std::move(o->eval);
            s.last_keys = std::move(o->keys);
            s.last_ms = o->ms;
            s.note.clear();
        } else if (o->kind == K::Failed) {
            r.kind = Polled::Kind::Failed;
            r.error = o->error;
            r.input_error = o->input_error;
            s.phase = EvalState::Phase::Failed;
            s.job = 0;
            s.job_keys.clear();
            s.failed_keys = std::move(o->keys);
            s.error = o->error;
            s.input_error = o->input_error;
            s.note = "The last evaluation failed" + (o->stage.empty() ? std::string() : " (last progress from " + o->stage + ")") + ": " + o->error +
                     (s.last ? "  (showing the last good frame)" : "");
        } else {
            r.kind = Polled::Kind::Cancelled;
            become_idle(s);
            s.phase = EvalState::Phase::Cancelled;
            s.note = kCancelledNote;
        }
        return r;
    }
    return std::nullopt;
}
}  // namespace mesolab::gui
