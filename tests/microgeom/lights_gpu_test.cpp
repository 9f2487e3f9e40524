// The goniometer's and the BTF's light images on the GPU (microgeom.device = gpu:
// gpu/microgeom/lights.comp through core/microgeom/scatter.h's LightSolver) against the CPU
// reference (scatter() per light, core/microgeom/goniometer.cpp and btf.cpp).
//
// Tolerance: the same sums in the same order, in float on both sides; the GPU may contract
// multiply-adds (FMA), so images, tables and mosaics agree to 1e-4 relative (of max(1, |x|)) and
// the shadow fractions to 1e-5 absolute. Measured on llvmpipe: printed by each test.
#include "app/workbench.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/btf.h"
#include "core/microgeom/curvature.h"
#include "core/microgeom/ellipse.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/microgeom.h"
#include "core/scene.h"
#include "gpu/microgeom/lights_gpu.h"
#include "gpu/microgeom/scatter_gpu.h"
#include "agreement.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {
struct Field {
    Heightfield hf;
    DirectionSet dirs;
    Visibility vis;
};

Field field(const char* name, int res, int n, bool periodic = true) {
    Field f;
    f.hf = test::procedural_field(name, res, periodic);
    f.dirs = make_direction_set(n);
    f.vis = compute_visibility(f.hf, f.dirs);
    return f;
}


double rel(double a, double b) { return std::fabs(a - b) / std::max(1.0, std::fabs(a)); }

double worst_rel(const std::vector<float>& cpu, const std::vector<float>& gpu) {
    EXPECT_EQ(cpu.size(), gpu.size());
    double worst = 0;
    for (size_t k = 0; k < std::min(cpu.size(), gpu.size()); ++k) worst = std::max(worst, rel(cpu[k], gpu[k]));
    return worst;
}

double worst_rel(const std::vector<vec3>& cpu, const std::vector<vec3>& gpu) {
    EXPECT_EQ(cpu.size(), gpu.size());
    double worst = 0;
    for (size_t k = 0; k < std::min(cpu.size(), gpu.size()); ++k)
        for (int c = 0; c < 3; ++c) worst = std::max(worst, rel(cpu[k][c], gpu[k][c]));
    return worst;
}

// A conformant GLSL compiler may fuse a * b + c into one rounding (an fma) wherever the value is
// not `precise`: NVIDIA's does, llvmpipe's does not. Compiled in ahead of lights.comp, this makes
// every dot() there fused, as NVIDIA computes it (the product of two floats is exact in double,
// the sum is rounded to double and then to float: an fma up to that double rounding).
constexpr const char* kFusedDot = R"(
float fused_mad(float a, float b, float c) { return float(double(a) * double(b) + double(c)); }
float fused_dot(vec2 a, vec2 b) { return fused_mad(a.y, b.y, a.x * b.x); }
float fused_dot(vec3 a, vec3 b) { return fused_mad(a.z, b.z, fused_mad(a.y, b.y, a.x * b.x)); }
#define dot fused_dot
)";

// Worst relative difference of the light images and worst absolute difference of the shadows
// (prelude: see make_gpu_light_solver).
void compare_images(const Field& f, const ScatterSettings& s, const std::vector<vec3>& wis, double& worst_L, double& worst_shadow,
                    const char* prelude = "") {
    const auto solver = gpu::make_gpu_light_solver(f.hf, f.dirs, f.vis, s, 0, prelude);
    std::vector<std::vector<vec3>> L;
    std::vector<std::vector<float>> shadow;
    solver->solve(wis, L, shadow);
    ASSERT_EQ(L.size(), wis.size());
    for (size_t k = 0; k < wis.size(); ++k) {
        ScatterSettings st = s;
        st.light_dir = wis[k];
        st.light_E = vec3(1.f);
        st.env = nullptr;
        const ScatterResult r = scatter(f.hf, f.dirs, f.vis, st);
        ASSERT_EQ(L[k].size(), r.direct.size());
        for (size_t p = 0; p < r.direct.size(); ++p) {
            const vec3 cpu = r.direct[p] + f.hf.albedo[p] * kInvPi * r.E_indirect[p];
            for (int c = 0; c < 3; ++c) {
                ASSERT_TRUE(std::isfinite(L[k][p][c]));
                worst_L = std::max(worst_L, rel(cpu[c], L[k][p][c]));
            }
            worst_shadow = std::max(worst_shadow, std::fabs(double(r.shadow[p]) - double(shadow[k][p])));
        }
    }
}

// Prints the worst difference found and expects it below tol.
void expect_worst_below(const char* what, double worst, double tol) {
    std::printf("%s: worst relative difference %.2g\n", what, worst);
    EXPECT_LT(worst, tol) << what;
}

void expect_images_agree(const char* what, double worst_L, double worst_shadow) {
    std::printf("%s: worst relative difference %.2g, shadow %.2g\n", what, worst_L, worst_shadow);
    EXPECT_LT(worst_L, 1e-4) << what;
    EXPECT_LT(worst_shadow, 1e-5) << what;
}

std::vector<vec3> some_lights() {
    std::vector<vec3> w = btf_directions(3, 5);
    w.push_back(glm::normalize(vec3(1.f, 0.2f, 0.001f)));  // grazing
    w.push_back(vec3(0.f, 0.f, 1.f));
    return w;
}
}  // namespace

TEST(LightsGpu, LightImagesAgreeWithScatterPerLight) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    double worst_L = 0, worst_shadow = 0;
    for (const char* name : {"triangles", "bricks", "gaussian"})
        for (bool periodic : {true, false})
            for (int depth : {0, 1, 3}) {
                const Field f = field(name, 32, 64, periodic);
                ScatterSettings s;
                s.depth = depth;
                compare_images(f, s, some_lights(), worst_L, worst_shadow);
                s.all_directions = false;  // random subsets per bounce, as scatter() draws them
                s.paths = 20;
                s.seed = 7;
                compare_images(f, s, some_lights(), worst_L, worst_shadow);
            }
    expect_images_agree("light images", worst_L, worst_shadow);
}

// Facets lying exactly along the light are unlit on both sides, also where the compiler fuses
// multiply-adds: the triangles field's 45 degree facets facing away from a light 45 degrees up
// have n . l = 0 in float on the CPU, and a fused dot product turns that 0 into the rounding error
// of one product (+-1e-8): decided by its sign, the shadow would be the texel's visibility (0.59)
// instead of 0.
TEST(LightsGpu, FacetsAlongTheLightAreUnlitAlsoWithFusedMultiplyAdds) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Field f = field("triangles", 32, 64);
    const vec3 l = btf_directions(3, 5)[5];  // theta 45 degrees, phi 0
    // The case is there: texels with n . l = 0, fused != 0, that see part of the light's triangle.
    vec3 bary;
    const auto& tri = f.dirs.triangles[size_t(f.dirs.locate(l, bary))];
    int ties = 0;
    for (int y = 0; y < f.hf.height; ++y)
        for (int x = 0; x < f.hf.width; ++x) {
            const vec3 n = f.hf.normal(x, y);
            float v = 0.f;
            for (int k = 0; k < 3; ++k) v += bary[k] * (f.vis.at(tri[size_t(k)], x, y) == Visibility::kNoHit ? 1.f : 0.f);
            if (glm::dot(n, l) == 0.f && std::fma(n.z, l.z, std::fma(n.y, l.y, n.x * l.x)) != 0.f && v > 0.f) ++ties;
        }
    ASSERT_GT(ties, 0) << "no facet along the light: the test tests nothing";
    for (const char* prelude : {"", kFusedDot}) {
        double worst_L = 0, worst_shadow = 0;
        ScatterSettings s;
        s.depth = 1;
        compare_images(f, s, {l}, worst_L, worst_shadow, prelude);
        expect_images_agree(*prelude ? "facets along the light, fused multiply-adds" : "facets along the light", worst_L, worst_shadow);
    }
}

TEST(LightsGpu, EllipseShadowsCurvedBasesAndNoShadowsAgree) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Field f = field("bricks", 32, 100);
    const EllipseMap ell = fit_ellipses(f.hf, f.dirs, f.vis);
    const Importance imp = compute_importance(f.hf, f.dirs, f.vis, Bending::from_degrees(60.f, -30.f, 32, 32));
    double worst_L = 0, worst_shadow = 0;
    ScatterSettings s;
    s.depth = 2;
    s.ellipses = &ell;
    compare_images(f, s, some_lights(), worst_L, worst_shadow);
    s.ellipses = nullptr;
    s.importance = &imp;
    compare_images(f, s, some_lights(), worst_L, worst_shadow);
    s.shadows = false;
    compare_images(f, s, some_lights(), worst_L, worst_shadow);
    expect_images_agree("ellipses / curved / unshadowed", worst_L, worst_shadow);
}

TEST(LightsGpu, SimulatedBrdfAndBtfAgreeWithTheCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Field f = field("bricks", 32, 64);
    GonioSettings g;
    g.scatter.depth = 2;
    g.resolution = 5;
    g.phong = true;
    g.ks = vec3(0.3f);
    const auto solver = gpu::make_gpu_light_solver(f.hf, f.dirs, f.vis, g.scatter);
    for (GonioSettings::Fit fit : {GonioSettings::Fit::Table, GonioSettings::Fit::SH}) {
        g.fit = fit;
        g.samples = 40;
        g.lights = nullptr;
        const SimulatedBrdf cpu = simulate_brdf(f.hf, f.dirs, f.vis, g);
        g.lights = solver.get();
        const SimulatedBrdf gpu = simulate_brdf(f.hf, f.dirs, f.vis, g);
        const double worst = worst_rel(cpu.table, gpu.table);
        EXPECT_EQ(cpu.images, gpu.images);
        expect_worst_below(fit == GonioSettings::Fit::SH ? "simulated BRDF (SH)" : "simulated BRDF (table)", worst, 1e-4);
    }
    g.lights = nullptr;
    const std::vector<vec3> lights = btf_directions(2, 3), views = btf_directions(2, 2);
    const Image cpu = btf_mosaic(f.hf, f.dirs, f.vis, g, lights, views);
    g.lights = solver.get();
    const Image gpu = btf_mosaic(f.hf, f.dirs, f.vis, g, lights, views);
    const double worst = worst_rel(cpu.data, gpu.data);
    expect_worst_below("BTF mosaic", worst, 1e-4);
}

TEST(LightsGpu, BatchesLargerThanOneDispatchGiveTheSameImages) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Field f = field("gaussian", 16, 32);
    const auto solver = gpu::make_gpu_light_solver(f.hf, f.dirs, f.vis, ScatterSettings{});
    ASSERT_GE(solver->batch(), 1);
    std::vector<vec3> wis = btf_directions(8, 20);  // 160 lights: more than one dispatch (at most 64 each)
    std::vector<std::vector<vec3>> all, one;
    std::vector<std::vector<float>> sa, so;
    solver->solve(wis, all, sa);
    for (size_t k : {size_t(0), size_t(63), size_t(64), size_t(159)}) {
        solver->solve({wis[k]}, one, so);
        EXPECT_EQ(one[0], all[k]) << k;
        EXPECT_EQ(so[0], sa[k]) << k;
    }
}

TEST(LightsGpu, BrdfLevelOfDetailOnDeviceGpuMatchesDeviceCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    // The BRDF level shades a smooth sphere.
    const test::DeviceRenders r = test::render_on_both_devices(
        {"microgeom.resolution=32", "microgeom.lod=brdf", "microgeom.brdf_resolution=5", "camera.mode=orbit", "geometry.type=sphere"}, "cpu");
    const RenderResult &cpu = r.cpu, &gpu = r.gpu;
    test::expect_ran_on_the_gpu(gpu, {microgeom::stages::brdf});
    const SimulatedBrdf* bc = cpu.eval.get(microgeom::stages::brdf, 0).get();
    const SimulatedBrdf* bg = gpu.eval.get(microgeom::stages::brdf, 0).get();
    ASSERT_TRUE(bc && bg);
    const double worst_table = worst_rel(bc->table, bg->table);
    expect_worst_below("brdf table, device gpu vs cpu", worst_table, 2e-2);
    const Image& a = cpu.frame.aov("radiance");
    const Image& b = gpu.frame.aov("radiance");
    ASSERT_FALSE(a.data.empty());
    EXPECT_GT(*std::max_element(a.data.begin(), a.data.end()), 0.f) << "a black frame agrees about nothing";
    const double worst = worst_rel(a.data, b.data);
    expect_worst_below("brdf level of detail, device gpu vs cpu (S_i from each device)", worst, 2e-2);
}

// S_i in chunks of directions (gpu/microgeom/chunks.h: what lets 1024^2 x 100 directions past
// llvmpipe's 128 MB storage-block limit), forced here on a small field: 7 directions per chunk.
TEST(LightsGpu, ChunkedDirectionsGiveTheSameResults) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Field f = field("bricks", 32, 64);
    const size_t chunk = size_t(32 * 32) * sizeof(uint32_t) * 7;
    const Importance imp = compute_importance(f.hf, f.dirs, f.vis, Bending::from_degrees(40.f, 20.f, 32, 32));
    double worst = 0;
    for (const Importance* bent : {static_cast<const Importance*>(nullptr), &imp}) {
        ScatterSettings s;
        s.depth = 2;
        s.importance = bent;
        s.light_dir = glm::normalize(vec3(0.3f, 0.2f, 0.9f));
        s.light_E = vec3(1.f);
        {
            const ScatterResult cpu = scatter(f.hf, f.dirs, f.vis, s);
            const auto g = gpu::make_gpu_gatherer(chunk);  // holds the compute context until the block ends
            s.gatherer = g.get();
            const ScatterResult gpu = scatter(f.hf, f.dirs, f.vis, s);
            for (size_t p = 0; p < cpu.E_indirect.size(); ++p)
                for (int c = 0; c < 3; ++c) worst = std::max(worst, rel(cpu.E_indirect[p][c], gpu.E_indirect[p][c]));
            s.gatherer = nullptr;
        }
        const auto solver = gpu::make_gpu_light_solver(f.hf, f.dirs, f.vis, s, chunk);
        std::vector<std::vector<vec3>> L;
        std::vector<std::vector<float>> shadow;
        const std::vector<vec3> wis = some_lights();
        solver->solve(wis, L, shadow);
        for (size_t k = 0; k < wis.size(); ++k) {
            ScatterSettings st = s;
            st.light_dir = wis[k];
            const ScatterResult r = scatter(f.hf, f.dirs, f.vis, st);
            for (size_t p = 0; p < r.direct.size(); ++p) {
                const vec3 ref = r.direct[p] + f.hf.albedo[p] * kInvPi * r.E_indirect[p];
                for (int c = 0; c < 3; ++c) worst = std::max(worst, rel(ref[c], L[k][p][c]));
                EXPECT_NEAR(r.shadow[p], shadow[k][p], 1e-5f);
            }
        }
    }
    expect_worst_below("10 chunks of 7 directions", worst, 1e-4);
}

// microgeom.device = gpu through the stages with everything switched on that has a GPU path:
// S_i, the curvature importance, the five curved ellipse fits, both scatterings. Every stage runs
// on the GPU (no CPU-fallback warning) and the frame matches device = cpu (S_i differ for a few
// grazing rays, see visibility_gpu_test.cpp, so as ScatterGpu.DeviceGpuThroughTheStages...).
TEST(LightsGpu, EveryPrecomputeRunsOnTheGpuThroughTheStages) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const test::DeviceRenders r = test::render_on_both_devices(
        {"microgeom.resolution=48", "microgeom.curvature_u=40", "microgeom.curvature_v=-20", "microgeom.shadows=ellipse"}, "cpu");
    test::expect_ran_on_the_gpu(r.gpu, {microgeom::stages::visibility, microgeom::stages::importance, microgeom::stages::ellipses_curved, microgeom::stages::ellipses,
                                        microgeom::stages::scatter, microgeom::stages::scatter_env});
    test::expect_frames_agree(r.cpu.frame, r.gpu.frame, {"radiance", "direct", "indirect", "shadow"}, test::agreement_of("microgeom"));
}
