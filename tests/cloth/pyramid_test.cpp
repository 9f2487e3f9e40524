// The mip levels of a BRDF array (core/cloth/pyramid.h): level counts, entries that reproduce
// uniform and two-material grids, frames, cancellation.
#include "core/cloth/pyramid.h"
#include "core/cloth/stages.h"
#include "core/cloth/acquire.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
std::vector<dvec3> hemisphere(int n, double z_min = 0.02) { return hemisphere_directions(n, z_min); }

Lafortune one_lobe(dvec3 kd, dvec3 Cxy, dvec3 Cz, dvec3 n) {
    Lafortune L;
    L.kd = kd;
    LafortuneLobe l;
    l.Cx = l.Cy = Cxy, l.Cz = Cz, l.n = n;
    L.lobes = {l};
    return L;
}

// A res × res grid whose point (x, y) reflects like `brdf(x, y)` in the pattern frame (normal +z).
SampleGrid grid_of(int res, int lights, int views, const std::function<Lafortune(int, int)>& brdf) {
    SampleGrid g;
    g.res = res;
    g.views = hemisphere(views, 0.05);
    const std::vector<dvec3> ls = hemisphere(lights, 0.05);
    for (size_t v = 0; v < g.views.size(); ++v)
        for (const dvec3& l : ls) g.l.push_back(l), g.v.push_back(g.views[v]), g.view_of.push_back(int(v));
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            const Lafortune L = brdf(x, y);
            std::vector<dvec3> f;
            for (size_t i = 0; i < g.l.size(); ++i) f.push_back(L.f(g.l[i], g.v[i]));
            g.f.push_back(f);
            g.normal.push_back(dvec3(0, 0, 1)), g.tangent.push_back(dvec3(1, 0, 0));
        }
    return g;
}
}  // namespace

TEST(BrdfPyramid, LevelsHalveTheGridDownToOneEntry) {
    const Lafortune A = one_lobe(dvec3(0.1, 0.05, 0.02), dvec3(-0.9), dvec3(0.95), dvec3(8.0));
    const SampleGrid g = grid_of(8, 12, 12, [&](int, int) { return A; });
    FitOptions o;
    o.lobes = 1;
    const BrdfPyramid p = fit_pyramid(g, o);
    ASSERT_EQ(p.level.size(), 4u);  // 8, 4, 2, 1
    EXPECT_EQ(p.count(), 64u + 16u + 4u + 1u);
    // A uniform grid: every entry is the same BRDF (to 3 significant digits), its table 1.
    for (const auto& level : p.level)
        for (const ClothBrdf& b : level)
            for (size_t i = 0; i < g.l.size(); i += 7) {
                const dvec3 a = b.f(g.l[i], g.v[i]), t = A.f(g.l[i], g.v[i]);
                for (int c = 0; c < 3; ++c) ASSERT_NEAR(a[c], t[c], 5e-4 * t[c]);
            }
}

// Left half one material, right half another: entries inside a half are that half's material;
// the top entry is their mean, which two lobes represent exactly (each lobe scaled by 1/2).
TEST(BrdfPyramid, CoarseEntriesFitTheMeanOfTheirBlock) {
    const Lafortune A = one_lobe(dvec3(0.10), dvec3(-0.9), dvec3(0.95), dvec3(10.0));
    const Lafortune B = one_lobe(dvec3(0.02), dvec3(0.7), dvec3(0.8), dvec3(3.0));
    const SampleGrid g = grid_of(4, 16, 16, [&](int x, int) { return x < 2 ? A : B; });
    FitOptions o;
    o.lobes = 2;
    o.lookup_table = false;
    const BrdfPyramid p = fit_pyramid(g, o);
    ASSERT_EQ(p.level.size(), 3u);
    const ClothBrdf& left = p.level[1][0];
    const ClothBrdf& right = p.level[1][1];
    const ClothBrdf& top = p.level[2][0];
    for (size_t i = 0; i < g.l.size(); ++i) {
        const dvec3 a = A.f(g.l[i], g.v[i]), b = B.f(g.l[i], g.v[i]), m = 0.5 * (a + b);
        ASSERT_NEAR(left.f(g.l[i], g.v[i]).x, a.x, 5e-4 * a.x);
        ASSERT_NEAR(right.f(g.l[i], g.v[i]).x, b.x, 5e-4 * b.x);
        ASSERT_NEAR(top.f(g.l[i], g.v[i]).x, m.x, 1e-3 * m.x);
    }
}

// Points whose surface is tilted (normal 17 degrees off the pattern's, tangent along x): their
// reflectance is a lobe about the tilted normal, foreshortened by it (radiance = f cos θ̂_l).
// The entry works in its averaged frame, so the fit finds that lobe.
TEST(BrdfPyramid, EntriesWorkInTheirAveragedFrame) {
    const Lafortune A = one_lobe(dvec3(0.05), dvec3(-0.9), dvec3(0.95), dvec3(6.0));
    const dvec3 n = glm::normalize(dvec3(0.3, 0.0, 1.0));
    const glm::dmat3 T = local_frame(n, dvec3(1, 0, 0));
    SampleGrid g = grid_of(2, 16, 16, [&](int, int) { return A; });
    // Stored as acquired: f_r relative to the fabric's normal, f_r cos θ_l = radiance.
    for (auto& f : g.f)
        for (size_t i = 0; i < f.size(); ++i) f[i] = A.f(T * g.l[i], T * g.v[i]) * std::max((T * g.l[i]).z, 0.0) / g.l[i].z;
    for (auto& x : g.normal) x = n;
    FitOptions o;
    o.lobes = 1;
    o.lookup_table = false;
    const BrdfPyramid p = fit_pyramid(g, o);
    const glm::dmat3 F = p.frame[1][0];
    EXPECT_NEAR(glm::length(F * n - dvec3(0, 0, 1)), 0.0, 1e-12);
    EXPECT_NEAR(glm::length(F * glm::normalize(dvec3(1, 0, -0.3)) - dvec3(1, 0, 0)), 0.0, 1e-12);
    size_t checked = 0;
    for (size_t i = 0; i < g.l.size(); ++i) {
        if ((F * g.l[i]).z <= 0.05) continue;  // below the entry's horizon: left out of the fit
        const double want = A.f(T * g.l[i], T * g.v[i]).x, got = p.level[1][0].f(F * g.l[i], F * g.v[i]).x;
        ASSERT_NEAR(got, want, 5e-4 * want);
        ++checked;
    }
    EXPECT_GT(checked, 200u);
}

TEST(BrdfPyramid, ReportsProgressAndCancels) {
    const Lafortune A = one_lobe(dvec3(0.1), dvec3(-0.9), dvec3(0.95), dvec3(8.0));
    const SampleGrid g = grid_of(8, 8, 8, [&](int, int) { return A; });
    FitOptions o;
    o.lobes = 1;
    double last = 0.0;
    fit_pyramid(g, o, [&](const std::string& what, double f) {
        EXPECT_EQ(what, "cloth.fit");
        last = std::max(last, f);
    });
    EXPECT_EQ(last, 1.0);
    std::atomic<bool> cancel{true};
    EXPECT_THROW(fit_pyramid(g, o, {}, &cancel), Cancelled);
}

TEST(BrdfPyramid, BadGridsNameTheKey) {
    SampleGrid g = grid_of(4, 4, 4, [](int, int) { return Lafortune{}; });
    g.res = 3;
    try {
        fit_pyramid(g, FitOptions{});
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.spatial"), std::string::npos);
    }
    g.res = 4;
    g.f.pop_back();
    EXPECT_THROW(fit_pyramid(g, FitOptions{}), InputError);
}
