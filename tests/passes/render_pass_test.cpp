// The render-pass contract: outputs declared once, AOVs on demand within GL_MAX_DRAW_BUFFERS,
// frame steps (offscreen work before the frame) timed and reused, on the CPU and the GPU.
#include "app/commands.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/technique.h"
#include "gpu/renderer.h"
#include "passes/probe.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>

using namespace mesolab;
using namespace mesolab::test;

namespace {

// One object of every registered technique (the probe included), side by side.
Scene every_technique() {
    Scene s = default_scene("basic");
    s.objects.clear();
    float x = -3.f;
    for (const Technique* t : Registry::instance().techniques()) {
        SceneObject o = default_scene(t->name()).objects[0];
        o.name = t->name();
        o.geometry.set("position", std::array<double, 3>{x, 0, 0});
        x += 2.2f;
        s.objects.push_back(o);
    }
    apply_set(s, "camera.distance=9");
    apply_set(s, "microgeom.resolution=16");
    apply_set(s, "microgeom.directions=32");
    apply_set(s, "bumpsynth.lut_size=64");
    apply_set(s, "bumpsynth.ndf_resolution=64");
    apply_set(s, "bumpsynth.detail_distance=100");  // octaves of noise at this distance (the AOV is not empty)
    apply_set(s, "translucency.atlas_size=128");
    apply_set(s, "translucency.compare=true");        // the reference and error AOVs hold the brute force
    return s;
}

std::vector<std::string> every_aov(const Scene& s) {
    std::vector<std::string> r;
    for (const auto& a : Registry::instance().aovs(s)) r.push_back(a.name);
    return r;
}

Scene probe_scene() {
    Scene s = default_scene("probe");
    apply_set(s, "geometry.resolution=48");
    return s;
}

struct TempDirForPasses : test::TempDir {
    TempDirForPasses() : TempDir("passes") {}
};

const FrameStepRun* step(const Frame& f, const std::string& name) {
    for (const auto& st : f.steps)
        if (st.name == name) return &st;
    return nullptr;
}
}  // namespace

// [SECTION] Outputs declared once
TEST(RenderPass, FragmentOutputsComeFromTheTechniquesDeclaration) {
    for (const Technique* t : Registry::instance().techniques()) {
        const std::string glsl = gpu::fragment_outputs(*t);
        const auto outs = t->outputs();
        ASSERT_GE(outs.size(), 2u);
        EXPECT_EQ(outs[0].name, "radiance");
        EXPECT_EQ(outs[1].name, "normal");
        for (size_t k = 0; k < outs.size(); ++k)
            EXPECT_NE(glsl.find("layout(location = " + std::to_string(k) + ") out vec4 o_" + outs[k].name + ";"), std::string::npos) << t->name() << " " << glsl;
        // The CPU writer resolves the same positions.
        Frame f = make_frame(Registry::instance().aovs(default_scene(t->name())), 1, 1);
        const AovWriter w(f, *t);
        for (size_t k = 0; k < outs.size(); ++k) EXPECT_EQ(w.index(outs[k].name), int(k));
        EXPECT_THROW(w.index("no-such-aov"), std::logic_error);
    }
}

// [SECTION] AOVs on demand
TEST(RenderPass, AFrameHoldsRadianceAndTheRequestedAovsOnly) {
    Workbench wb;
    Scene s = default_scene("microgeom");
    apply_set(s, "microgeom.resolution=16");
    apply_set(s, "microgeom.directions=32");
    RenderRequest req;
    req.width = req.height = 48;
    req.aovs = {"shadow"};
    for (std::string b : {"cpu", "gpu"}) {
        req.renderer = b;
        const Frame f = wb.render(s, req).frame;
        ASSERT_EQ(f.layout.size(), 2u);
        EXPECT_EQ(f.layout[0].name, "radiance");
        EXPECT_EQ(f.layout[1].name, "shadow");
        EXPECT_FALSE(f.has("normal"));
        EXPECT_FALSE(f.has("direct"));
    }
    EXPECT_EQ(wb.gpu().layout().size(), 2u) << "the GPU frame has two attachments";
    req.aovs = {"octaves"};  // a bumpsynth AOV, not this scene's
    EXPECT_THROW(wb.render(s, req), InputError);
}

TEST(RenderPass, EveryTechniqueAndEveryAovStaysWithinTheDrawBuffers) {
    Workbench wb;
    const Scene s = every_technique();
    RenderRequest req;
    req.width = 160;
    req.height = 64;
    req.aovs = every_aov(s);
    // Every technique's AOVs: at least radiance, normal, microgeom's five, bumpsynth's octaves and the probe's texel.
    for (const char* a : {"radiance", "normal", "direct", "indirect", "shadow", "folded", "octaves", "texel"})
        ASSERT_NE(std::find(req.aovs.begin(), req.aovs.end(), a), req.aovs.end()) << a;
    auto [cpu, gpu] = render_cpu_and_gpu(wb, s, req.width, req.height, req.aovs);
    const int max_draw = wb.gpu().max_attachments();
    GLint gl_max = 0;
    glGetIntegerv(GL_MAX_DRAW_BUFFERS, &gl_max);
    EXPECT_LE(max_draw, gl_max);
    EXPECT_EQ(gpu.layout.size(), req.aovs.size());
    EXPECT_EQ(wb.gpu().last_batches(), int((req.aovs.size() + size_t(max_draw) - 1) / size_t(max_draw)));
    // Every AOV was drawn: the objects cover pixels in each of them, on both paths; `folded` is 0
    // everywhere (the microgeom object's base is not bent, so nothing folds).
    for (const auto& a : req.aovs) {
        if (a == "folded") {
            expect_all_zero(cpu, "folded");
            expect_all_zero(gpu, "folded");
            continue;
        }
        double sum_cpu = 0, sum_gpu = 0;
        for (float v : cpu.aov(a).data) sum_cpu += std::fabs(v);
        for (float v : gpu.aov(a).data) sum_gpu += std::fabs(v);
        EXPECT_GT(sum_cpu, 0.0) << a;
        EXPECT_GT(sum_gpu, 0.0) << a;
    }
    expect_frames_agree(s, cpu, gpu, {"radiance", "normal"});

    // Forced into batches of two attachments, the GPU frame is the same, byte for byte.
    wb.gpu().set_max_attachments(2);
    req.renderer = "gpu";
    const Frame batched = wb.render(s, req).frame;
    EXPECT_EQ(wb.gpu().last_batches(), int((req.aovs.size() + 1) / 2));
    for (const auto& a : req.aovs) EXPECT_EQ(batched.aov(a).data, gpu.aov(a).data) << a;
    wb.gpu().set_max_attachments(0);
}

// [SECTION] Frame steps
TEST(FrameSteps, RunBeforeTheFrameOnBothPathsAndAgree) {
    Workbench wb;
    const Scene s = probe_scene();
    RenderRequest req;
    req.width = req.height = 96;
    req.aovs = {"texel"};
    auto [cpu, gpu] = render_cpu_and_gpu(wb, s, req.width, req.height, req.aovs);
    for (const Frame* f : {&cpu, &gpu}) {
        ASSERT_EQ(f->steps.size(), 2u);
        EXPECT_EQ(f->steps[0].name, "probe.illumination");
        EXPECT_EQ(f->steps[1].name, "probe.blurred");
        EXPECT_EQ(f->steps[0].status, StageStatus::Ran);
    }
    // A step that ran was timed.
    EXPECT_TRUE(std::isfinite(cpu.steps[0].ms) && cpu.steps[0].ms > 0.0) << cpu.steps[0].ms;
    // The same texel at (almost) every pixel, then the same radiance there.
    size_t same_texel = 0, covered = 0;
    for (size_t i = 0; i < cpu.aov("texel").data.size(); i += 3) {
        if (cpu.aov("radiance").data[i] == 0.f && gpu.aov("radiance").data[i] == 0.f) continue;
        ++covered;
        same_texel += cpu.aov("texel").data[i] == gpu.aov("texel").data[i] && cpu.aov("texel").data[i + 1] == gpu.aov("texel").data[i + 1];
    }
    ASSERT_GT(covered, 1000u);
    EXPECT_GE(double(same_texel), 0.98 * double(covered));
    expect_frames_agree(cpu, gpu, {"radiance"}, {.tight = 1e-4, .frac_tight = 0.97, .loose = 0.02, .frac_loose = 0.995, .interior_max = 0.02});
}

TEST(FrameSteps, AreReusedWhileTheirInputsHold) {
    Workbench wb;
    Scene s = probe_scene();
    RenderRequest req;
    req.width = req.height = 64;
    for (std::string b : {"cpu", "gpu"}) {
        req.renderer = b;
        const Frame first = wb.render(s, req).frame;
        Scene moved = s;
        apply_set(moved, "camera.orbit=40,10");  // not an input of either step
        const Frame second = wb.render(moved, req).frame;
        ASSERT_EQ(second.steps.size(), 2u);
        EXPECT_EQ(step(second, "probe.illumination")->status, StageStatus::Cached);
        EXPECT_EQ(step(second, "probe.blurred")->status, StageStatus::Cached);
        apply_set(moved, "probe.blur=2");  // an input of the blur only
        const Frame third = wb.render(moved, req).frame;
        EXPECT_EQ(step(third, "probe.illumination")->status, StageStatus::Cached);
        EXPECT_EQ(step(third, "probe.blurred")->status, StageStatus::Ran);
        apply_set(moved, "light.direction=10,20");  // an input of both
        const Frame fourth = wb.render(moved, req).frame;
        EXPECT_EQ(step(fourth, "probe.illumination")->status, StageStatus::Ran);
        EXPECT_EQ(step(fourth, "probe.blurred")->status, StageStatus::Ran);
        EXPECT_NE(fourth.aov("radiance").data, third.aov("radiance").data) << "the light moved";
        // Back to the first scene: the reused outputs must not be stale.
        wb.forget_frame_steps();
        const Frame again = wb.render(s, req).frame;
        EXPECT_EQ(again.aov("radiance").data, first.aov("radiance").data);
    }
}

TEST(FrameSteps, AreTimedAsTheirOwnRows) {
    Workbench wb;
    const Scene s = probe_scene();
    RenderRequest req;
    req.width = req.height = 32;
    req.renderer = "cpu";
    wb.render(s, req);
    TimingStat st;
    EXPECT_TRUE(wb.session().profiler().find("frame.cpu/step.probe.illumination", st));
    EXPECT_TRUE(wb.session().profiler().find("frame.cpu/step.probe.blurred", st));
    req.renderer = "gpu";
    wb.render(s, req);
    EXPECT_TRUE(wb.session().profiler().find("frame.gpu/step.probe.illumination", st));
}

TEST(FrameSteps, BenchAndTheCaptureSidecarListThem) {
    TempDirForPasses dir;
    BenchCommand b;
    b.run.tables = {"probe"};
    b.run.repeat = 2;
    b.out = dir / "bench.md";
    ASSERT_EQ(run_bench(b), 0);
    const std::string md = test::slurp(dir / "bench.md");
    EXPECT_NE(md.find("| sphere |"), std::string::npos) << md;
    EXPECT_NE(md.find("| ↳ step probe.illumination |"), std::string::npos) << md;
    EXPECT_NE(md.find("| ↳ step probe.blurred |"), std::string::npos) << md;

    test::write_file(dir / "p.json", R"({"schema":1,"name":"probe-scene","objects":[{"material":{"technique":"probe"}}]})");
    CaptureOptions c;
    c.presets = {dir / "p.json"};
    c.out_dir = dir.path.string();
    c.size = "32x32";
    c.backend = "cpu";
    ASSERT_EQ(run_capture(c), 0);
    const json side = json::parse(test::slurp(dir / "probe-scene.json"));
    ASSERT_TRUE(side.contains("frame_steps"));
    ASSERT_EQ(side["frame_steps"].size(), 2u);
    EXPECT_EQ(side["frame_steps"][0]["name"], "probe.illumination");
    EXPECT_EQ(side["frame_steps"][0]["status"], "ran");
    EXPECT_TRUE(side["frame_steps"][0].contains("ms"));
}

// [SECTION] GPU timings
// A frame's GPU time is the sum of its steps' and passes' ranges; the workbench waits for the
// frame's fence, then takes them. On a software renderer they are the wall times of that work.
TEST(GpuTimings, AFramesTimeIsTheSumOfItsStepsAndPasses) {
    Workbench wb;
    const Scene s = probe_scene();
    RenderRequest req;
    req.width = req.height = 48;
    req.renderer = "gpu";
    wb.gpu().set_pass_timing(true);
    wb.render(s, req);
    wb.forget_frame_steps();
    const RenderResult r = wb.render(s, req);
    ASSERT_TRUE(std::isfinite(r.gpu_ms)) << "the frame's timings were taken after its fence";
    EXPECT_EQ(r.gpu_ms_is_wall, wb.gpu().software());
    double steps = 0;
    for (const FrameStepRun& st : r.frame.steps) {
        EXPECT_EQ(st.status, StageStatus::Ran) << st.name;
        EXPECT_TRUE(std::isfinite(st.ms) && st.ms >= 0.0) << st.name << ": " << st.ms;
        steps += st.ms;
    }
    EXPECT_EQ(r.frame.steps.size(), 2u);
    EXPECT_GE(r.gpu_ms, steps * (1 - 1e-9));
    // Every range under its own path: the steps, the clear and the technique's draw.
    TimingStat st;
    for (const char* path : {"frame.gpu/gpu", "frame.gpu/step.probe.illumination/gpu", "frame.gpu/step.probe.blurred/gpu", "frame.gpu/clear/gpu",
                             "frame.gpu/draw.probe/gpu"})
        EXPECT_TRUE(wb.session().profiler().find(path, st)) << path;
    // A frame whose steps are reused adds no step ranges, and its total is still complete.
    const RenderResult again = wb.render(s, req);
    EXPECT_TRUE(std::isfinite(again.gpu_ms));
    for (const FrameStepRun& run : again.frame.steps) EXPECT_EQ(run.status, StageStatus::Cached) << run.name;
}

// bench --row / --column measure the cells asked for; an unmatched filter names what exists, and
// --update-pages (whole tables) refuses them.
TEST(GpuTimings, BenchMeasuresOnlyTheRowsAndColumnsAskedFor) {
    TempDirForPasses dir;
    BenchCommand b;
    b.run.tables = {"basic"};  // three rows (sphere 64, sphere 512, torus 256), three columns
    b.run.repeat = 1;
    b.run.backend = "cpu";
    b.format = "json";
    b.run.rows = {"sphere 64"};
    b.run.columns = {"tessellate"};
    b.out = dir / "bench.json";
    ASSERT_EQ(run_bench(b), 0);
    const json j = json::parse(test::slurp(dir / "bench.json"));
    ASSERT_EQ(j["cells"].size(), 1u) << j.dump();
    EXPECT_EQ(j["cells"][0]["row"], "sphere 64");
    EXPECT_EQ(j["cells"][0]["column"], "tessellate");
    b.run.rows = {"no such row"};
    try {
        run_bench(b);
        ADD_FAILURE() << "an unmatched --row was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'torus 256'"), std::string::npos) << e.what();
    }
    b.run.rows = {"sphere 64"};
    b.update_pages = true;
    EXPECT_THROW(run_bench(b), InputError);
}

// Another machine's run (bench/NAME.json) is merged into the pages beside this machine's figures,
// and a second --update-pages keeps it: this machine never overwrites it. A bad file is an error
// naming the file and the key.
TEST(GpuTimings, PagesKeepAnotherMachinesFiguresBesideThisOnes) {
    TempDirForPasses dir;
    test::write_file(dir / "README.md", "# page\n\n<!-- bench probe -->\nold\n<!-- /bench -->\n\nafter\n");
    std::filesystem::create_directories(dir / "bench");
    test::write_file(dir / "bench/h100.json", R"({"machine": "Intel Xeon, 16 threads; GL: NVIDIA H100 80GB HBM3/PCIe/SSE2", "label": "H100", "repeat": 5,
        "cells": [{"table": "probe", "row": "sphere", "column": "frame 64x64", "device": "gpu", "median_ms": 0.25, "min_ms": 0.2, "max_ms": 0.3, "gpu_time_ms": 0.05},
                  {"table": "probe", "row": "sphere", "column": "frame 64x64", "step": "probe.blurred", "device": "gpu", "median_ms": 0.01, "min_ms": 0.01, "max_ms": 0.02},
                  {"table": "elsewhere", "row": "x", "column": "y", "device": "cpu", "median_ms": 1, "min_ms": 1, "max_ms": 1}]})");
    BenchCommand b;
    b.run.tables = {"probe"};
    b.run.repeat = 1;
    b.run.backend = "cpu";
    b.update_pages = true;
    b.pages_root = dir.path.string();
    for (int run = 0; run < 2; ++run) {
        ASSERT_EQ(run_bench(b), 0);
        const std::string md = test::slurp(dir / "README.md");
        EXPECT_EQ(md.find("old"), std::string::npos) << md;
        EXPECT_NE(md.find("**H100:** Intel Xeon, 16 threads; GL: NVIDIA H100"), std::string::npos) << md;
        EXPECT_NE(md.find("CPU "), std::string::npos) << "this machine's figure: " << md;
        EXPECT_NE(md.find("**H100** GPU 250 µs [200 µs–300 µs] (GPU time 50 µs)"), std::string::npos) << md;
        EXPECT_NE(md.find("**H100** GPU 10 µs"), std::string::npos) << "the step's row: " << md;
        EXPECT_NE(md.find("after"), std::string::npos);
    }
    test::write_file(dir / "bench/h100.json", R"({"machine": "x", "cells": [{"table": "probe", "row": "sphere", "column": "c", "device": "gpu"}]})");
    try {
        run_bench(b);
        ADD_FAILURE() << "a cell without median_ms was accepted";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("h100.json"), std::string::npos) << m;
        EXPECT_NE(m.find("cells[0]: \"median_ms\""), std::string::npos) << m;
    }
}

// A frame that fails in a pass (more lights than the GPU path takes) leaves no timer range open:
// the next frame renders and is timed.
TEST(GpuTimings, AFailedFrameLeavesTheTimelineClean) {
    Workbench wb;
    Scene bad = default_scene("basic");
    while (bad.lights.size() < 9) bad.lights.push_back(bad.lights.front());
    RenderRequest req;
    req.width = req.height = 32;
    req.renderer = "gpu";
    EXPECT_THROW(wb.render(bad, req), InputError);
    const RenderResult r = wb.render(default_scene("basic"), req);
    EXPECT_TRUE(std::isfinite(r.gpu_ms)) << r.gpu_ms;
}
