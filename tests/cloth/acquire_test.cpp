// Virtual acquisition (core/cloth/acquire.h): a Lambertian slab gives ρ/π everywhere; alpha
// follows a weave's holes; stitches give finite samples that the pyramid fits.
#include "core/cloth/acquire.h"
#include "core/cloth/stages.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
// A closed box [lo, hi], each face its own four vertices (exact normals), in `color`.
StitchMesh slab(vec3 lo, vec3 hi, vec3 color, vec2 tile) {
    StitchMesh s;
    TriMesh& m = s.mesh;
    auto quad = [&](vec3 a, vec3 b, vec3 c, vec3 d, vec3 n) {
        const uint32_t o = uint32_t(m.position.size());
        for (const vec3& p : {a, b, c, d}) m.position.push_back(p), m.normal.push_back(n), m.tangent.push_back(vec3(1, 0, 0));
        m.index.insert(m.index.end(), {o, o + 1, o + 2, o, o + 2, o + 3});
    };
    quad({lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}, {0, 0, 1});
    quad({lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, lo.y, lo.z}, {0, 0, -1});
    quad({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z}, {0, -1, 0});
    quad({lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {hi.x, hi.y, hi.z}, {hi.x, hi.y, lo.z}, {0, 1, 0});
    quad({lo.x, lo.y, lo.z}, {lo.x, lo.y, hi.z}, {lo.x, hi.y, hi.z}, {lo.x, hi.y, lo.z}, {-1, 0, 0});
    quad({hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z}, {1, 0, 0});
    s.color.assign(m.position.size(), color);
    s.tile = tile;
    s.lo = vec3(0.f, 0.f, lo.z), s.hi = vec3(tile, hi.z);
    return s;
}
}  // namespace

// Nothing above a flat Lambertian top: no shadow, no bounce, f_r = ρ/π at every pair.
TEST(ClothAcquire, ALambertianSlabGivesRhoOverPiEverywhere) {
    const vec3 rho(0.5f, 0.25f, 1.0f);
    const StitchMesh s = slab(vec3(-3.f, -3.f, -0.2f), vec3(4.f, 4.f, 0.f), rho, vec2(1.f));
    AcquireParams p;
    p.spatial = 4;
    p.directions = 12;
    p.visibility_rays = 16;
    const SampleGrid g = acquire(s, p);
    ASSERT_EQ(g.f.size(), 16u);
    ASSERT_EQ(g.l.size(), 144u);
    for (size_t pt = 0; pt < g.f.size(); ++pt) {
        for (size_t i = 0; i < g.l.size(); ++i)
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(g.f[pt][i][c], rho[c] / M_PI, 1e-5) << pt << " " << i;
        for (double a : g.alpha[pt]) ASSERT_EQ(a, 1.0);
        EXPECT_NEAR(glm::length(g.normal[pt] - dvec3(0, 0, 1)), 0.0, 1e-6);
    }
    // The fit of such samples is the diffuse term alone.
    FitOptions o;
    o.lobes = 1;
    const BrdfPyramid pyr = fit_pyramid(g, o);
    const dvec3 f = pyr.level.back()[0].f(dvec3(0, 0, 1), glm::normalize(dvec3(1, 0, 1)));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[c], rho[c] / M_PI, 1e-4);
}

// A plain weave of thin threads (radius 0.12, one apart): seen from straight above, a point is
// covered when it lies within about a radius of a thread's axis, else it is a hole.
TEST(ClothAcquire, AlphaFollowsTheWeavesHoles) {
    StitchParams sp;
    sp.stitch = "weave";
    const StitchMesh s = build_stitch_mesh(make_stitch(sp), 48);
    AcquireParams p;
    p.spatial = 32;
    p.directions = 16;
    p.visibility_rays = 0;
    const SampleGrid g = acquire(s, p);
    // The most vertical view (cos θ ≈ 0.97): the hit point lies within 0.06 of the point.
    size_t agree = 0, counted = 0, holes = 0;
    for (int b = 0; b < 32; ++b)
        for (int a = 0; a < 32; ++a) {
            const float x = (float(a) + 0.5f) / 32.f * s.tile.x, y = (float(b) + 0.5f) / 32.f * s.tile.y;
            const float dx = std::abs(x - (std::floor(x) + 0.5f)), dy = std::abs(y - (std::floor(y) + 0.5f));
            const float d = std::min(dx, dy);  // to the nearest thread axis in xy
            if (std::abs(d - 0.12f) < 0.07f) continue;  // too close to the edge to call
            const bool covered = d < 0.12f;
            ++counted;
            const double alpha = g.alpha[size_t(b) * 32 + size_t(a)][0];
            holes += alpha == 0.0;
            agree += (alpha == 1.0) == covered;
        }
    EXPECT_GT(counted, 500u);
    EXPECT_EQ(agree, counted);
    EXPECT_GT(holes, 300u);
    EXPECT_LT(holes, counted);
    // Holes close at grazing views: the mean alpha grows with θ.
    double top = 0.0, grazing = 0.0;
    for (const auto& a : g.alpha) top += a[0], grazing += a.back();
    EXPECT_GT(grazing, top);
}

TEST(ClothAcquire, StitchSamplesAreFiniteAndFit) {
    StitchParams sp;
    sp.stitch = "knit";
    const StitchMesh s = build_stitch_mesh(make_stitch(sp), 24);
    AcquireParams p;
    p.spatial = 4;
    p.directions = 8;
    p.visibility_rays = 16;
    double last = 0.0;
    const SampleGrid g = acquire(s, p, [&](const std::string& what, double f) {
        EXPECT_EQ(what, "cloth.acquire");
        last = f;
    });
    EXPECT_EQ(last, 1.0);
    double sum = 0.0;
    for (const auto& f : g.f)
        for (const dvec3& x : f) {
            ASSERT_TRUE(std::isfinite(x.x) && x.x >= 0.0);
            sum += x.x;
        }
    EXPECT_GT(sum, 0.0);
    FitOptions o;
    o.lobes = 1;
    const BrdfPyramid pyr = fit_pyramid(g, o);
    EXPECT_EQ(pyr.count(), 16u + 4u + 1u);
    for (const auto& l : pyr.report)
        for (const FitReport& r : l) EXPECT_TRUE(std::isfinite(r.rms));
    std::atomic<bool> cancel{true};
    EXPECT_THROW(acquire(s, p, {}, &cancel), Cancelled);
}

TEST(ClothAcquire, BadParametersNameTheirKey) {
    const StitchMesh s = slab(vec3(-3.f, -3.f, -0.2f), vec3(4.f, 4.f, 0.f), vec3(0.5f), vec2(1.f));
    AcquireParams p;
    p.spatial = 12;
    try {
        acquire(s, p);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.spatial"), std::string::npos);
    }
    p.spatial = 4;
    p.directions = 2;
    try {
        acquire(s, p);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.directions"), std::string::npos);
    }
}

// The acquisition's bounces (AcquireParams::bounces): none is the direct light alone, each adds
// light, less each time (the gather is a contraction: ρ < 1 and rays escape), and the series has
// converged to a part in a thousand by 32; a count out of range names the key.
TEST(ClothAcquire, BouncesAddLightThatConverges) {
    StitchParams sp;
    sp.stitch = "knit";
    const StitchMesh s = build_stitch_mesh(make_stitch(sp), 24);
    AcquireParams p;
    p.spatial = 4;
    p.directions = 8;
    p.visibility_rays = 16;
    const auto mean_f = [&](int bounces) {
        p.bounces = bounces;
        const SampleGrid g = acquire(s, p);
        double sum = 0;
        size_t n = 0;
        for (const auto& pt : g.f)
            for (const dvec3& f : pt) sum += f.x + f.y + f.z, ++n;
        return sum / double(n);
    };
    std::vector<double> m;
    for (int b : {0, 1, 2, 3, 4, 8, 16, 32}) m.push_back(mean_f(b));
    for (size_t i = 1; i < m.size(); ++i) EXPECT_GT(m[i], m[i - 1]) << "bounce step " << i;
    for (size_t i = 2; i < 5; ++i) EXPECT_LT(m[i] - m[i - 1], m[i - 1] - m[i - 2]) << "each bounce adds less than the one before";
    EXPECT_LT(m[7] - m[6], 1e-3 * m[7]);
    EXPECT_GT(m[7] - m[1], 0.01 * m[7]) << "the bounces beyond the paper's one matter on a knit";
    // No bounce: the same bytes as no visibility rays.
    p.bounces = 0;
    const SampleGrid a = acquire(s, p);
    p.bounces = 1;
    p.visibility_rays = 0;
    const SampleGrid b = acquire(s, p);
    EXPECT_EQ(a.f, b.f);
    p.bounces = 65;
    try {
        acquire(s, p);
        FAIL() << "65 bounces were accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.bounces"), std::string::npos) << e.what();
    }
}
