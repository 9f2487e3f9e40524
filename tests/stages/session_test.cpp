// Sessions own the mutable state: two sessions share nothing and may run in parallel; object
// stages are keyed by their own object only; the cache never trusts a 64-bit key alone; a stage
// above the memory budget stops before it allocates.
#include "core/strings.h"
#include "app/workbench.h"
#include "core/microgeom/stages.h"
#include "core/scene_stages.h"
#include "core/bumpsynth/stages.h"
#include "core/basic/stages.h"
#include "core/bumpsynth/lut.h"
#include "core/error.h"
#include "core/mesh.h"
#include "core/microgeom/microgeom.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/technique.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <map>
#include <thread>

using namespace mesolab;
using namespace mesolab::test;

namespace {

StageStatus status(const Evaluation& e, const StageName& stage, int object) {
    const StageRun* r = e.run(stage, object);
    EXPECT_NE(r, nullptr) << stage << " for object " << object;
    return r ? r->status : StageStatus::Failed;
}

// Two objects side by side, both using `technique`.
Scene two_objects(const std::string& technique) {
    Scene s = default_scene(technique);
    s.objects.push_back(s.objects[0]);
    s.objects[0].name = "left";
    s.objects[1].name = "right";
    s.objects[0].geometry.set("position", std::array<double, 3>{-1.2, 0, 0});
    s.objects[1].geometry.set("position", std::array<double, 3>{1.2, 0, 0});
    return s;
}

bool same_bytes(const Frame& a, const Frame& b) {
    if (a.width != b.width || a.height != b.height || a.aovs.size() != b.aovs.size()) return false;
    for (const auto& [name, img] : a.aovs)
        if (!b.has(name) || img.data != b.aov(name).data) return false;
    return true;
}
}  // namespace

// [SECTION] Sessions share nothing
TEST(Sessions, TwoSessionsOnTwoThreadsGiveTheSameBytesAsEachAlone) {
    Scene a = default_scene("basic");
    apply_set(a, "geometry.type=torus");
    Scene b = default_scene("bumpsynth");
    apply_set(b, "bumpsynth.lut_size=64");
    apply_set(b, "bumpsynth.ndf_resolution=64");
    RenderRequest req;
    req.renderer = "cpu";
    req.width = 96;
    req.height = 64;
    Frame alone_a, alone_b;
    {
        Workbench wa, wb;
        alone_a = wa.render(a, req).frame;
        alone_b = wb.render(b, req).frame;
        // Each session's cache holds its own scene's stages only.
        EXPECT_NE(wa.session().cache().entries(), 0u);
        EXPECT_EQ(wa.evaluate(b, {bumpsynth::stages::lut}).run(bumpsynth::stages::lut)->status, StageStatus::Ran) << "session a must not see session b's results";
    }
    Frame par_a, par_b;
    Workbench wa, wb;
    std::thread ta([&] { par_a = wa.render(a, req).frame; });
    std::thread tb([&] { par_b = wb.render(b, req).frame; });
    ta.join();
    tb.join();
    EXPECT_TRUE(same_bytes(alone_a, par_a)) << "basic torus differs when rendered beside another session";
    EXPECT_TRUE(same_bytes(alone_b, par_b)) << "bumpsynth sphere differs when rendered beside another session";
    // Their timings went to their own profilers.
    TimingStat st;
    EXPECT_TRUE(wa.session().profiler().find("stage/basic.albedo", st) || wa.session().profiler().find("stage/scene.geometry", st));
    EXPECT_FALSE(wa.session().profiler().find("stage/bumpsynth.lut", st));
    EXPECT_TRUE(wb.session().profiler().find("stage/bumpsynth.lut", st));
}

// The same on the GPU: each session renders through its own EGL context on its own thread.
TEST(Sessions, TwoSessionsOnTwoThreadsRenderTheSameGpuFramesAsEachAlone) {
    Scene a = default_scene("basic");
    apply_set(a, "geometry.type=torus");
    Scene b = default_scene("microgeom");
    apply_set(b, "microgeom.resolution=16");
    apply_set(b, "microgeom.directions=32");
    RenderRequest req;
    req.renderer = "gpu";
    req.width = 96;
    req.height = 64;
    Frame alone_a, alone_b;
    std::thread([&] {
        Workbench w;
        alone_a = w.render(a, req).frame;
    }).join();
    std::thread([&] {
        Workbench w;
        alone_b = w.render(b, req).frame;
    }).join();
    Frame par_a, par_b;
    std::thread ta([&] {
        Workbench w;
        for (int i = 0; i < 3; ++i) par_a = w.render(a, req).frame;
    });
    std::thread tb([&] {
        Workbench w;
        for (int i = 0; i < 3; ++i) par_b = w.render(b, req).frame;
    });
    ta.join();
    tb.join();
    EXPECT_TRUE(same_bytes(alone_a, par_a));
    EXPECT_TRUE(same_bytes(alone_b, par_b));
}

// [SECTION] Object stages
TEST(ObjectStages, ChangingOneObjectsMaterialNeverRecomputesTheOther) {
    Session session;
    Scene s = two_objects("bumpsynth");
    apply_set(s, "objects.1.material.lut_size=128");
    Evaluation e = session.evaluate_frame(s);
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 0), StageStatus::Ran);
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 1), StageStatus::Ran);
    apply_set(s, "objects.1.material.lut_size=64");
    e = session.evaluate_frame(s);
    EXPECT_EQ(status(e, bumpsynth::stages::ndf, 0), StageStatus::Cached);
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 0), StageStatus::Cached);
    EXPECT_EQ(status(e, bumpsynth::stages::ndf, 1), StageStatus::Cached) << "the NDF does not read lut_size";
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 1), StageStatus::Ran);
    EXPECT_EQ(e.get(bumpsynth::stages::lut, 0)->size(), 256);
    EXPECT_EQ(e.get(bumpsynth::stages::lut, 1)->size(), 64);
    // Moving object 1 (a scene-level change of its geometry's position) recomputes nothing.
    apply_set(s, "objects.1.geometry.position=3,0,0");
    e = session.evaluate_frame(s);
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 0), StageStatus::Cached);
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 1), StageStatus::Cached);
    for (const auto& r : e.runs) EXPECT_NE(r.status, StageStatus::Ran) << r.label(s);
}

TEST(ObjectStages, TwoMicrogeomObjectsWithDifferentHeightfields) {
    Session session;
    Scene s = two_objects("microgeom");
    apply_set(s, "geometry.type=plane");
    apply_set(s, "objects.1.geometry.type=plane");
    apply_set(s, "microgeom.resolution=16");
    apply_set(s, "microgeom.directions=32");
    apply_set(s, "objects.1.material.heightfield=bumps");
    Evaluation e = session.evaluate_frame(s);
    EXPECT_EQ(status(e, microgeom::stages::visibility, 0), StageStatus::Ran);
    EXPECT_EQ(status(e, microgeom::stages::visibility, 1), StageStatus::Ran);
    apply_set(s, "objects.1.material.heightfield=triangles");
    e = session.evaluate_frame(s);
    for (const StageName& st : std::vector<StageName>{microgeom::stages::heightfield, microgeom::stages::directions, microgeom::stages::visibility})
        EXPECT_EQ(status(e, st, 0), StageStatus::Cached) << st << ": object 0 did not change";
    EXPECT_EQ(status(e, microgeom::stages::heightfield, 1), StageStatus::Ran);
    EXPECT_EQ(status(e, microgeom::stages::visibility, 1), StageStatus::Ran);
    EXPECT_EQ(status(e, microgeom::stages::directions, 1), StageStatus::Cached) << "the direction set reads microgeom.directions only";
}

TEST(ObjectStages, LoadingOneMeshNeverReloadsTheOthers) {
    TempDir dir("object-meshes");
    write_file(dir / "a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write_file(dir / "b.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
    write_file(dir / "c.obj", "v 0 0 0\nv 3 0 0\nv 0 3 0\nv 3 3 0\nf 1 2 3\nf 2 4 3\n");
    write_file(dir / "p.json", R"({"schema":1,"objects":[
        {"name":"a","geometry":{"type":"mesh","path":"a.obj"},"material":{"technique":"basic"}},
        {"name":"b","geometry":{"type":"mesh","path":"b.obj"},"material":{"technique":"basic"}}]})");
    Scene s = load_preset(dir / "p.json");
    Session session;
    Evaluation e = session.evaluate_frame(s);
    EXPECT_EQ(status(e, mesolab::stages::geometry, 0), StageStatus::Ran);
    EXPECT_EQ(status(e, mesolab::stages::geometry, 1), StageStatus::Ran);
    apply_set(s, "objects.1.geometry.path=" + (dir / "c.obj"));
    e = session.evaluate_frame(s);
    EXPECT_EQ(status(e, mesolab::stages::geometry, 0), StageStatus::Cached);
    EXPECT_EQ(status(e, mesolab::stages::geometry, 1), StageStatus::Ran);
    EXPECT_EQ(e.get(mesolab::stages::geometry, 1)->triangle_count(), 2u);
    EXPECT_EQ(e.get(mesolab::stages::geometry, 0)->triangle_count(), 1u);
}

TEST(ObjectStages, ObjectsWithEqualSettingsShareOneResult) {
    Session session;
    const Scene s = two_objects("bumpsynth");
    const Evaluation e = session.evaluate_frame(s);
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 0), StageStatus::Ran);
    EXPECT_EQ(status(e, bumpsynth::stages::lut, 1), StageStatus::Cached);
    EXPECT_EQ(e.get(bumpsynth::stages::lut, 0).get(), e.get(bumpsynth::stages::lut, 1).get());
}

TEST(ObjectStages, AnotherTechniquesObjectsAreNotComputedFor) {
    Session session;
    Scene s = two_objects("bumpsynth");
    s.objects[1] = default_scene("basic").objects[0];
    const Evaluation e = session.evaluate_frame(s);
    EXPECT_NE(e.run(bumpsynth::stages::ndf, 0), nullptr);
    EXPECT_EQ(e.run(bumpsynth::stages::ndf, 1), nullptr);
    EXPECT_EQ(e.get(bumpsynth::stages::ndf, 1), nullptr);
    EXPECT_EQ(status(e, basic::stages::albedo, 1), StageStatus::Ran);
    EXPECT_EQ(e.get(basic::stages::albedo, 1), nullptr) << "no albedo map: no image, and no error";
    EXPECT_EQ(e.run(basic::stages::albedo, 0), nullptr);
}

// [SECTION] The cache never trusts the key alone
TEST(StageCache, AForcedHashCollisionNeverReturnsAnotherInputsResult) {
    StageGraph g;
    int runs = 0;
    static constexpr Stage<double> kValue{"t.value"};
    g.add(kValue, {.params = {"camera.distance"}, .run = [&](StageContext& ctx) {
                       ++runs;
                       return stage_result(kValue, ctx.scene.camera.get_float("distance"));
                   }});
    // Every fingerprint hashes to the same key.
    Session session(g, [](std::string_view) { return uint64_t(42); });
    Scene a = default_scene("basic"), b = a;
    apply_set(b, "camera.distance=7");
    const Evaluation ea = session.evaluate(a, {kValue});
    const Evaluation eb = session.evaluate(b, {kValue});
    EXPECT_EQ(ea.run(kValue)->key, eb.run(kValue)->key) << "the test wants colliding keys";
    EXPECT_EQ(eb.run(kValue)->status, StageStatus::Ran) << "a colliding key must not be a cache hit";
    EXPECT_DOUBLE_EQ(*eb.get(kValue), 7.0);
    // Equal inputs still hit.
    const Evaluation ea2 = session.evaluate(a, {kValue});
    EXPECT_EQ(ea2.run(kValue)->status, StageStatus::Cached);
    EXPECT_DOUBLE_EQ(*ea2.get(kValue), *ea.get(kValue));
    EXPECT_EQ(runs, 2);
}

TEST(StageCache, FingerprintsCoverTheInputsFingerprints) {
    // Two scenes whose stage parameters are equal but whose upstream differs must differ.
    const StageGraph& g = Registry::instance().stages();
    Scene a = default_scene("bumpsynth"), b = a;
    apply_set(b, "bumpsynth.alpha_x=0.11");
    EXPECT_NE(g.fingerprint(a, bumpsynth::stages::lut, 0), g.fingerprint(b, bumpsynth::stages::lut, 0));
    EXPECT_NE(g.fingerprint(a, bumpsynth::stages::lut, 0).find("bumpsynth.ndf"), std::string::npos);
}

// [SECTION] Memory budget
TEST(Memory, AStageAboveTheBudgetStopsNamingTheParametersToLower) {
    Session session;
    session.set_memory_limit(64ull << 20);
    Scene s = default_scene("microgeom");
    apply_set(s, "microgeom.resolution=1024");
    apply_set(s, "microgeom.directions=256");
    try {
        session.evaluate_frame(s);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("microgeom.visibility"), std::string::npos) << m;
        EXPECT_NE(m.find("microgeom.resolution"), std::string::npos) << m;
        EXPECT_NE(m.find("microgeom.directions"), std::string::npos) << m;
        EXPECT_NE(m.find("--memory-limit"), std::string::npos) << m;
    }
    // Nothing of the refused stage is cached; a smaller setting runs.
    apply_set(s, "microgeom.resolution=32");
    apply_set(s, "microgeom.directions=32");
    EXPECT_NO_THROW(session.evaluate_frame(s));
}

TEST(Memory, EstimatesBoundWhatTheStagesAllocate) {
    // The visibility estimate against the real S_i, and the LUT's against its table.
    Session session;
    Scene s = default_scene("microgeom");
    apply_set(s, "microgeom.resolution=64");
    apply_set(s, "microgeom.directions=64");
    const Evaluation e = session.evaluate_frame(s);
    const StageDecl& d = Registry::instance().stages().at(microgeom::stages::visibility);
    ASSERT_TRUE(d.memory);
    const ProgressFn no_progress;
    const StageContext ctx(s, e, d.name, 0, no_progress, nullptr);  // its inputs are in e
    const double est = d.memory(ctx).bytes;
    const double real = double(e.get(microgeom::stages::visibility, 0)->bytes());
    EXPECT_GE(est, real);
    EXPECT_LE(est, 2.0 * real) << "an estimate far above the allocation would refuse settings that fit";
}

TEST(Memory, TheCommandLineExitsWith2AndNamesTheParameters) {
    // 4096^2 texels x 1024 directions x 4 bytes = 64 GiB: above any budget here.
    const CliResult r = run_mesolab("capture presets/microgeom/fig1b-scattering.json -o /tmp --backend cpu --set microgeom.resolution=4096 "
                                    "--set microgeom.directions=1024 --memory-limit 8G");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("microgeom.resolution"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("microgeom.directions"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("bad_alloc"), std::string::npos) << r.err;
    const CliResult bad = run_mesolab("capture presets/basic/sphere.json -o /tmp --memory-limit lots");
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("--memory-limit"), std::string::npos) << bad.err;
}

TEST(Memory, SizesParseAndPrint) {
    EXPECT_EQ(parse_memory_size("512M"), 512ull << 20);
    EXPECT_EQ(parse_memory_size("4G"), 4ull << 30);
    EXPECT_EQ(parse_memory_size("1.5GiB"), uint64_t(1.5 * double(1ull << 30)));
    EXPECT_EQ(parse_memory_size("1000"), 1000u);
    EXPECT_THROW(parse_memory_size("-1G"), InputError);
    EXPECT_THROW(parse_memory_size("12 parsecs"), InputError);
    EXPECT_EQ(format_bytes(1536.0 * 1024 * 1024), "1.50 GiB");
}

TEST(Memory, AFrameAboveTheBudgetStopsBeforeItIsAllocated) {
    Workbench wb;
    wb.session().set_memory_limit(64ull << 20);
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 4096;  // 16.8 M pixels: over 800 MB for the G-buffer alone
    try {
        wb.render(default_scene("basic"), req);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("4096x4096 frame"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("--size"), std::string::npos) << e.what();
    }
    req.width = req.height = 64;
    EXPECT_NO_THROW(wb.render(default_scene("basic"), req));
}
