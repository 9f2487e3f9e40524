// The read contract of stages (core/read_contract.h): a stage reading a key that neither it nor a
// stage upstream declares is refused, wherever the read happens: in its work, in tasks on TBB's
// worker threads, in its memory estimate, or through a whole table (ParamTable::values(), ==).
// Declared keys are checked where the declarations are made, at start-up.
#include "core/parallel.h"
#include "core/read_contract.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/stage.h"
#include "core/technique.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <chrono>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <thread>

using namespace mesolab;

namespace {
constexpr Stage<int> kUp{"t.up"}, kProbe{"t.probe"};

// A graph of two stages: t.up declares camera.fov; t.probe, downstream, declares `params` and
// runs `work`, with `memory` as its estimate (when set).
struct Graph {
    StageGraph g;
    Graph(std::vector<std::string> params, std::function<void(StageContext&)> work, std::function<void(const StageContext&)> memory = {}) {
        g.add(kUp, {.params = {"camera.fov"}, .run = [](StageContext&) { return stage_result(kUp, 1); }});
        StageDecl d{.params = std::move(params), .inputs = {kUp}, .run = [work](StageContext& ctx) {
                        work(ctx);
                        return stage_result(kProbe, 2);
                    }};
        if (memory)
            d.memory = [memory](const StageContext& ctx) {
                memory(ctx);
                return MemoryEstimate{1.0, "one byte", {}};
            };
        g.add(kProbe, std::move(d));
    }
    // The message of the refusal (empty when the stage ran).
    std::string refusal() {
        Session session(g);
        session.check_stage_reads = true;
        try {
            session.evaluate(default_scene("basic"), {kProbe});
        } catch (const std::logic_error& e) {
            return e.what();
        } catch (const std::exception& e) {
            return std::string("another error: ") + e.what();
        }
        return {};
    }
};

bool names(const std::string& msg, const std::string& what) { return msg.find(what) != std::string::npos; }
}  // namespace

TEST(StageReads, DeclaredKeysAndThoseUpstreamMayBeRead) {
    Graph ok({"camera.distance", "light.*"}, [](StageContext& ctx) {
        (void)ctx.scene.camera.get_float("distance");
        (void)ctx.scene.camera.get_float("fov");  // declared upstream
        for (const ParamTable& l : ctx.scene.lights) (void)l.values();
    });
    EXPECT_EQ(ok.refusal(), "");
}

TEST(StageReads, AnUndeclaredKeyIsRefusedNamingTheStageAndTheKey) {
    Graph bad({"camera.distance"}, [](StageContext& ctx) { (void)ctx.scene.camera.get_vec2("orbit"); });
    const std::string msg = bad.refusal();
    EXPECT_TRUE(names(msg, "stage t.probe read camera.orbit")) << msg;
}

TEST(StageReads, AReadInTasksOnTbbWorkerThreadsIsRefused) {
    // Only tasks running on another thread than the stage's read the key.
    Graph bad({"camera.distance"}, [](StageContext& ctx) {
        const std::thread::id stage_thread = std::this_thread::get_id();
        mesolab::parallel_for(0, 256, [&](int) {
            std::this_thread::sleep_for(std::chrono::microseconds(200));
            if (std::this_thread::get_id() != stage_thread) (void)ctx.scene.camera.get_vec2("orbit");
        });
    });
    const std::string msg = bad.refusal();
    EXPECT_TRUE(names(msg, "stage t.probe read camera.orbit")) << msg;
}

TEST(StageReads, EveryParallelLoopCarriesTheCheck) {
    // TBB's own parallel_for would run tasks outside the watch: the sources call core/parallel.h's.
    namespace fs = std::filesystem;
    std::vector<std::string> direct;
    for (const char* dir : {"core", "gpu", "app", "panels", "python", "tests"})
        for (const auto& f : fs::recursive_directory_iterator(fs::path(test::source_dir()) / dir)) {
            const std::string ext = f.path().extension().string();
            if (ext != ".cpp" && ext != ".h") continue;
            if (f.path().filename() == "parallel.h" && f.path().parent_path().filename() == "core") continue;
            const std::string text = test::slurp(f.path().string());
            if (text.find(std::string("tbb::") + "parallel_for(") != std::string::npos) direct.push_back(f.path().string());
        }
    EXPECT_TRUE(direct.empty()) << direct.size() << " files call tbb::parallel_for directly, e.g. " << (direct.empty() ? "" : direct.front());
}

TEST(StageReads, AReadInTheMemoryEstimateIsRefused) {
    Graph bad({"camera.distance"}, [](StageContext&) {}, [](const StageContext& ctx) { (void)ctx.scene.camera.get_vec2("orbit"); });
    const std::string msg = bad.refusal();
    EXPECT_TRUE(names(msg, "stage t.probe read camera.orbit")) << msg;
}

TEST(StageReads, AWholeTableIsAReadOfEveryKey) {
    Graph values({"camera.distance"}, [](StageContext& ctx) { (void)ctx.scene.camera.values(); });
    EXPECT_TRUE(names(values.refusal(), "stage t.probe read camera.* (every key of camera)")) << values.refusal();
    Graph equal({"camera.distance"}, [](StageContext& ctx) { (void)(ctx.scene.camera == ctx.scene.camera); });
    EXPECT_TRUE(names(equal.refusal(), "read camera.*")) << equal.refusal();
    Graph all({"camera.*"}, [](StageContext& ctx) { (void)ctx.scene.camera.values(); });
    EXPECT_EQ(all.refusal(), "");
}

TEST(StageReads, PatternsCoverTheirKeys) {
    EXPECT_TRUE(pattern_covers("camera.*", "camera", "fov"));
    EXPECT_TRUE(pattern_covers("camera.*", "camera", "*"));
    EXPECT_TRUE(pattern_covers("camera.fov", "camera", "fov"));
    EXPECT_FALSE(pattern_covers("camera.fov", "camera", "*"));
    EXPECT_FALSE(pattern_covers("camera.fov", "camera", "fo"));
    EXPECT_FALSE(pattern_covers("camera.fov", "camer", "fov"));
    EXPECT_FALSE(pattern_covers("cameras.*", "camera", "fov"));
}

TEST(Declarations, AMisspeltKeyFailsWhereTheDeclarationsAreChecked) {
    const Registry& r = Registry::instance();
    const auto group = [&](std::string_view name) { return r.group(std::string(name)); };
    EXPECT_NO_THROW(check_key_patterns("stage t.ok", {"camera.fov", "light.*", "basic.kd"}, group));
    for (const char* bad : {"camera.fvo", "camra.fov", "camera", "basic.kd_map", ".fov"}) {
        SCOPED_TRACE(bad);
        try {
            check_key_patterns("stage t.bad", {bad}, group);
            ADD_FAILURE() << "accepted";
        } catch (const std::logic_error& e) {
            EXPECT_TRUE(names(e.what(), "stage t.bad declares")) << e.what();
            EXPECT_TRUE(names(e.what(), bad)) << e.what();
        }
    }
}

TEST(Declarations, EveryDeclaredKeyOfTheRegistryExists) {
    // The registry checks them when it is built (a misspelt key stops the program at start-up);
    // this says so for every stage, frame step and truth that ships.
    const Registry& r = Registry::instance();
    const auto group = [&](std::string_view name) { return r.group(std::string(name)); };
    for (const StageDecl& d : r.stages().stages()) EXPECT_NO_THROW(check_key_patterns("stage " + d.name, d.params, group));
    for (const Technique* t : r.techniques()) {
        for (const FrameStepDecl& f : t->frame_steps()) EXPECT_NO_THROW(check_key_patterns("frame step " + f.name, f.params, group));
        if (auto truth = t->truth()) {
            EXPECT_NO_THROW(check_key_patterns("the truth of " + t->name(), truth->params, group));
        }
    }
}

TEST(Declarations, ANameIsEitherAStageOrAKey) {
    const Registry& r = Registry::instance();
    for (const StageDecl& d : r.stages().stages()) {
        const auto dot = d.name.find('.');
        const ParamGroup* g = r.group(d.name.substr(0, dot));
        EXPECT_FALSE(g && g->find(d.name.substr(dot + 1))) << "stage " << d.name << " is also a key";
    }
    for (const Technique* t : r.techniques())
        for (const FrameStepDecl& f : t->frame_steps()) EXPECT_FALSE(t->params().find(f.name.substr(f.name.find('.') + 1))) << "frame step " << f.name << " is also a key";
}
