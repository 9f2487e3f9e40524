// Light-driven scattering on non-planar bases (microgeom.scatter_directions, DirectionalScatter in
// core/microgeom/scatter.h): tabulated for the set directions above the horizon and blended per
// pixel over the spherical triangle of the light's tangent-space direction.
//
// Tolerances:
//  - at a set direction the blend is that direction's solve: barycentrics (1, 0, 0) up to the
//    rounding of the cone coordinates, so 1e-5 relative (of max(1, |E|)) per texel and channel;
//  - between directions (Bricks 32x32, depth 2; 64 random light directions with theta <= 80
//    degrees): per light direction, the texture's RMS error relative to the direct solve's mean
//    irradiance. Measured (printed) at N = 100: theta <= 60 degrees mean 0.037, worst 0.27;
//    theta 60..80 mean 0.26, worst 1.0 (grazing light: the pattern changes fast, and the set's
//    ~20 degree triangles near the horizon blend with zero corners below it); the old
//    approximation (the solve along the macro normal times the macro cosine): 0.25 and 1.39.
//    At N = 400: 0.013 / 0.054 and 0.052 / 0.25. Bounds at N = 100: mean 0.05 / worst 0.4 and
//    mean 0.4 / worst 1.2, at most 1/4 and 1/2 of the old error; N = 400 must lower both means;
//  - CPU vs GPU frames: the tolerances of CpuGpu.AgreeOnEveryAov's orbit presets (scatter_test.cpp);
//  - device = gpu table vs the CPU table: 1e-4 relative (as ScatterGpu, scatter_gpu_test.cpp).
#include "app/workbench.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/microgeom.h"
#include "core/scene.h"
#include "gpu/microgeom/scatter_gpu.h"
#include "agreement.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;
using namespace mesolab::test;

namespace {

// A bump-mapped sphere (default scene) with small, fast settings.
Scene small_sphere() {
    Scene s = default_scene("microgeom");
    for (const char* kv : {"geometry.type=sphere", "microgeom.heightfield=bricks", "microgeom.resolution=32", "microgeom.directions=100", "microgeom.depth=2",
                           "effects.environment=false"})
        apply_set(s, kv);
    return s;
}

RenderResult render(Workbench& wb, const Scene& s, const std::string& backend = "cpu") {
    RenderRequest req;
    req.renderer = backend;
    req.width = req.height = 64;
    return wb.render(s, req);
}

// The stages' inputs and the table of a scene's first object.
struct Solved {
    std::shared_ptr<const Heightfield> hf;
    std::shared_ptr<const DirectionSet> dirs;
    std::shared_ptr<const Visibility> vis;
    std::shared_ptr<const DirectionalScatter> table;
};
Solved solved(const RenderResult& r) {
    return {r.eval.get(microgeom::stages::heightfield, 0), r.eval.get(microgeom::stages::directions, 0),
            r.eval.get(microgeom::stages::visibility, 0), r.eval.get(microgeom::stages::scatter_directions, 0)};
}

ScatterResult direct_solve(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, vec3 l) {
    ScatterSettings st;
    st.depth = 2;
    st.light_dir = l;
    st.light_E = vec3(1.f);
    return scatter(hf, dirs, vis, st);
}
}  // namespace

TEST(ScatterDirections, AtASetDirectionTheBlendIsThatDirectionsSolve) {
    Workbench wb;
    const RenderResult r = render(wb, small_sphere());
    const Solved s = solved(r);
    ASSERT_TRUE(s.table) << "a sphere must tabulate its scattering";
    const Heightfield& hf = *s.hf;
    const DirectionSet& dirs = *s.dirs;
    const DirectionalScatter& table = *s.table;
    EXPECT_EQ(table.count, 50) << "N = 100: the 50 directions with z > 0";
    EXPECT_EQ(table.bytes(), size_t(50) * 32 * 32 * sizeof(vec3));
    double worst = 0;
    for (int j : {0, 7, 23, 38, 49}) {
        const vec3 l = dirs.d[size_t(j)];
        const ScatterResult ref = direct_solve(hf, dirs, *s.vis, l);
        for (int y = 0; y < hf.height; ++y)
            for (int x = 0; x < hf.width; ++x) {
                const vec3 a = ref.E_indirect[hf.index(x, y)], b = table.irradiance(dirs, l, float(x), float(y));
                for (int c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(double(a[c]) - double(b[c])) / std::max(1.0, std::fabs(double(a[c]))));
            }
    }
    std::printf("[ set directions ] max relative difference %.2e\n", worst);
    EXPECT_LT(worst, 1e-5);
    // Below the horizon: nothing.
    EXPECT_EQ(table.irradiance(dirs, vec3(0.f, 0.f, -1.f), 3.f, 5.f), vec3(0.f));
}

namespace {
// Interpolation error of the table between set directions, per light direction the texture's
// RMS error relative to the direct solve's mean irradiance, averaged (and the worst) over random
// light directions in two bands of theta; the same for the old approximation (the solve along
// the macro normal times the macro cosine).
struct BandError {
    double mean = 0, worst = 0, old_mean = 0;
    int count = 0;
};
std::pair<BandError, BandError> interpolation_error(int n_dirs) {
    const Heightfield hf = procedural_field("bricks", 32);
    const DirectionSet dirs = make_direction_set(n_dirs);
    const Visibility vis = compute_visibility(hf, dirs);
    ScatterSettings st;
    st.depth = 2;
    const DirectionalScatter table = scatter_directions(hf, dirs, vis, st);
    const ScatterResult normal = direct_solve(hf, dirs, vis, vec3(0.f, 0.f, 1.f));
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    BandError low, high;  // theta <= 60 degrees, 60..80 degrees
    for (int k = 0; k < 64; ++k) {
        const float cos_max = std::cos(glm::radians(80.f)), z = cos_max + (1.f - cos_max) * u(rng), phi = 2.f * kPi * u(rng);
        const vec3 l(std::sqrt(1.f - z * z) * std::cos(phi), std::sqrt(1.f - z * z) * std::sin(phi), z);
        const ScatterResult ref = direct_solve(hf, dirs, vis, l);
        double err = 0, old_err = 0, sum = 0;
        for (int y = 0; y < hf.height; ++y)
            for (int x = 0; x < hf.width; ++x) {
                const size_t p = hf.index(x, y);
                const vec3 b = table.irradiance(dirs, l, float(x), float(y)), old = normal.E_indirect[p] * l.z;
                for (int c = 0; c < 3; ++c) {
                    err += std::pow(double(b[c]) - double(ref.E_indirect[p][c]), 2.0);
                    old_err += std::pow(double(old[c]) - double(ref.E_indirect[p][c]), 2.0);
                    sum += double(ref.E_indirect[p][c]);
                }
            }
        const double n = 3.0 * double(hf.width) * double(hf.height), level = std::max(sum / n, 1e-9);
        BandError& band = z >= 0.5f ? low : high;
        const double rel = std::sqrt(err / n) / level;
        band.worst = std::max(band.worst, rel);
        band.mean += rel;
        band.old_mean += std::sqrt(old_err / n) / level;
        ++band.count;
    }
    for (BandError* b : {&low, &high}) b->mean /= std::max(1, b->count), b->old_mean /= std::max(1, b->count);
    std::printf("[ between directions ] N = %d: theta <= 60: %d lights, RMS error / mean irradiance: mean %.3f, worst %.3f (old: mean %.3f); "
                "theta 60..80: %d lights, mean %.3f, worst %.3f (old: mean %.3f)\n", n_dirs, low.count, low.mean, low.worst, low.old_mean, high.count,
                high.mean, high.worst, high.old_mean);
    return {low, high};
}
}  // namespace

TEST(ScatterDirections, BetweenDirectionsTheBlendIsCloseToADirectSolve) {
    const auto [low, high] = interpolation_error(100);
    EXPECT_LT(low.mean, 0.05);
    EXPECT_LT(low.worst, 0.4);
    EXPECT_LT(high.mean, 0.4);
    EXPECT_LT(high.worst, 1.2);
    EXPECT_LT(low.mean, 0.25 * low.old_mean) << "the table must beat the macro-normal approximation";
    EXPECT_LT(high.mean, 0.5 * high.old_mean) << "the table must beat the macro-normal approximation";
    // More directions, smaller triangles: the grazing band's error drops.
    const auto [low4, high4] = interpolation_error(400);
    EXPECT_LT(high4.mean, high.mean);
    EXPECT_LT(low4.mean, low.mean);
}

TEST(ScatterDirections, MovingTheLightOnASphereReusesTheTableAndChangesTheImage) {
    Workbench wb;
    Scene s = small_sphere();
    apply_set(s, "microgeom.resolution=30");  // not cached by another test
    const RenderResult first = render(wb, s);
    ASSERT_NE(first.eval.run(microgeom::stages::scatter_directions), nullptr);
    EXPECT_EQ(first.eval.run(microgeom::stages::scatter_directions)->status, StageStatus::Ran);
    EXPECT_EQ(first.eval.run(microgeom::stages::scatter)->status, StageStatus::Skipped) << "a sphere has no per-light solve";
    const uint64_t key = Registry::instance().stages().key(s, microgeom::stages::scatter_directions);
    std::vector<float> prev = first.frame.aov("indirect").data;
    for (const char* set : {"light.direction=70,120", "light.direction=20,-60", "light.intensity=2"}) {
        SCOPED_TRACE(set);
        apply_set(s, set);
        EXPECT_EQ(Registry::instance().stages().key(s, microgeom::stages::scatter_directions), key);
        const RenderResult r = render(wb, s);
        EXPECT_EQ(r.eval.run(microgeom::stages::scatter_directions)->status, StageStatus::Cached);
        const std::vector<float>& now = r.frame.aov("indirect").data;
        EXPECT_NE(now, prev) << "the light change did not reach the scattered light";
        prev = now;
    }
    apply_set(s, "microgeom.depth=3");
    EXPECT_NE(Registry::instance().stages().key(s, microgeom::stages::scatter_directions), key) << "the depth must recompute the table";
}

TEST(ScatterDirections, PlanarBasesKeepTheirPerLightSolve) {
    Workbench wb;
    Scene s = small_sphere();
    apply_set(s, "geometry.type=plane");
    apply_set(s, "camera.mode=texture");
    const RenderResult r = render(wb, s);
    EXPECT_EQ(r.eval.run(microgeom::stages::scatter)->status, StageStatus::Ran);
    EXPECT_EQ(r.eval.run(microgeom::stages::scatter_directions)->status, StageStatus::Skipped);
}

// A point light's direction varies over the plane: the plane then takes the table too, so each
// texel scatters the light arriving from its own direction (the per-light solve could only take one
// direction, from the plane's centre). Moving the light reuses the table and changes the image.
TEST(ScatterDirections, PointLightsOnAPlaneUseTheTable) {
    Workbench wb;
    Scene s = small_sphere();
    apply_set(s, "geometry.type=plane");
    apply_set(s, "camera.mode=texture");
    apply_set(s, "light.type=point");
    apply_set(s, "light.position=0,0,0.6");
    const RenderResult r = render(wb, s);
    EXPECT_EQ(r.eval.run(microgeom::stages::scatter)->status, StageStatus::Skipped);
    EXPECT_EQ(r.eval.run(microgeom::stages::scatter_directions)->status, StageStatus::Ran);
    const Image& ind = r.frame.aov("indirect");
    double sum = 0.0;
    for (float v : ind.data) {
        ASSERT_TRUE(std::isfinite(v));
        sum += v;
    }
    EXPECT_GT(sum, 0.0);
    // Moving the point light reuses the table.
    apply_set(s, "light.position=0.3,0.2,0.5");
    const RenderResult moved = render(wb, s);
    EXPECT_EQ(moved.eval.run(microgeom::stages::scatter_directions)->status, StageStatus::Cached);
    EXPECT_NE(moved.frame.aov("indirect").data, ind.data);
}

// The frame's scattered light on a sphere: the GLSL blend (microgeom.frag) against shade_cpu.
TEST(ScatterDirections, CpuAndGpuAgreeOnASphere) {
    Workbench wb;
    for (const char* preset : {"presets/microgeom/fig10b-scattering.json", "presets/microgeom/fig10c-environment.json"}) {
        SCOPED_TRACE(preset);
        const Scene s = load_preset(source_path(preset));
        const auto [cpu, gpu] = render_cpu_and_gpu(wb, s, 160, 120);
        expect_frames_agree(cpu, gpu, {"radiance", "normal", "direct", "indirect", "shadow"}, agreement_of("microgeom"));
        for (const Frame* f : {&cpu, &gpu}) {
            const std::vector<float>& ind = f->aov("indirect").data;
            EXPECT_GT(*std::max_element(ind.begin(), ind.end()), 1e-3f) << "no scattered light";
        }
    }
}

// microgeom.device = gpu: the table's solves through the GPU gatherer match the CPU's.
TEST(ScatterDirections, DeviceGpuTableMatchesTheCpu) {
    if (!have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = procedural_field("bricks", 24);
    const DirectionSet dirs = make_direction_set(36);
    const Visibility vis = compute_visibility(hf, dirs);
    ScatterSettings st;
    st.depth = 2;
    const DirectionalScatter cpu = scatter_directions(hf, dirs, vis, st);
    const auto g = gpu::make_gpu_gatherer();
    st.gatherer = g.get();
    const DirectionalScatter gpu = scatter_directions(hf, dirs, vis, st);
    ASSERT_EQ(cpu.count, gpu.count);
    ASSERT_EQ(cpu.E.size(), gpu.E.size());
    double worst = 0;
    for (size_t k = 0; k < cpu.E.size(); ++k)
        for (int c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(double(cpu.E[k][c]) - double(gpu.E[k][c])) / std::max(1.0, std::fabs(double(cpu.E[k][c]))));
    std::printf("[ device gpu ] max relative difference %.2e over %d directions\n", worst, cpu.count);
    EXPECT_LT(worst, 1e-4);
}
