// The microfacet sheen BRDF and its fit (core/cloth/sheen.h): the distribution is normalised, Λ
// is continuous where its two branches meet and the BRDF reciprocal; the fit recovers a sheen
// from its own noiseless samples exactly (every roughness, with and without a view table), and
// bad options and black samples are handled.
#include "app/workbench.h"
#include "core/cloth/sheen.h"
#include "core/cloth/stages.h"
#include "core/scene.h"
#include "support/frames.h"
#include "core/cloth/fit.h"
#include "core/cloth/acquire.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
PointSamples samples_of(const ClothBrdf& truth, const std::vector<dvec3>& lights, const std::vector<dvec3>& views) {
    std::vector<BrdfSample> s;
    for (const dvec3& v : views)
        for (const dvec3& l : lights) s.push_back({l, v, truth.f(l, v), 0, l.z});
    return group_by_view(std::move(s));
}
}  // namespace

// A small fabric (8 x 8 points, 12 x 12 directions) on a curtain lit from the front, fitted with
// the sheen (cloth.method = sheen).
Scene small_sheen_curtain() {
    Scene s = default_scene("cloth");
    apply_set(s, "cloth.method", "sheen");
    apply_set(s, "cloth.stitch_resolution", "24");
    apply_set(s, "cloth.spatial", "8");
    apply_set(s, "cloth.directions", "12");
    apply_set(s, "cloth.visibility_rays", "8");
    apply_set(s, "cloth.garment_resolution", "32");
    apply_set(s, "cloth.repeat", "4");
    apply_set(s, "camera.orbit", "80,-90");
    apply_set(s, "light.direction", "50,-60");
    apply_set(s, "light.intensity", "3");
    return s;
}

// ∫ D cos θ_h dω_h = 1: midpoint rule in θ (4,000 steps) for rough to nearly smooth fibres.
TEST(Sheen, TheDistributionIsNormalised) {
    for (const double r : {0.02, 0.1, 0.3, 0.7, 1.0}) {
        const int n = 4000;
        double sum = 0.0;
        for (int i = 0; i < n; ++i) {
            const double th = (i + 0.5) * (3.14159265358979323846 / 2) / n;
            sum += sheen_D(std::cos(th), r) * std::cos(th) * std::sin(th) * 2 * 3.14159265358979323846 * (3.14159265358979323846 / 2) / n;
        }
        EXPECT_NEAR(sum, 1.0, 1e-4) << "r " << r;
    }
}

TEST(Sheen, LambdaIsContinuousAndTheBrdfReciprocal) {
    for (const double r : {0.05, 0.4, 1.0}) {
        EXPECT_NEAR(sheen_lambda(0.5 - 1e-9, r), sheen_lambda(0.5 + 1e-9, r), 1e-6 * sheen_lambda(0.5, r)) << r;
        // Λ falls from grazing to normal incidence.
        EXPECT_GT(sheen_lambda(0.1, r), sheen_lambda(0.9, r)) << r;
        std::mt19937 rng(7);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (int k = 0; k < 50; ++k) {
            const dvec3 l = glm::normalize(dvec3(u(rng), u(rng), std::abs(u(rng)) + 0.05)), v = glm::normalize(dvec3(u(rng), u(rng), std::abs(u(rng)) + 0.05));
            EXPECT_NEAR(sheen_lobe(l, v, r), sheen_lobe(v, l, r), 1e-12 * sheen_lobe(l, v, r));
            EXPECT_GE(sheen_lobe(l, v, r), 0.0);
        }
    }
}

// A sheen's own samples on 32 light and 32 view directions: the fit returns its parameters
// (k_d and S within 1e-4 relative, r within 1e-4) and its values (relative RMS < 1e-6), for
// smooth to rough fibres and for a sheen without a diffuse term.
TEST(Sheen, RefitsItsOwnSamplesExactly) {
    const std::vector<dvec3> lights = hemisphere_directions(32, 0.02), views = hemisphere_directions(32, 0.05);
    for (const double r : {0.05, 0.2, 0.5, 0.9}) {
        for (const bool diffuse : {true, false}) {
            ClothBrdf truth;
            truth.L.kd = diffuse ? dvec3(0.12, 0.07, 0.03) : dvec3(0.0);
            truth.sheen = SheenLobe{dvec3(0.9, 0.6, 0.75), r};
            FitOptions o;
            o.sheen = true;
            o.lookup_table = false;
            FitReport rep;
            const ClothBrdf fit = fit_brdf(samples_of(truth, lights, views), o, &rep);
            SCOPED_TRACE("r " + std::to_string(r) + (diffuse ? ", with k_d" : ", no k_d"));
            ASSERT_TRUE(fit.sheen.has_value());
            EXPECT_TRUE(fit.L.lobes.empty());
            EXPECT_NEAR(fit.sheen->r, r, 1e-4);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(fit.L.kd[c], truth.L.kd[c], 1e-4 * truth.sheen->S[c]);
                EXPECT_NEAR(fit.sheen->S[c], truth.sheen->S[c], 1e-4 * truth.sheen->S[c]);
            }
            EXPECT_LT(rep.rel_rms, 1e-6);
        }
    }
}

// With a view table the alternation converges on a sheen times a colour shift per view (T is
// determined up to the model's scale: compare values, not parameters).
TEST(Sheen, RefitsASheenTimesAViewTable) {
    ClothBrdf truth;
    truth.L.kd = dvec3(0.05, 0.05, 0.04);
    truth.sheen = SheenLobe{dvec3(0.8, 0.7, 0.6), 0.35};
    truth.table.v = hemisphere_directions(32, 0.05);
    for (const dvec3& v : truth.table.v) truth.table.T.push_back(dvec4(1.0, 0.5 + 0.5 * v.z, 0.4 + 0.6 * v.z, 1.0));
    const PointSamples ps = samples_of(truth, hemisphere_directions(32, 0.02), truth.table.v);
    FitOptions o;
    o.sheen = true;
    o.lookup_table = false;
    FitReport plain;
    fit_brdf(ps, o, &plain);
    o.lookup_table = true;
    o.tolerance = 1e-6;
    o.max_rounds = 40;
    FitReport rep;
    fit_brdf(ps, o, &rep);
    EXPECT_LT(rep.rel_rms, 1e-4);
    EXPECT_LT(rep.rel_rms, plain.rel_rms / 50.0);
}

TEST(SheenHardCases, BlackSamplesAndBadOptions) {
    std::vector<BrdfSample> s;
    for (const dvec3& v : hemisphere_directions(8, 0.05))
        for (const dvec3& l : hemisphere_directions(8, 0.05)) s.push_back({l, v, dvec3(0.0), 0, l.z});
    const PointSamples ps = group_by_view(s);
    FitReport rep;
    FitOptions o;
    o.sheen = true;
    const ClothBrdf b = fit_brdf(ps, o, &rep);
    ASSERT_TRUE(b.sheen.has_value());
    EXPECT_EQ(b.L.kd, dvec3(0.0));
    EXPECT_EQ(b.sheen->S, dvec3(0.0));
    EXPECT_TRUE(std::isfinite(b.sheen->r));
    FitOptions bad = o;
    bad.tolerance = 0.0;
    EXPECT_THROW(fit_brdf(ps, bad), InputError);
    bad = o;
    bad.r_min = 1.5;
    EXPECT_THROW(fit_brdf(ps, bad), InputError);
}

// [SECTION] The method: cloth.method = sheen
// Every entry of the pyramid holds a sheen; the CPU and GPU frames agree as the paper's method's do.
TEST(ClothSheen, CpuAndGpuAgreeAndEveryEntryIsASheen) {
    Workbench wb;
    const Scene s = small_sheen_curtain();
    const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 200, 140);
    test::expect_frames_agree(cpu, gpu, {"radiance", "normal", "alpha"}, test::agreement_of("cloth"));
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 32;
    const RenderResult r = wb.render(s, req);
    const auto p = r.eval.get(cloth::stages::fit, 0);
    ASSERT_TRUE(p);
    for (const auto& level : p->level)
        for (const ClothBrdf& b : level) {
            ASSERT_TRUE(b.sheen.has_value());
            EXPECT_TRUE(b.L.lobes.empty());
            EXPECT_GE(b.sheen->r, 0.01);
            EXPECT_LE(b.sheen->r, 1.0);
        }
}

// Switching between the paper's lobes and the sheen refits without acquiring again, and the lobe
// count is a key of the paper's method only.
TEST(ClothSheen, SwitchingTheMethodRefitsOnlyAndLobesIsThePapersKey) {
    Workbench wb;
    Scene s = small_sheen_curtain();
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 48;
    wb.render(s, req);
    apply_set(s, "cloth.method", "daubert");
    const RenderResult paper = wb.render(s, req);
    EXPECT_EQ(paper.eval.run(cloth::stages::acquire)->status, StageStatus::Cached);
    EXPECT_EQ(paper.eval.run(cloth::stages::fit)->status, StageStatus::Ran);
    apply_set(s, "cloth.method", "sheen");
    const RenderResult back = wb.render(s, req);
    EXPECT_EQ(back.eval.run(cloth::stages::fit)->status, StageStatus::Cached);
    try {
        apply_sets(s, {"cloth.lobes=3"});
        ADD_FAILURE() << "cloth.lobes was accepted under sheen";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("lobes"), std::string::npos) << e.what();
    }
    EXPECT_EQ(Registry::instance().technique("cloth")->method_names(), (std::vector<std::string>{"daubert", "sheen"}));
}
