// The GUI's background evaluation without a window: the worker (submit, supersede, cancel,
// failures) and the redraw-or-evaluate decisions made by comparing stage keys. The evaluation is
// injected: a fake that records the scenes it is given and, for some scene names, waits for the
// cancel flag or for a gate the test opens.
#include "app/gui/evaluator.h"
#include "core/microgeom/stages.h"
#include "core/error.h"
#include "core/scene.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::gui;

namespace {

// Only a failsafe against a hang: every wait below ends as soon as the awaited event happens.
constexpr std::chrono::milliseconds kFailsafe{60000};

struct Gate {
    std::atomic<bool> open{false};
    void release() {
        open.store(true);
        open.notify_all();
    }
};

// Opens the gate when the test leaves (before the evaluator, declared earlier, joins its worker).
struct ReleaseOnExit {
    Gate& gate;
    ~ReleaseOnExit() { gate.release(); }
};

// The injected evaluation. Scene names pick its behaviour:
//   "block": waits for the cancel flag, then throws Cancelled (as a cancelled stage does)
//   "gate": waits until `gate` opens, then succeeds
//   "bad-input" / "bug": throws InputError / std::runtime_error
//   anything else: succeeds at once with one stage run named after the scene
struct FakeStages {
    std::mutex mutex;
    std::condition_variable cv;
    std::vector<std::string> started;  // scene names, in call order
    Gate gate;

    EvaluateFn fn() {
        return [this](const Scene& s, const ProgressFn& progress, const std::atomic<bool>* cancel) {
            {
                std::lock_guard lock(mutex);
                started.push_back(s.name);
            }
            cv.notify_all();
            if (progress) progress("fake." + s.name, 0.5);
            if (s.name == "block") {
                cancel->wait(false);
                throw Cancelled();
            }
            if (s.name == "gate") gate.open.wait(false);
            if (s.name == "bad-input") throw InputError("broken.json: objects.0.geometry.type: unknown value 'sphear'");
            if (s.name == "bug") throw std::runtime_error("stage exploded");
            Evaluation e;
            StageRun run;
            run.name = "fake." + s.name;
            run.status = StageStatus::Ran;
            e.runs.push_back(run);
            return e;
        };
    }
    // Blocks until `n` evaluations have started.
    void wait_started(size_t n) {
        std::unique_lock lock(mutex);
        ASSERT_TRUE(cv.wait_for(lock, kFailsafe, [&] { return started.size() >= n; })) << "evaluation " << n << " never started";
    }
    size_t calls() {
        std::lock_guard lock(mutex);
        return started.size();
    }
};

Scene named(const std::string& name) {
    Scene s = default_scene();
    s.name = name;  // not a stage parameter: the keys stay those of the default scene
    return s;
}

std::optional<Evaluator::Outcome> next_outcome(Evaluator& ev) {
    if (!ev.wait_outcome(kFailsafe)) return std::nullopt;
    return ev.poll();
}

// The wanted job's result; superseded outcomes are dropped on the way.
std::optional<Polled> wait_polled(EvalState& st, Evaluator& ev, const Scene& current) {
    for (;;) {
        if (auto r = poll_evaluation(st, ev, current)) return r;
        if (!ev.wait_outcome(kFailsafe)) return std::nullopt;
    }
}
}  // namespace

// [SECTION] Evaluator
TEST(Evaluator, SubmittedSceneIsEvaluatedAndItsOutcomePolled) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    EXPECT_TRUE(ev.idle());
    const Scene s = named("one");
    const StageKeys keys{{"fake.one", -1, 42}};
    const uint64_t id = ev.submit(s, keys);

    const auto o = next_outcome(ev);
    ASSERT_TRUE(o);
    EXPECT_EQ(o->kind, Evaluator::Outcome::Kind::Done);
    EXPECT_EQ(o->id, id);
    EXPECT_EQ(o->keys, keys);
    EXPECT_EQ(o->scene.name, "one");
    ASSERT_EQ(o->eval.runs.size(), 1u);
    EXPECT_EQ(o->eval.runs[0].name, "fake.one");
    EXPECT_EQ(o->stage, "fake.one");  // the last progress report
    EXPECT_TRUE(ev.idle());
    EXPECT_FALSE(ev.poll());
}

TEST(Evaluator, NewerSubmitCancelsTheRunningJob) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    const uint64_t first = ev.submit(named("block"), {});
    fake.wait_started(1);
    EXPECT_TRUE(ev.busy());
    const uint64_t second = ev.submit(named("two"), {});
    EXPECT_NE(first, second);

    const auto a = next_outcome(ev);
    ASSERT_TRUE(a);
    EXPECT_EQ(a->id, first);
    EXPECT_EQ(a->kind, Evaluator::Outcome::Kind::Cancelled);
    const auto b = next_outcome(ev);
    ASSERT_TRUE(b);
    EXPECT_EQ(b->id, second);
    EXPECT_EQ(b->kind, Evaluator::Outcome::Kind::Done);
    EXPECT_EQ(b->scene.name, "two");
    EXPECT_TRUE(ev.idle());
}

TEST(Evaluator, QueuedJobIsReplacedByANewerOne) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    ev.submit(named("block"), {});
    fake.wait_started(1);
    ev.submit(named("skipped"), {});  // queued behind "block", then replaced before it starts
    const uint64_t last = ev.submit(named("three"), {});
    std::optional<Evaluator::Outcome> o;
    do o = next_outcome(ev);
    while (o && o->id != last);
    ASSERT_TRUE(o);
    EXPECT_EQ(o->kind, Evaluator::Outcome::Kind::Done);
    EXPECT_EQ(fake.calls(), 2u);  // "skipped" never ran
    EXPECT_TRUE(ev.idle());
}

TEST(Evaluator, CancelLeavesItIdle) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    ev.submit(named("block"), {});
    fake.wait_started(1);
    ev.cancel();
    const auto o = next_outcome(ev);
    ASSERT_TRUE(o);
    EXPECT_EQ(o->kind, Evaluator::Outcome::Kind::Cancelled);
    EXPECT_FALSE(ev.busy());
    EXPECT_TRUE(ev.idle());
    EXPECT_FALSE(ev.progress().running);
}

TEST(Evaluator, FailuresReportTheMessageAndWhetherTheInputWasBad) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    ev.submit(named("bad-input"), {});
    const auto bad = next_outcome(ev);
    ASSERT_TRUE(bad);
    EXPECT_EQ(bad->kind, Evaluator::Outcome::Kind::Failed);
    EXPECT_TRUE(bad->input_error);
    EXPECT_NE(bad->error.find("broken.json"), std::string::npos) << bad->error;
    EXPECT_EQ(bad->stage, "fake.bad-input");

    ev.submit(named("bug"), {});
    const auto bug = next_outcome(ev);
    ASSERT_TRUE(bug);
    EXPECT_EQ(bug->kind, Evaluator::Outcome::Kind::Failed);
    EXPECT_FALSE(bug->input_error);
    EXPECT_EQ(bug->error, "stage exploded");
}

TEST(Evaluator, DestructionCancelsTheRunningJob) {
    FakeStages fake;
    {
        Evaluator ev(fake.fn());
        ev.submit(named("block"), {});
        fake.wait_started(1);
    }  // joins: the job saw its cancel flag
    EXPECT_EQ(fake.calls(), 1u);
}

// [SECTION] Redraw or evaluate
TEST(EvalTransitions, RedrawCostEditsDoNotEvaluateRecomputeCostEditsDo) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    EvalState st;
    Scene s = named("scene");
    ASSERT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    EXPECT_EQ(st.phase, EvalState::Phase::Evaluating);
    auto r = wait_polled(st, ev, s);
    ASSERT_TRUE(r);
    ASSERT_EQ(r->kind, Polled::Kind::Done);
    EXPECT_EQ(st.phase, EvalState::Phase::Idle);
    ASSERT_TRUE(st.last);
    EXPECT_EQ(st.last_keys, registry_frame_keys(s));
    EXPECT_EQ(fake.calls(), 1u);

    // Redraw-cost parameters: the last evaluation still holds.
    apply_set(s, "light.direction=80,200");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::Redraw);
    apply_set(s, "camera.orbit=30,40");
    apply_set(s, "camera.distance=4.5");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::Redraw);
    EXPECT_EQ(st.phase, EvalState::Phase::Idle);
    EXPECT_TRUE(ev.idle());
    EXPECT_EQ(fake.calls(), 1u);

    // A recompute-cost parameter: the stages run again.
    apply_set(s, "geometry.resolution=32");
    EXPECT_NE(registry_frame_keys(s), st.last_keys);
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    r = wait_polled(st, ev, s);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->kind, Polled::Kind::Done);
    EXPECT_EQ(fake.calls(), 2u);
    EXPECT_EQ(st.last_keys, registry_frame_keys(s));

    // Back to the first geometry: a new evaluation (the stage cache makes it cheap).
    apply_set(s, "geometry.resolution=64");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
}

TEST(EvalTransitions, NewerEditSupersedesTheRunningEvaluation) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    EvalState st;
    Scene s = named("block");
    ASSERT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    fake.wait_started(1);
    const uint64_t first = st.job;

    // An edit that the running job computes anyway: nothing new is submitted.
    apply_set(s, "light.direction=10,20");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::InFlight);
    EXPECT_EQ(st.job, first);

    // A recompute-cost edit: submitted, the running job is cancelled and its outcome dropped.
    s.name = "newer";
    apply_set(s, "geometry.resolution=33");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    EXPECT_NE(st.job, first);
    const auto r = wait_polled(st, ev, s);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->kind, Polled::Kind::Done);
    EXPECT_EQ(r->scene.name, "newer");
    EXPECT_EQ(st.phase, EvalState::Phase::Idle);
    EXPECT_EQ(st.last_keys, registry_frame_keys(s));
    EXPECT_EQ(fake.calls(), 2u);
    EXPECT_TRUE(ev.idle());
}

TEST(EvalTransitions, RedrawCostEditDuringAnEvaluationIsDrawnWithItsResult) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    ReleaseOnExit release{fake.gate};
    EvalState st;
    Scene s = named("gate");
    ASSERT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    fake.wait_started(1);
    apply_set(s, "camera.distance=7");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::InFlight);
    fake.gate.release();
    const auto r = wait_polled(st, ev, s);
    ASSERT_TRUE(r);
    ASSERT_EQ(r->kind, Polled::Kind::Done);
    EXPECT_EQ(r->scene, s);  // the current camera, not the snapshot's
    EXPECT_EQ(fake.calls(), 1u);
}

TEST(EvalTransitions, CancelLeavesTheWorkerIdleAndTheLastEvaluationInPlace) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    EvalState st;
    Scene s = named("first");
    scene_changed(st, ev, s);
    ASSERT_TRUE(wait_polled(st, ev, s));
    ASSERT_TRUE(st.last);

    s.name = "block";
    apply_set(s, "geometry.resolution=20");
    ASSERT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    fake.wait_started(2);
    cancel_evaluation(st, ev);
    EXPECT_EQ(st.phase, EvalState::Phase::Cancelled);
    EXPECT_TRUE(st.cancelled());
    EXPECT_FALSE(st.note.empty());
    ASSERT_TRUE(ev.wait_outcome(kFailsafe));
    EXPECT_FALSE(poll_evaluation(st, ev, s));  // the cancelled job's outcome is not wanted
    EXPECT_TRUE(ev.idle());
    EXPECT_EQ(st.phase, EvalState::Phase::Cancelled);
    ASSERT_TRUE(st.last);
    EXPECT_EQ(st.last->runs.at(0).name, "fake.first");

    // The next edit starts again.
    s.name = "again";
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    ASSERT_TRUE(wait_polled(st, ev, s));
    EXPECT_EQ(st.phase, EvalState::Phase::Idle);
    EXPECT_TRUE(st.note.empty());
}

TEST(EvalTransitions, FailureIsReportedAndNotRetriedUntilTheKeysChangeOrReevaluate) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    EvalState st;
    Scene s = named("bad-input");
    ASSERT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    const auto r = wait_polled(st, ev, s);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->kind, Polled::Kind::Failed);
    EXPECT_TRUE(r->input_error);
    EXPECT_NE(r->error.find("sphear"), std::string::npos) << r->error;
    EXPECT_TRUE(st.failed());
    EXPECT_TRUE(st.input_error);
    EXPECT_EQ(st.error, r->error);
    EXPECT_NE(st.note.find("sphear"), std::string::npos) << st.note;
    EXPECT_FALSE(st.last);

    // The same inputs again (a redraw-cost edit): not submitted.
    apply_set(s, "light.direction=5,5");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::KnownFailure);
    EXPECT_EQ(fake.calls(), 1u);

    // Re-evaluate forgets the failure and tries again.
    EXPECT_TRUE(reevaluate(st, ev, s));
    EXPECT_EQ(st.phase, EvalState::Phase::Evaluating);
    ASSERT_TRUE(wait_polled(st, ev, s));
    EXPECT_EQ(fake.calls(), 2u);
    EXPECT_TRUE(st.failed());

    // Other inputs: evaluated, and a success clears the failure.
    s.name = "fixed";
    apply_set(s, "geometry.resolution=40");
    EXPECT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    const auto ok = wait_polled(st, ev, s);
    ASSERT_TRUE(ok);
    EXPECT_EQ(ok->kind, Polled::Kind::Done);
    EXPECT_EQ(st.phase, EvalState::Phase::Idle);
    EXPECT_TRUE(st.error.empty());
    EXPECT_TRUE(st.note.empty());
}

TEST(EvalTransitions, ReevaluateIsANoOpWhenEveryKeyMatches) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    EvalState st;
    Scene s = named("scene");
    scene_changed(st, ev, s);
    ASSERT_TRUE(wait_polled(st, ev, s));
    EXPECT_FALSE(reevaluate(st, ev, s));
    EXPECT_EQ(st.phase, EvalState::Phase::Idle);
    EXPECT_TRUE(ev.idle());
    EXPECT_EQ(fake.calls(), 1u);
}

TEST(EvalTransitions, BugsAreFailuresThatAreNotInputErrors) {
    FakeStages fake;
    Evaluator ev(fake.fn());
    EvalState st;
    const Scene s = named("bug");
    scene_changed(st, ev, s);
    const auto r = wait_polled(st, ev, s);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->kind, Polled::Kind::Failed);
    EXPECT_FALSE(r->input_error);
    EXPECT_EQ(r->error, "stage exploded");
}

// [SECTION] The window's session
// Settings above the memory budget fail as bad input naming the parameters to lower (the window
// shows the message and keeps running); lowering them evaluates again.
TEST(EvalTransitions, ASessionsMemoryBudgetFailsAsBadInputNamingTheParameters) {
    Session session;
    session.set_memory_limit(32ull << 20);
    Evaluator ev(session);
    EvalState st;
    Scene s = default_scene("microgeom");
    apply_set(s, "microgeom.resolution=1024");
    apply_set(s, "microgeom.directions=512");
    ASSERT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    const auto r = wait_polled(st, ev, s);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->kind, Polled::Kind::Failed);
    EXPECT_TRUE(r->input_error);
    EXPECT_NE(r->error.find("microgeom.resolution"), std::string::npos) << r->error;
    EXPECT_NE(r->error.find("microgeom.directions"), std::string::npos) << r->error;
    apply_set(s, "microgeom.resolution=32");
    apply_set(s, "microgeom.directions=32");
    ASSERT_EQ(scene_changed(st, ev, s), SceneChange::Evaluate);
    const auto ok = wait_polled(st, ev, s);
    ASSERT_TRUE(ok);
    EXPECT_EQ(ok->kind, Polled::Kind::Done);
    EXPECT_EQ(ev.keys(s), session.frame_keys(s));
}
