// Shadow ellipses fitted on the GPU (gpu/microgeom/ellipse_gpu.h, ellipse_fit.comp) against the
// CPU reference fit_ellipses (core/microgeom/ellipse.h).
//
// Agreement: both fits see the same points and run the same search, but the GPU's cos, sin, exp,
// log and atan may differ from libm in the last bits and its argmax breaks 1e-6 margin ties
// differently from the CPU's sequential sweep, so a near-tie can send the pattern search
// elsewhere. Stated for every field below: the two maps classify the texels' own points (hard
// test ellipse_visibility(e, w, 0) >= 1/2) the same way for >= 99.5% of all (texel, point)
// pairs, and the GPU fit's score (correctly classified points) is never below the CPU's by more
// than 1 on >= 99% of texels. Special cases (nothing lit, everything lit) are exact.
// Measured on llvmpipe (Mesa 22.3, 2 cores; printed by each test): on every field here (bricks,
// gaussian, triangles 64x64 and bricks 128x128 at N = 100, the bent bricks and gaussian, N = 16,
// N = 1024, a single spike) 100% of the pairs classify alike and no texel's score is below the
// CPU's; 13-97% of the ellipses are bit-identical. Timing is `mesolab bench microgeom`.
#include "core/microgeom/ellipse.h"
#include "gpu/context.h"
#include "gpu/microgeom/ellipse_gpu.h"

#include "agreement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {


bool well_formed(const Ellipse& e) {
    return std::isfinite(e.centre.x) && std::isfinite(e.centre.y) && std::isfinite(e.angle) && std::isfinite(e.a) &&
           std::isfinite(e.b) && e.a >= e.b && e.b > 0.f && e.angle >= 0.f && e.angle < kPi;
}

bool same(const Ellipse& a, const Ellipse& b) { return std::memcmp(&a, &b, sizeof(Ellipse)) == 0; }

// The points a texel's fit sees (ellipse.h): lit = no hit, unbent; the others at their bent
// direction, kept above the base plane (Bending{}: the upper directions, unbent).
struct Point {
    vec3 w;
    bool lit;
};
std::vector<Point> texel_points(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b, int x, int y) {
    std::vector<Point> P;
    for (int j = 0; j < dirs.size(); ++j) {
        const bool lit = vis.at(j, x, y) == Visibility::kNoHit;
        const vec3 w = lit || b.zero() ? dirs.d[size_t(j)] : bent_direction(hf, dirs, vis, b, x, y, j);
        if (w.z > 0.f) P.push_back({w, lit});
    }
    return P;
}

struct Agreement {
    size_t pairs = 0, same_class = 0;   // (texel, point) pairs, classified alike by both maps
    size_t texels = 0, within_one = 0;  // texels, with GPU score >= CPU score - 1
    size_t identical = 0;               // texels with bit-identical ellipses
    int worst = 0;                      // min over texels of GPU score - CPU score
    double cpu_score = 0, gpu_score = 0;  // mean fraction of points correctly classified
    bool well_formed = true;
    double class_fraction() const { return pairs ? double(same_class) / double(pairs) : 1.0; }
    double score_fraction() const { return texels ? double(within_one) / double(texels) : 1.0; }
};

Agreement compare(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b, const EllipseMap& cpu,
                  const EllipseMap& gpu) {
    Agreement A;
    EXPECT_EQ(gpu.width, cpu.width);
    EXPECT_EQ(gpu.height, cpu.height);
    EXPECT_EQ(gpu.edge, cpu.edge);
    if (gpu.e.size() != cpu.e.size()) {
        ADD_FAILURE() << "map sizes differ";
        return A;
    }
    for (int y = 0; y < hf.height; ++y)
        for (int x = 0; x < hf.width; ++x) {
            const Ellipse &ec = cpu.at(x, y), &eg = gpu.at(x, y);
            A.well_formed = A.well_formed && well_formed(eg);
            int sc = 0, sg = 0;
            const std::vector<Point> P = texel_points(hf, dirs, vis, b, x, y);
            for (const Point& p : P) {
                const bool in_c = ellipse_visibility(ec, p.w, 0.f) >= 0.5f, in_g = ellipse_visibility(eg, p.w, 0.f) >= 0.5f;
                A.same_class += in_c == in_g ? 1 : 0;
                sc += in_c == p.lit ? 1 : 0;
                sg += in_g == p.lit ? 1 : 0;
            }
            A.pairs += P.size();
            ++A.texels;
            A.within_one += sg >= sc - 1 ? 1 : 0;
            A.identical += same(ec, eg) ? 1 : 0;
            A.worst = std::min(A.worst, sg - sc);
            if (!P.empty()) {
                A.cpu_score += double(sc) / double(P.size());
                A.gpu_score += double(sg) / double(P.size());
            }
        }
    A.cpu_score /= double(std::max<size_t>(1, A.texels));
    A.gpu_score /= double(std::max<size_t>(1, A.texels));
    return A;
}

void report(const std::string& what, const Agreement& A) {
    std::printf("[ ellipse gpu ] %s: same class %.3f%% of %zu (texel, point) pairs; GPU score >= CPU - 1 on %.3f%% of %zu "
                "texels (worst %+d); mean score CPU %.4f, GPU %.4f; bit-identical ellipses %.2f%%\n",
                what.c_str(), 100.0 * A.class_fraction(), A.pairs, 100.0 * A.score_fraction(), A.texels, A.worst, A.cpu_score,
                A.gpu_score, 100.0 * double(A.identical) / double(std::max<size_t>(1, A.texels)));
}

void expect_agreement(const Agreement& A) {
    EXPECT_TRUE(A.well_formed);
    EXPECT_GE(A.class_fraction(), 0.995);
    EXPECT_GE(A.score_fraction(), 0.99);
}


}  // namespace

// [SECTION] Agreement on the flat base
TEST(EllipseGpu, FlatFieldsAgreeWithTheCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const DirectionSet dirs = make_direction_set(100);
    for (const char* name : {"bricks", "gaussian", "triangles"}) {
        SCOPED_TRACE(name);
        const Heightfield hf = test::procedural_field(name, 64);
        const Visibility vis = compute_visibility(hf, dirs);
        const EllipseMap cpu = fit_ellipses(hf, dirs, vis);
        const EllipseMap gpu = gpu::fit_ellipses_gpu(hf, dirs, vis);
        const Agreement A = compare(hf, dirs, vis, Bending{}, cpu, gpu);
        report(std::string(name) + " 64x64, N = 100", A);
        expect_agreement(A);
    }
}

// [SECTION] Agreement on a curved base
TEST(EllipseGpu, CurvedBaseAgreesWithTheCpu) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const DirectionSet dirs = make_direction_set(100);
    for (const char* name : {"bricks", "gaussian"}) {
        SCOPED_TRACE(name);
        const Heightfield hf = test::procedural_field(name, 64);
        const Visibility vis = compute_visibility(hf, dirs);
        const Bending b = Bending::from_degrees(60.f, -30.f, hf.width, hf.height);
        const EllipseMap cpu = fit_ellipses(hf, dirs, vis, b);
        const EllipseMap gpu = gpu::fit_ellipses_gpu(hf, dirs, vis, b);
        const Agreement A = compare(hf, dirs, vis, b, cpu, gpu);
        report(std::string(name) + " 64x64, N = 100, bent (60, -30) degrees", A);
        expect_agreement(A);
    }
}

// [SECTION] Hard cases
TEST(EllipseGpu, AllZeroFieldIsTheAllLitCircle) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    Heightfield hf = test::procedural_field("flat", 16);
    std::fill(hf.h.begin(), hf.h.end(), 0.f);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    const EllipseMap cpu = fit_ellipses(hf, dirs, vis);
    const EllipseMap gpu = gpu::fit_ellipses_gpu(hf, dirs, vis);
    ASSERT_EQ(gpu.e.size(), cpu.e.size());
    const Ellipse circle{vec2(0.f), 0.f, 1.f + cpu.edge, 1.f + cpu.edge};
    for (size_t p = 0; p < gpu.e.size(); ++p) {
        ASSERT_TRUE(same(gpu.e[p], cpu.e[p])) << p;
        ASSERT_TRUE(same(gpu.e[p], circle)) << p;
    }
}

TEST(EllipseGpu, HardCases) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    struct Case {
        std::string name;
        Heightfield hf;
        int n;
    };
    Heightfield spike = test::procedural_field("flat", 32);
    spike.h[spike.index(16, 16)] = 12.f;
    std::vector<Case> cases{{"bricks 32x32, N = 16", test::procedural_field("bricks", 32), 16},
                            {"gaussian 32x32, N = 16", test::procedural_field("gaussian", 32), 16},
                            {"single spike 32x32, N = 100", spike, 100},
                            {"bricks 16x16, N = 1024", test::procedural_field("bricks", 16), 1024}};
    size_t special_total = 0;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const DirectionSet dirs = make_direction_set(c.n);
        const Visibility vis = compute_visibility(c.hf, dirs);
        for (const Bending b : {Bending{}, Bending::from_degrees(60.f, -30.f, c.hf.width, c.hf.height)}) {
            const EllipseMap cpu = fit_ellipses(c.hf, dirs, vis, b);
            const EllipseMap gpu = gpu::fit_ellipses_gpu(c.hf, dirs, vis, b);
            const Agreement A = compare(c.hf, dirs, vis, b, cpu, gpu);
            report(c.name + (b.zero() ? "" : ", bent"), A);
            expect_agreement(A);
            // Nothing lit and everything lit are decided exactly as on the CPU.
            size_t special = 0;
            for (size_t p = 0; p < cpu.e.size(); ++p)
                if (same(cpu.e[p], kEmptyEllipse) || (cpu.e[p].centre == vec2(0.f) && cpu.e[p].a == 1.f + cpu.edge && cpu.e[p].b == cpu.e[p].a)) {
                    ++special;
                    EXPECT_TRUE(same(gpu.e[p], cpu.e[p])) << p;
                }
            std::printf("[ ellipse gpu ]   %zu texels with nothing or everything lit, identical\n", special);
            special_total += special;
        }
    }
    EXPECT_GT(special_total, 0u) << "no texel with nothing or everything lit: the exact special cases were not compared";
}

TEST(EllipseGpu, TooManyPointsThrow) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = test::procedural_field("flat", 8);
    const DirectionSet dirs = make_direction_set(2500);  // about 1250 upper directions
    const Visibility vis = compute_visibility(hf, dirs);
    EXPECT_THROW(gpu::fit_ellipses_gpu(hf, dirs, vis), std::runtime_error);
    EXPECT_THROW(gpu::fit_ellipses_gpu(hf, dirs, vis, Bending::from_degrees(30.f, 0.f, 8, 8)), std::runtime_error);
}

TEST(EllipseGpu, ErrorsAndProgress) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = test::procedural_field("bricks", 16);
    const DirectionSet dirs = make_direction_set(64);
    const Visibility vis = compute_visibility(hf, dirs);
    Visibility wrong = vis;
    wrong.count = 63;
    EXPECT_THROW(gpu::fit_ellipses_gpu(hf, dirs, wrong), std::invalid_argument);
    EXPECT_THROW(gpu::fit_ellipses_gpu(hf, dirs, wrong, Bending::from_degrees(30.f, 0.f, 16, 16)), std::invalid_argument);
    std::vector<double> f;
    const EllipseMap map = gpu::fit_ellipses_gpu(hf, dirs, vis, {}, [&](double x) { f.push_back(x); });
    ASSERT_GE(f.size(), 2u);
    EXPECT_EQ(f.front(), 0.0);
    EXPECT_EQ(f.back(), 1.0);
    EXPECT_TRUE(std::is_sorted(f.begin(), f.end()));
    // Cancelling leaves the context usable; the same input gives the same map again.
    struct Cancel {};
    EXPECT_THROW(gpu::fit_ellipses_gpu(hf, dirs, vis, {}, [](double x) { if (x > 0.0) throw Cancel{}; }), Cancel);
    const EllipseMap again = gpu::fit_ellipses_gpu(hf, dirs, vis);
    ASSERT_EQ(again.e.size(), map.e.size());
    EXPECT_EQ(std::memcmp(again.e.data(), map.e.data(), map.bytes()), 0);
    // An empty field and no directions.
    Heightfield none;
    const Visibility no_vis = compute_visibility(none, dirs);
    EXPECT_TRUE(gpu::fit_ellipses_gpu(none, dirs, no_vis).e.empty());
    const DirectionSet no_dirs;
    const EllipseMap empty = gpu::fit_ellipses_gpu(hf, no_dirs, compute_visibility(hf, no_dirs));
    ASSERT_EQ(empty.e.size(), size_t(16 * 16)) << "no directions: one (empty) ellipse per texel";
    for (const Ellipse& e : empty.e) EXPECT_TRUE(same(e, kEmptyEllipse));
}

// [SECTION] The bench's size: bricks 128x128, N = 100
TEST(EllipseGpu, Bricks128AgreesWithTheCpu) {
    // Timing is `mesolab bench microgeom` (column "shadow (ellipse) precompute", GPU line).
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = test::procedural_field("bricks", 128);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    const EllipseMap cpu = fit_ellipses(hf, dirs, vis), gpu = gpu::fit_ellipses_gpu(hf, dirs, vis);
    const Agreement A = compare(hf, dirs, vis, Bending{}, cpu, gpu);
    report("bricks 128x128, N = 100", A);
    expect_agreement(A);
}
