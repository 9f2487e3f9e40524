// translucency.method = separable: screen-space separable subsurface scattering (Jimenez et al.
// 2015; core/translucency/separable.h). The kernel's strips hold what the profile holds over them
// (against the closed-form tail), its weights make the profile's albedo; the blur keeps power (a
// point of light leaves as R_total), gives R_total E under uniform light everywhere, and does not
// cross to another object or over a depth step; CPU and GPU frames agree; the method runs none of
// the pipeline's stages and its truth is the technique's.
#include "app/workbench.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/translucency/burley.h"
#include "core/translucency/dipole.h"
#include "core/translucency/separable.h"
#include "core/translucency/separable_blur.h"
#include "core/translucency/stages.h"
#include "core/translucency/translucency.h"
#include "core/truth/cache.h"
#include "support/frames.h"
#include "translucency/sphere_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
constexpr double kPiD = 3.14159265358979323846;

std::unique_ptr<Profile> profile(const char* kind, const char* material) {
    const Medium m = measured_material(material).medium;
    if (std::string(kind) == "burley") return std::make_unique<BurleyProfile>(m);
    return std::make_unique<Dipole>(m);
}

// A small translucent sphere, side-lit.
Scene small_sphere() {
    Scene s = test::side_lit_sphere();
    apply_set(s, "translucency.method", "separable");
    apply_set(s, "translucency.material", "skin1");
    return s;
}

using test::max_value;

// A flat image: every pixel of object 0 at depth 100 mm, pixels of `pixel_mm`.
BlurImage flat_image(int w, int h, float pixel_mm) {
    BlurImage im;
    im.width = w, im.height = h;
    im.value.assign(size_t(w) * size_t(h), vec3(0.f));
    im.object.assign(im.value.size(), 0);
    im.depth_mm.assign(im.value.size(), 100.f);
    im.pixel_mm.assign(im.value.size(), pixel_mm);
    return im;
}

std::vector<vec3> blur_both(const BlurImage& im, const SeparableKernel& k) {
    std::vector<vec3> across, B;
    separable_blur_pass(im, {&k}, false, across);
    BlurImage second = im;
    second.value = across;
    separable_blur_pass(second, {&k}, true, B);
    return B;
}
}  // namespace

// [SECTION] The kernel
// S(m) = ∫∫_{|x|≤m} R_d dA, by an independent route: in polar coordinates about the origin the
// strip's boundary lies m / |cos θ| away, so S = R_total − ∫_0^{2π} T(m / |cos θ|) dθ with T the
// profile's closed-form tail (midpoint rule, 20,000 directions). Within 1e-4 of R_total, for both
// profiles, three materials and strips from a hundredth of a mean free path to many.
TEST(TranslucencySeparable, TheStripIntegralIsTheProfileOverTheStrip) {
    for (const char* kind : {"dipole", "burley"})
        for (const char* material : {"skin1", "marble", "ketchup"}) {
            const auto p = profile(kind, material);
            for (double m : {0.003, 0.05, 0.4, 3.0, 30.0}) {
                const int n = 20000;
                dvec3 lost(0.0);
                for (int i = 0; i < n; ++i) {
                    const double c = std::abs(std::cos((i + 0.5) * 2.0 * kPiD / n));
                    if (c > 0.0) lost += p->tail(m / c) * (2.0 * kPiD / n);
                }
                const dvec3 expected = p->total_reflectance() - lost, got = strip_integral(*p, m);
                for (int ch = 0; ch < 3; ++ch)
                    EXPECT_NEAR(got[ch], expected[ch], 1e-4 * p->total_reflectance()[ch]) << kind << " " << material << " m " << m << " channel " << ch;
            }
            EXPECT_EQ(strip_integral(*p, 0.0), dvec3(0.0));
        }
}

// Each pass's weights sum to √R_total (the strips tile the line), so the two passes' product holds
// R_total exactly: the profile's albedo, whatever the tap count. Offsets are symmetric, 0 in the
// middle, out to where the profile holds 99.5% of R_total; the weights, as densities over their strips, fall
// off from the centre outwards (the last strip reaches to infinity).
TEST(TranslucencySeparable, TheKernelsWeightsMakeTheProfilesAlbedo) {
    for (const char* kind : {"dipole", "burley"})
        for (const char* material : {"skin1", "marble", "skimmilk"})
            for (int taps : {3, 7, 17, 63}) {
                SCOPED_TRACE(std::string(kind) + " " + material + " " + std::to_string(taps));
                const auto p = profile(kind, material);
                const SeparableKernel k = make_separable_kernel(*p, taps);
                ASSERT_EQ(k.offset_mm.size(), size_t(taps));
                EXPECT_EQ(k.offset_mm[size_t(taps / 2)], 0.f);
                EXPECT_NEAR(k.reach_mm, p->radius_holding(0.995), 1e-5 * k.reach_mm);
                dvec3 sum(0.0);
                for (int i = 0; i < taps; ++i) {
                    EXPECT_EQ(k.offset_mm[size_t(i)], -k.offset_mm[size_t(taps - 1 - i)]);
                    EXPECT_EQ(k.weight[size_t(i)], k.weight[size_t(taps - 1 - i)]);
                    sum += dvec3(k.weight[size_t(i)]);
                }
                // The marginal's density over each tap's strip (its weight over the strip's width)
                // falls from the centre outwards.
                const int h = taps / 2;
                std::vector<double> edge(size_t(h) + 1);
                for (int i = 0; i < h; ++i) edge[size_t(i)] = 0.5 * (double(k.offset_mm[size_t(h + i)]) + double(k.offset_mm[size_t(h + i + 1)]));
                for (int c = 0; c < 3; ++c) {
                    EXPECT_NEAR(sum[c] * sum[c], p->total_reflectance()[c], 2e-6 * p->total_reflectance()[c]) << "channel " << c;
                    double last = double(k.weight[size_t(h)][c]) / (2.0 * edge[0]);
                    for (int i = 1; i < h; ++i) {
                        const double density = double(k.weight[size_t(h + i)][c]) / (edge[size_t(i)] - edge[size_t(i - 1)]);
                        EXPECT_LE(density, last * (1.0 + 1e-6)) << "tap " << i << " channel " << c;
                        last = density;
                    }
                }
            }
    EXPECT_THROW(make_separable_kernel(Dipole(measured_material("skin1").medium), 4), std::invalid_argument);
}

// [SECTION] The blur
// Uniform irradiance leaves as R_total E at every pixel: in the middle, at the image's edges and
// at the object's (taps beyond them read the centre), on a tilted surface (its depth changes from
// pixel to pixel) too.
TEST(TranslucencySeparable, UniformIrradianceLeavesAsTheAlbedoEverywhere) {
    const auto p = profile("dipole", "skin1");
    const SeparableKernel k = make_separable_kernel(*p, 17);
    BlurImage im = flat_image(64, 48, 0.2f);
    for (int y = 0; y < im.height; ++y)
        for (int x = 0; x < im.width; ++x) {
            const size_t i = size_t(y) * size_t(im.width) + size_t(x);
            im.value[i] = vec3(2.f);
            im.depth_mm[i] = 100.f + 0.3f * float(x);        // a slope of 56° in x
            if (x < 6 || (x > 40 && y > 30)) im.object[i] = -1;  // the background, a notch
        }
    const std::vector<vec3> B = blur_both(im, k);
    for (size_t i = 0; i < B.size(); ++i) {
        if (im.object[i] < 0) continue;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(B[i][c], 2.0 * p->total_reflectance()[c], 2e-5) << "pixel " << i;
    }
}

// A point of light (one pixel) on a flat surface much larger than the kernel: the power leaving
// is R_total times the power that entered (linear interpolation splits each tap's weight between
// two pixels without loss), in every channel, from coarse pixels (a few taps land on the same
// pixel) to fine ones (the kernel spans hundreds of pixels, its taps tens of pixels apart: a
// single lit pixel comes out as the taps' pattern, which only a smooth irradiance fills in).
TEST(TranslucencySeparable, APointOfLightLeavesAsTheAlbedo) {
    const auto p = profile("dipole", "marble");
    const SeparableKernel k = make_separable_kernel(*p, 33);
    for (float pixel : {2.f, 0.5f, 0.05f}) {
        SCOPED_TRACE(pixel);
        const int n = 2 * int(std::ceil(k.reach_mm / pixel)) + 11;
        BlurImage im = flat_image(n, n, pixel);
        const int c0 = n / 2;
        im.value[size_t(c0) * size_t(n) + size_t(c0)] = vec3(1.f);
        const std::vector<vec3> B = blur_both(im, k);
        dvec3 out(0.0);
        for (const vec3& b : B) out += dvec3(b);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[c], p->total_reflectance()[c], 1e-5 * p->total_reflectance()[c]) << "channel " << c;
    }
}

// Light does not cross to another object, nor over a step in depth much larger than the taps'
// offsets (the surface turns away: another surface seen behind).
TEST(TranslucencySeparable, TheBlurStopsAtAnotherObjectAndAtADepthStep) {
    const auto p = profile("dipole", "skin1");
    const SeparableKernel k = make_separable_kernel(*p, 17);
    for (const char* what : {"object", "depth"}) {
        SCOPED_TRACE(what);
        BlurImage im = flat_image(60, 20, 0.1f);
        for (int y = 0; y < im.height; ++y)
            for (int x = 0; x < im.width; ++x) {
                const size_t i = size_t(y) * size_t(im.width) + size_t(x);
                if (x < 30) {
                    im.value[i] = vec3(1.f);
                } else if (std::string(what) == "object") {
                    im.object[i] = 1;
                } else {
                    im.depth_mm[i] = 500.f;
                }
            }
        std::vector<vec3> across, B;
        separable_blur_pass(im, {&k, &k}, false, across);
        BlurImage second = im;
        second.value = across;
        separable_blur_pass(second, {&k, &k}, true, B);
        for (int y = 0; y < im.height; ++y)
            for (int x = 30; x < im.width; ++x) ASSERT_EQ(B[size_t(y) * size_t(im.width) + size_t(x)], vec3(0.f)) << x << "," << y;
        // The lit side keeps its own light: R_total E.
        EXPECT_NEAR(B[size_t(10) * size_t(im.width) + 29].x, p->total_reflectance().x, 1e-5);
    }
}

// [SECTION] Frames
// A plane lit straight from above, seen at an angle: every pixel's radiosity is R_total times its
// irradiance, on both devices (the blur of a uniform irradiance, with the plane's edges and its
// depth changing across the image).
TEST(TranslucencySeparable, APlaneUnderUniformLightLeavesAsTheAlbedoOnBothDevices) {
    Workbench wb;
    Scene s = default_scene("translucency");
    apply_set(s, "geometry.type", "plane");
    apply_set(s, "geometry.resolution", "8");
    apply_set(s, "translucency.method", "separable");
    apply_set(s, "translucency.material", "marble");
    apply_set(s, "translucency.mm_per_unit", "20");
    apply_set(s, "light.direction", "0,0");
    apply_set(s, "effects.environment", "false");
    apply_set(s, "camera.orbit", "35,-70");
    const double A = Dipole(measured_material("marble").medium).total_reflectance().y;
    const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 96, 80, {"irradiance", "radiosity"});
    for (const Frame* f : {&cpu, &gpu}) {
        size_t covered = 0;
        for (int y = 0; y < f->height; ++y)
            for (int x = 0; x < f->width; ++x) {
                if (!cpu.coverage.covered(size_t(y) * size_t(f->width) + size_t(x)) || cpu.coverage.edge[size_t(y) * size_t(f->width) + size_t(x)]) continue;
                const float E = f->aov("irradiance").at(x, y)[1], B = f->aov("radiosity").at(x, y)[1];
                ASSERT_GT(E, 0.5f);
                ASSERT_NEAR(B / E, A, 1e-4 * A) << (f == &cpu ? "cpu " : "gpu ") << x << "," << y;
                ++covered;
            }
        EXPECT_GT(covered, 1000u);
    }
}

TEST(TranslucencySeparable, CpuAndGpuAgreeOnEveryAov) {
    Workbench wb;
    const Scene s = small_sphere();
    const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 160, 120);
    EXPECT_GT(max_value(cpu.aov("radiance")), 0.05);
    EXPECT_GT(max_value(gpu.aov("radiance")), 0.05);
    test::expect_frames_agree(s, cpu, gpu, {"radiance", "normal", "irradiance", "radiosity", "local", "exitance"});
    // No vertex factors: the global part is 0, the whole radiosity the blur's.
    for (const Frame* f : {&cpu, &gpu}) test::expect_all_zero(*f, "global");
}

// The method reads the material and the shadows and runs none of the atlas and vertex pipeline's
// stages; its kernel's keys rerun no stage; the truth is the technique's (its key does not read
// the method); the pipeline's own keys are errors under it; texture mode has no screen to blur in.
TEST(TranslucencySeparable, RunsNoStageOfThePipelineAndSharesTheTruth) {
    Workbench wb;
    Scene s = small_sphere();
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 64;
    const RenderResult first = wb.render(s, req);
    for (const StageName& st : std::vector<StageName>{stages::mesh, stages::atlas, stages::kernels, stages::factors, stages::blend, stages::gather, stages::albedo})
        EXPECT_EQ(first.eval.run(st, 0), nullptr) << st;
    const std::string truth_key = truth_cache_key(version_string(), s, 64, 64, 1);
    apply_set(s, "translucency.separable_taps", "31");
    apply_set(s, "translucency.separable_profile", "burley");
    const RenderResult second = wb.render(s, req);
    for (const StageRun& r : second.eval.runs) EXPECT_NE(r.status, StageStatus::Ran) << r.name;
    EXPECT_EQ(truth_cache_key(version_string(), s, 64, 64, 1), truth_key);
    EXPECT_GT(std::abs(max_value(second.frame.aov("radiance")) - max_value(first.frame.aov("radiance"))), 1e-5);
    Scene bad = small_sphere();
    apply_set(bad, "translucency.veins", "0.5");
    EXPECT_THROW(check_set_used(bad, "translucency.veins"), InputError);
    Scene texture = small_sphere();
    apply_set(texture, "camera.mode", "texture");
    EXPECT_THROW(wb.render(texture, req), InputError);
}

// Hard cases: tiny and huge objects against the diffusion length (a kernel far below a pixel, or
// hundreds of pixels wide), a coarse mesh: finite on both devices, and lit.
TEST(TranslucencySeparable, NoNanAtSmallAndLargeScaleOnEitherDevice) {
    Workbench wb;
    for (const char* mm : {"0.05", "10", "5000"}) {
        SCOPED_TRACE(mm);
        Scene s = small_sphere();
        apply_set(s, "geometry.resolution", "6");
        apply_set(s, "translucency.mm_per_unit", mm);
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 64, 64);
        for (const Frame* f : {&cpu, &gpu})
            for (const auto& [name, img] : f->aovs)
                for (float v : img.data) ASSERT_TRUE(std::isfinite(v)) << name;
        EXPECT_GT(max_value(cpu.aov("radiance")), 0.0);
        EXPECT_GT(max_value(gpu.aov("radiance")), 0.0);
    }
}
