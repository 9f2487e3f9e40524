// Dependent-test scattering on the GPU (microgeom.device = gpu: gpu/microgeom/scatter.comp
// through core/microgeom/scatter.h's Gatherer) against the CPU reference (core/microgeom/scatter.cpp).
//
// Tolerance: the same sums in the same order, in float on both sides; the GPU may contract
// multiply-adds (FMA), so every irradiance value must agree to 1e-4 relative (of max(1, |E|)).
// Measured on llvmpipe: at most 4e-7 relative (printed).
// Through the stage graph, S_i also come from the GPU, where a few grazing rays classify
// differently (visibility_gpu_test.cpp); frames then agree for >= 99% of values to 1e-3.
#include "app/workbench.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/curvature.h"
#include "core/microgeom/microgeom.h"
#include "core/scene.h"
#include "gpu/microgeom/scatter_gpu.h"
#include "agreement.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>
#include <thread>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

// Max |E_cpu - E_gpu| / max(1, |E_cpu|) over texels and channels.
double compare(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, ScatterSettings s) {
    const ScatterResult cpu = scatter(hf, dirs, vis, s);
    const auto g = gpu::make_gpu_gatherer();
    s.gatherer = g.get();
    const ScatterResult gpu = scatter(hf, dirs, vis, s);
    EXPECT_EQ(cpu.E_indirect.size(), size_t(hf.width) * size_t(hf.height)) << "nothing to compare";
    EXPECT_EQ(gpu.E_indirect.size(), cpu.E_indirect.size());
    EXPECT_EQ(cpu.direct, gpu.direct);
    double worst = 0, largest = 0;
    for (size_t p = 0; p < cpu.E_indirect.size(); ++p)
        for (int c = 0; c < 3; ++c) {
            const double a = cpu.E_indirect[p][c], b = gpu.E_indirect[p][c];
            EXPECT_TRUE(std::isfinite(b));
            worst = std::max(worst, std::fabs(a - b) / std::max(1.0, std::fabs(a)));
            largest = std::max(largest, std::fabs(a));
        }
    EXPECT_GT(largest, 0.0) << "no irradiance anywhere: two zero results agree about nothing";
    return worst;
}

}  // namespace

TEST(ScatterGpu, EveryBounceAgreesWithTheCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    Environment env;
    env.color = vec3(0.3f, 0.5f, 0.8f);
    struct Case {
        const char* name;
        int res;
        bool periodic;
    };
    for (const Case& c : {Case{"triangles", 32, true}, Case{"bricks", 48, true}, Case{"gaussian", 40, false}}) {
        const Heightfield hf = test::procedural_field(c.name, c.res, c.periodic);
        const DirectionSet dirs = make_direction_set(64);
        const Visibility vis = compute_visibility(hf, dirs);
        for (int depth : {0, 1, 4}) {
            for (bool subset : {false, true}) {
                ScatterSettings s;
                s.env = &env;
                s.light_dir = glm::normalize(vec3(0.6f, 0.2f, 0.7f));
                s.light_E = vec3(2.f);
                s.depth = depth;
                s.all_directions = !subset;
                s.paths = 24;
                s.seed = 7;
                const double worst = compare(hf, dirs, vis, s);
                std::printf("%s %dx%d depth %d %s: max relative difference %.2e\n", c.name, c.res, c.res, depth, subset ? "24 random" : "all", worst);
                EXPECT_LT(worst, 1e-4) << c.name << " depth " << depth;
            }
        }
    }
}

TEST(ScatterGpu, CurvedBaseWeightsAgreeWithTheCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = test::procedural_field("triangles", 48, true);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    for (float deg : {-60.f, 60.f}) {
        const Importance imp = compute_importance(hf, dirs, vis, Bending::from_degrees(deg, 0.f, hf.width, hf.height));
        ScatterSettings s;
        s.light_dir = glm::normalize(vec3(0.7f, 0.f, 0.7f));
        s.light_E = vec3(1.f);
        s.depth = 4;
        s.importance = &imp;
        EXPECT_LT(compare(hf, dirs, vis, s), 1e-4) << deg;
    }
}

// The compute context is made current on a worker thread (as the GUI evaluates stages) while
// another thread renders with its own context; both keep working.
TEST(ScatterGpu, RunsFromAWorkerThreadBesideARenderingThread) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = test::procedural_field("bumps", 32, true);
    const DirectionSet dirs = make_direction_set(64);
    const Visibility vis = compute_visibility(hf, dirs);
    ScatterSettings s;
    s.light_E = vec3(1.f);
    s.depth = 2;
    double worst = 1;
    std::thread worker([&] { worst = compare(hf, dirs, vis, s); });
    Scene scene = default_scene("basic");
    Workbench wb;
    RenderRequest req;
    req.renderer = "gpu";
    req.width = req.height = 64;
    const RenderResult r = wb.render(scene, req);
    worker.join();
    EXPECT_LT(worst, 1e-4);
    double sum = 0;
    for (float v : r.frame.aov("radiance").data) sum += v;
    EXPECT_GT(sum, 0.0);
}

// microgeom.device = gpu through the stage graph (S_i and scattering on the GPU) renders what
// device = cpu renders, with the GPU backend drawing afterwards on its own context.
TEST(ScatterGpu, DeviceGpuThroughTheStagesMatchesDeviceCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const test::DeviceRenders r = test::render_on_both_devices({"microgeom.resolution=64"}, "gpu");
    test::expect_ran_on_the_gpu(r.gpu, {microgeom::stages::visibility, microgeom::stages::scatter, microgeom::stages::scatter_env});
    test::expect_frames_agree(r.cpu.frame, r.gpu.frame, {"radiance", "direct", "indirect", "shadow"}, test::agreement_of("microgeom"));
}
