// The stage graph runs only what an enabled effect needs, caches by declared inputs, and
// invalidates exactly what depends on a change.
#include "core/bumpsynth/ndf.h"
#include "core/scene_stages.h"
#include "core/bumpsynth/stages.h"
#include "core/basic/stages.h"
#include "core/error.h"
#include "core/image.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/stage.h"
#include "core/technique.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <atomic>
#include <filesystem>
#include <map>

using namespace mesolab;

namespace {

// A private graph: geometry <- shade(light) ; env <- envlight (effect environment). Each stage's
// result is its own name.
constexpr Stage<std::string> kGeometry{"t.geometry"}, kShade{"t.shade"}, kEnv{"t.env"}, kEnvLight{"t.envlight"};

struct Counting {
    std::map<std::string, int> runs;
    StageGraph g;
    std::unique_ptr<Session> session;
    Counting() {
        auto counter = [this](const Stage<std::string>& stage) {
            return [this, stage](StageContext& ctx) {
                ++runs[std::string(stage.name)];
                ctx.progress(0.5);
                return stage_result(stage, std::string(stage.name));
            };
        };
        g.add(kGeometry, {.params = {"geometry.resolution"}, .run = counter(kGeometry)});
        g.add(kShade, {.params = {"light.*", "basic.kd"}, .inputs = {kGeometry}, .run = counter(kShade)});
        g.add(kEnv, {.params = {"env.map"}, .run = counter(kEnv)});
        g.add(kEnvLight, {.inputs = {kEnv}, .effects = {"environment"}, .run = counter(kEnvLight)});
        session = std::make_unique<Session>(g);
    }
    Evaluation eval(const Scene& s) { return session->evaluate(s, {kShade, kEnvLight}); }
};

StageStatus status(const Evaluation& e, const StageName& n) { return e.run(n)->status; }
}  // namespace

TEST(StageGraph, RunsOnceThenCaches) {
    Counting c;
    Scene s = default_scene("basic");
    Evaluation e = c.eval(s);
    EXPECT_EQ(status(e, kGeometry), StageStatus::Ran);
    EXPECT_EQ(status(e, kShade), StageStatus::Ran);
    EXPECT_EQ(status(e, kEnv), StageStatus::Ran);
    EXPECT_EQ(status(e, kEnvLight), StageStatus::Ran);
    e = c.eval(s);
    ASSERT_EQ(e.runs.size(), 4u);
    for (const auto& r : e.runs) EXPECT_EQ(r.status, StageStatus::Cached) << r.name;
    EXPECT_EQ(c.runs["t.geometry"], 1);
    EXPECT_EQ(*e.get(kShade), "t.shade");
}

TEST(StageGraph, ChangeRecomputesExactlyItsDependents) {
    Counting c;
    Scene s = default_scene("basic");
    c.eval(s);
    apply_set(s, "light.direction=10,20");  // shade reads light.*; geometry does not
    Evaluation e = c.eval(s);
    EXPECT_EQ(status(e, kGeometry), StageStatus::Cached);
    EXPECT_EQ(status(e, kShade), StageStatus::Ran);
    EXPECT_EQ(status(e, kEnvLight), StageStatus::Cached);
    apply_set(s, "geometry.resolution=17");  // geometry and everything downstream
    e = c.eval(s);
    EXPECT_EQ(status(e, kGeometry), StageStatus::Ran);
    EXPECT_EQ(status(e, kShade), StageStatus::Ran);
    EXPECT_EQ(status(e, kEnv), StageStatus::Cached);
    apply_set(s, "camera.distance=7");  // nobody reads it
    e = c.eval(s);
    ASSERT_EQ(e.runs.size(), 4u);
    for (const auto& r : e.runs) EXPECT_EQ(r.status, StageStatus::Cached) << r.name;
    apply_set(s, "geometry.resolution=64");  // back to a cached setting
    e = c.eval(s);
    EXPECT_EQ(status(e, kGeometry), StageStatus::Cached);
    EXPECT_EQ(c.runs["t.geometry"], 2);
}

TEST(StageGraph, DisabledEffectSkipsItsStagesAndTheirUpstream) {
    Counting c;
    Scene s = default_scene("basic");
    apply_set(s, "effects.environment=false");
    Evaluation e = c.eval(s);
    EXPECT_EQ(status(e, kEnvLight), StageStatus::Skipped);
    EXPECT_NE(e.run(kEnvLight)->reason.find("effects.environment is off"), std::string::npos);
    EXPECT_EQ(e.run(kEnv), nullptr);  // not even visited: nothing enabled needs it
    EXPECT_EQ(c.runs["t.env"], 0);
    EXPECT_EQ(c.runs["t.envlight"], 0);
    EXPECT_EQ(e.get(kEnvLight), nullptr);
    EXPECT_EQ(c.g.key(s, kEnvLight), 0u);
}

TEST(StageGraph, CancellationAndProgress) {
    Counting c;
    Scene s = default_scene("basic");
    std::atomic<bool> cancel{true};
    EXPECT_THROW(c.session->evaluate(s, {kShade}, {}, &cancel), Cancelled);
    EXPECT_EQ(c.session->cache().entries(), 0u);
    cancel = false;
    std::vector<std::string> seen;
    c.session->evaluate(s, {kShade}, [&](const std::string& n, double) { seen.push_back(n); }, &cancel);
    EXPECT_FALSE(seen.empty());
    EXPECT_EQ(seen.front(), std::string(kGeometry.name));
}

TEST(StageGraph, FailingStageReportsAndIsNotCached) {
    StageGraph g;
    int calls = 0;
    static constexpr Stage<int> kFail{"x.fail"};
    g.add(kFail, {.run = [&](StageContext&) -> std::any {
                      ++calls;
                      throw InputError("bad file");
                  }});
    Scene s = default_scene("basic");
    Session session(g);
    EXPECT_THROW(session.evaluate(s, {kFail}), InputError);
    EXPECT_THROW(session.evaluate(s, {kFail}), InputError);
    EXPECT_EQ(calls, 2);
}

TEST(StageGraph, DeclarationErrorsAreCaught) {
    StageGraph g;
    static constexpr Stage<int> kA{"a"}, kB{"b"}, kNope{"nope"};  // kNope is never declared
    g.add(kA, {.run = [](StageContext&) { return std::any(); }});
    EXPECT_THROW(g.add(kA, {.run = [](StageContext&) { return std::any(); }}), std::logic_error);
    EXPECT_THROW(g.add(kB, {.inputs = {kNope}, .run = [](StageContext&) { return std::any(); }}), std::logic_error);
}

// The real graph: moving the light or the camera recomputes nothing; files invalidate by content.
TEST(FrameStages, LightAndCameraNeverRecompute) {
    const StageGraph& g = Registry::instance().stages();
    Scene s = default_scene("basic");
    std::map<std::string, uint64_t> before;
    for (const auto& st : Registry::instance().frame_stages(s)) before[st] = g.key(s, st);
    // The stages a basic frame needs are there and enabled (a key of 0 would compare equal anyway).
    for (const StageName& st : std::vector<StageName>{mesolab::stages::geometry, basic::stages::albedo, mesolab::stages::env_irradiance}) {
        ASSERT_EQ(before.count(st), 1u) << st << " is not a frame stage";
        EXPECT_NE(before[st], 0u) << st << " is skipped";
    }
    for (const char* set : {"light.direction=80,170", "light.intensity=9", "light.color=1,0,0", "camera.orbit=10,10", "camera.distance=50",
                            "camera.mode=texture", "env.color=1,1,1", "env.intensity=3", "basic.kd=0.1,0.1,0.1", "geometry.scale=2"}) {
        Scene t = s;
        apply_set(t, set);
        for (const auto& [st, k] : before) EXPECT_EQ(g.key(t, st), k) << set << " changed " << st;
    }
    Scene t = s;
    apply_set(t, "geometry.resolution=12");
    EXPECT_NE(g.key(t, mesolab::stages::geometry), before[mesolab::stages::geometry]);
    EXPECT_EQ(g.key(t, mesolab::stages::env_map), before[mesolab::stages::env_map]);
}

TEST(FrameStages, EditingAReferencedFileInvalidates) {
    using namespace mesolab::test;
    TempDir dir("filekey");
    write_file(dir / "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write_file(dir / "p.json", R"({"schema":1,"objects":[{"geometry":{"type":"mesh","path":"m.obj"},"material":{"technique":"basic"}}]})");
    const Scene s = load_preset(dir / "p.json");
    const StageGraph& g = Registry::instance().stages();
    const uint64_t k0 = g.key(s, mesolab::stages::geometry);
    write_file(dir / "m.obj", "v 0 0 0\nv 2 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n");
    EXPECT_NE(g.key(s, mesolab::stages::geometry), k0);
}

// The NDF editor re-saves the same file (same path, often the same size) after every stroke, by
// an atomic rename, possibly within one tick of the file system's coarse clock: the key must
// still change, and the recomputed stage must read the new content.
TEST(FrameStages, AtomicRewriteOfASameSizeFileInvalidates) {
    using namespace mesolab::test;
    TempDir dir("rewritekey");
    // Two pixels over [-1, 1]^2: all the mass in the right half of the disk, or in the left half
    // (centroid x = +-4/(3 pi)). Too small to compress, so both files have the same size.
    auto half = [](bool right) {
        Image img(2, 1, 1, 0.f);
        *img.at(right ? 1 : 0, 0) = 1.f;
        return img;
    };
    write_exr(dir / "d.exr", half(true));
    Scene s = default_scene("bumpsynth");
    s.base_dir = dir.path.string();
    s.objects[0].material.set("ndf", std::string("image"));
    s.objects[0].material.set("ndf_image", std::string("d.exr"));
    s.objects[0].material.set("ndf_resolution", int64_t(64));
    const StageGraph& g = Registry::instance().stages();
    Session session;
    const uint64_t k0 = g.key(s, bumpsynth::stages::ndf);
    const Evaluation e0 = session.evaluate(s, {bumpsynth::stages::ndf});
    const auto centroid_x = [](const Evaluation& e) {
        const bumpsynth::Ndf& d = *e.get(bumpsynth::stages::ndf, 0);
        double cx = 0;
        for (int j = 0; j < d.resolution(); ++j)
            for (int i = 0; i < d.resolution(); ++i) cx += d.mass(i, j) * double(d.cell_centre(i, j).x);
        return cx;
    };
    EXPECT_NEAR(centroid_x(e0), 4.0 / (3.0 * M_PI), 0.01);

    // The mirror image, same size, with the modification time of the first: file systems stamp
    // files with a coarse clock (one tick is several ms here), so two saves within one tick look
    // alike by size and time.
    const auto size0 = std::filesystem::file_size(dir / "d.exr");
    const auto time0 = std::filesystem::last_write_time(dir / "d.exr");
    write_exr(dir / "d.exr", half(false));
    std::filesystem::last_write_time(dir / "d.exr", time0);
    ASSERT_EQ(std::filesystem::file_size(dir / "d.exr"), size0) << "the test wants two files of one size";
    EXPECT_NE(g.key(s, bumpsynth::stages::ndf), k0);
    const Evaluation e1 = session.evaluate(s, {bumpsynth::stages::ndf});
    EXPECT_EQ(e1.run(bumpsynth::stages::ndf)->status, StageStatus::Ran);
    EXPECT_NEAR(centroid_x(e1), -4.0 / (3.0 * M_PI), 0.01);
}
