// Curved-base importance on the GPU (gpu/microgeom/importance_gpu.h, importance.comp) against the
// CPU reference (core/microgeom/curvature.cpp compute_importance), from the same S_i.
//
// Agreement: both sides evaluate the same float expressions (the GPU's `precise`, so no FMA
// contraction), except the bent solid angles (double on the CPU, a size-relative float determinant
// on the GPU), the per-texel sums (double / compensated float) and the float atan. So for each
// entry of I and w, |gpu - cpu| / max(1e-3, |cpu|) <= 1e-4 for >= 99.9% of entries (an
// orientation within rounding of 0 may flip a triangle between "hit-only" and "folded" on one side,
// which moves the I of its corners by a whole triangle: those are the allowed outliers), and
// folded flags agree on >= 99.9% of texels. Every GPU texel's weights sum to 1 within 1e-5.
// Measured worst errors and mismatch counts are printed.
#include "core/microgeom/curvature.h"
#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/microgeom/importance_gpu.h"

#include "agreement.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

// A flat field with one tall, one-texel spike: extreme slopes and long hit offsets around it.
Heightfield spike(int res, bool periodic) {
    Heightfield hf;
    hf.width = hf.height = res;
    hf.periodic = periodic;
    hf.h.assign(size_t(res) * size_t(res), 0.f);
    hf.h[hf.index(res / 2, res / 2)] = 0.75f * float(res);
    hf.albedo.assign(hf.h.size(), vec3(0.8f));
    return hf;
}


struct Agreement {
    size_t entries = 0, I_off = 0, w_off = 0;  // entries beyond 1e-4 relative
    size_t texels = 0, folded_diff = 0;
    double I_worst = 0, w_worst = 0, sum_worst = 0;  // worst relative errors; worst |sum w - 1| (GPU)
};

double relative(float gpu, float cpu) { return std::fabs(double(gpu) - double(cpu)) / std::max(1e-3, std::fabs(double(cpu))); }

Agreement compare(const Importance& cpu, const Importance& gpu) {
    Agreement a;
    EXPECT_EQ(gpu.width, cpu.width);
    EXPECT_EQ(gpu.height, cpu.height);
    EXPECT_EQ(gpu.count, cpu.count);
    EXPECT_EQ(gpu.I.size(), cpu.I.size());
    EXPECT_EQ(gpu.w.size(), cpu.w.size());
    EXPECT_EQ(gpu.folded.size(), cpu.folded.size());
    if (gpu.I.size() != cpu.I.size() || gpu.w.size() != cpu.w.size() || gpu.folded.size() != cpu.folded.size()) return a;
    // A bent base always has weights: two empty results would agree about nothing.
    EXPECT_EQ(cpu.I.size(), size_t(cpu.width) * size_t(cpu.height) * size_t(cpu.count));
    EXPECT_FALSE(cpu.empty()) << "the CPU result is empty: nothing to compare";
    a.entries = cpu.I.size();
    a.texels = cpu.folded.size();
    for (size_t k = 0; k < a.entries; ++k) {
        EXPECT_TRUE(std::isfinite(gpu.I[k]) && gpu.I[k] > 0.f) << "I entry " << k << " = " << gpu.I[k];
        EXPECT_TRUE(std::isfinite(gpu.w[k]) && gpu.w[k] >= 0.f) << "w entry " << k << " = " << gpu.w[k];
        const double eI = relative(gpu.I[k], cpu.I[k]), ew = relative(gpu.w[k], cpu.w[k]);
        a.I_worst = std::max(a.I_worst, eI);
        a.w_worst = std::max(a.w_worst, ew);
        a.I_off += !(eI <= 1e-4);
        a.w_off += !(ew <= 1e-4);
    }
    const size_t N = size_t(cpu.count);
    for (size_t p = 0; p < a.texels; ++p) {
        double sum = 0;
        for (size_t j = 0; j < N; ++j) sum += double(gpu.w[p * N + j]);
        a.sum_worst = std::max(a.sum_worst, std::fabs(sum - 1.0));
        a.folded_diff += gpu.folded[p] != cpu.folded[p];
    }
    EXPECT_EQ(gpu.folded_count, size_t(std::count(gpu.folded.begin(), gpu.folded.end(), uint8_t(1))));
    return a;
}

void expect_agreement(const Agreement& a, const std::string& what) {
    const double n = double(a.entries), t = double(a.texels);
    EXPECT_LE(double(a.I_off), 1e-3 * n) << what << ": " << a.I_off << " of " << a.entries << " I differ by more than 1e-4";
    EXPECT_LE(double(a.w_off), 1e-3 * n) << what << ": " << a.w_off << " of " << a.entries << " w differ by more than 1e-4";
    EXPECT_LE(double(a.folded_diff), 1e-3 * t) << what << ": " << a.folded_diff << " of " << a.texels << " folded flags differ";
    EXPECT_LT(a.sum_worst, 1e-5) << what;
}

void print(const Agreement& a, const std::string& what, const Importance& cpu) {
    std::printf("%-34s I: worst %.1e, %zu/%zu > 1e-4 | w: worst %.1e, %zu > 1e-4 | |sum w - 1| <= %.1e | folded %zu (cpu), %zu differ\n",
                what.c_str(), a.I_worst, a.I_off, a.entries, a.w_worst, a.w_off, a.sum_worst, cpu.folded_count, a.folded_diff);
}

std::string label(const char* name, int res, bool periodic, int N, float bu, float bv) {
    char s[96];
    std::snprintf(s, sizeof s, "%s %d%s N=%d (%g, %g)", name, res, periodic ? "" : " np", N, double(bu), double(bv));
    return s;
}

}  // namespace

TEST(ImportanceGpu, AgreesWithTheCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    struct Case {
        const char* name;
        int res;
    };
    const DirectionSet dirs = make_direction_set(100);
    const float bends[][2] = {{60.f, 30.f}, {60.f, -30.f}, {-60.f, 30.f}, {-60.f, -30.f}, {120.f, 0.f}};
    for (const Case& c : {Case{"triangles", 48}, Case{"bricks", 64}, Case{"gaussian", 64}})
        for (bool periodic : {true, false}) {
            const Heightfield hf = test::procedural_field(c.name, c.res, periodic);
            const Visibility vis = compute_visibility(hf, dirs);
            for (const auto& bend : bends) {
                const Bending b = Bending::from_degrees(bend[0], bend[1], hf.width, hf.height);
                const Importance cpu = compute_importance(hf, dirs, vis, b);
                const Importance gpu = gpu::compute_importance_gpu(hf, dirs, vis, b);
                const std::string what = label(c.name, c.res, periodic, dirs.size(), bend[0], bend[1]);
                const Agreement a = compare(cpu, gpu);
                print(a, what, cpu);
                expect_agreement(a, what);
            }
        }
}

TEST(ImportanceGpu, ZeroCurvatureGivesAnEmptyResult) {
    // As the CPU: no weights (the flat quadrature), no GL needed.
    const Heightfield hf = test::procedural_field("triangles", 16, true);
    const DirectionSet dirs = make_direction_set(32);
    const Visibility vis = compute_visibility(hf, dirs);
    const Importance imp = gpu::compute_importance_gpu(hf, dirs, vis, Bending{});
    EXPECT_TRUE(imp.empty());
    EXPECT_TRUE(imp.I.empty());
    EXPECT_TRUE(imp.folded.empty());
    EXPECT_EQ(imp.folded_count, 0u);
    EXPECT_EQ(imp.width, 16);
    EXPECT_EQ(imp.height, 16);
    EXPECT_EQ(imp.count, 32);
    EXPECT_EQ(imp.importance(0, 0), 1.f);
}

TEST(ImportanceGpu, HardCasesStayFinite) {
    // A one-texel spike (slopes of 24 texels per texel, hits far away in every direction) and a
    // coarse N = 16 triangulation, with bends strong enough to fold: everything finite, I > 0,
    // w >= 0 summing to 1, and still the CPU's result.
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    struct Case {
        Heightfield hf;
        int N;
        const char* name;
    };
    std::vector<Case> cases;
    for (bool periodic : {true, false}) {
        cases.push_back({spike(32, periodic), 100, "spike"});
        cases.push_back({spike(32, periodic), 16, "spike"});
        cases.push_back({test::procedural_field("bricks", 48, periodic), 16, "bricks"});
        cases.push_back({test::procedural_field("gaussian", 48, periodic), 16, "gaussian"});
    }
    const float bends[][2] = {{360.f, 0.f}, {-360.f, -360.f}, {120.f, -120.f}, {1e-3f, 0.f}};
    for (const Case& c : cases) {
        const DirectionSet dirs = make_direction_set(c.N);
        const Visibility vis = compute_visibility(c.hf, dirs);
        for (const auto& bend : bends) {
            const Bending b = Bending::from_degrees(bend[0], bend[1], c.hf.width, c.hf.height);
            const Importance cpu = compute_importance(c.hf, dirs, vis, b);
            const Importance gpu = gpu::compute_importance_gpu(c.hf, dirs, vis, b);
            const std::string what = label(c.name, c.hf.width, c.hf.periodic, c.N, bend[0], bend[1]);
            const Agreement a = compare(cpu, gpu);  // finiteness, I > 0, w >= 0 inside
            print(a, what, cpu);
            expect_agreement(a, what);
        }
    }
}

TEST(ImportanceGpu, ReportsProgressAndCancels) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    // 44 rows in batches of 5: the last batch is short.
    const Heightfield hf = test::procedural_field("bricks", 44, false);
    const DirectionSet dirs = make_direction_set(64);
    const Visibility vis = compute_visibility(hf, dirs);
    const Bending b = Bending::from_degrees(60.f, -30.f, hf.width, hf.height);
    std::vector<double> fractions;
    const Importance imp = gpu::compute_importance_gpu(hf, dirs, vis, b, [&](double f) { fractions.push_back(f); });
    ASSERT_GT(fractions.size(), 1u);
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
    EXPECT_GT(fractions.front(), 0.0);
    EXPECT_EQ(fractions.back(), 1.0);
    expect_agreement(compare(compute_importance(hf, dirs, vis, b), imp), "bricks 44 np N=64 (60, -30)");
    // A throwing callback cancels; the next call works and agrees with the first.
    struct Cancelled {};
    EXPECT_THROW(gpu::compute_importance_gpu(hf, dirs, vis, b, [](double) { throw Cancelled{}; }), Cancelled);
    const Importance again = gpu::compute_importance_gpu(hf, dirs, vis, b);
    EXPECT_EQ(again.I, imp.I);
    EXPECT_EQ(again.w, imp.w);
    EXPECT_EQ(again.folded, imp.folded);
}

TEST(ImportanceGpu, RejectsMismatchedVisibility) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = test::procedural_field("bricks", 16, true);
    const DirectionSet dirs = make_direction_set(32);
    const Visibility vis = compute_visibility(test::procedural_field("bricks", 24, true), dirs);
    EXPECT_THROW(gpu::compute_importance_gpu(hf, dirs, vis, Bending{0.01f, 0.f}), std::invalid_argument);
}

TEST(ImportanceGpu, Bricks128AgreesWithTheCpu) {
    // bricks 128^2, N = 100, bend (60, -30): the bench's field size, one run each.
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = test::procedural_field("bricks", 128, true);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    const Bending b = Bending::from_degrees(60.f, -30.f, hf.width, hf.height);
    const Importance cpu = compute_importance(hf, dirs, vis, b), gpu = gpu::compute_importance_gpu(hf, dirs, vis, b);
    const Agreement a = compare(cpu, gpu);
    print(a, "bricks 128 N=100 (60, -30)", cpu);
    expect_agreement(a, "bricks 128");
}
