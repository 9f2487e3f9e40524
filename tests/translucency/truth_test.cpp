// translucency's truth (core/translucency/truth.cpp): volumetric light transport inside the
// closed mesh, traced from the lights. A non-absorbing medium behind an index-matched boundary
// (η = 1) lets every bit of entered power out, so under a uniform sky of radiance 1 it glows at
// exactly 1 (within the exitance estimate's edge loss on coarse facets); absorption darkens it; the photons' sums are the same
// bytes at any thread count; an open mesh is refused by name.
#include "core/truth/cache.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/truth/truth.h"
#include "support/cli.h"
#include "support/meshes.h"
#include "support/truth.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <array>
#include <map>
#include <cmath>
#include <cstdio>
#include <string>

using namespace mesolab;

namespace {
Scene ball(const std::string& medium, const std::string& lights, float env, const std::string& type = "sphere") {
    const std::string text = R"({"schema": 1, "name": "translucency-truth", "camera": {"mode": "orbit", "distance": 4.0, "orbit": [60, -60], "fov": 40},
        "lights": )" + lights + R"(, "env": {"color": [1, 1, 1], "intensity": )" + std::to_string(env) +
                             R"(}, "effects": {"environment": true}, "objects": [{"name": "ball", "geometry": {"type": ")" + type +
                             R"(", "resolution": 16}, "material": {"technique": "translucency", "material": "custom", "mm_per_unit": 1, )" + medium + "}}]}";
    return scene_from_json(nlohmann::json::parse(text), "translucency-truth", test::source_path("presets"));
}

Frame truth(const Scene& s, int size, int spp) {
    return test::render_uncached(s, test::truth_request("truth", size, spp, {"truth_stderr"})).frame;
}
}  // namespace

// σa = 0 and η = 1: the photons that enter all leave, and in a uniform sky of radiance 1 every
// point sends out what it receives, π per unit area: L = M / π = 1. All pixels share a sample's
// photons, so the mean over the ball's pixels is judged by its spread over 8 seeds: per channel,
// the grand mean within 4.4 of its standard error (three tests: 1e-5 each, Šidák).
TEST(TranslucencyTruth, ANonAbsorbingIndexMatchedBallInAUniformSkyGlowsAtOne) {
    const Scene s = ball(R"("sigma_s": [1, 2, 4], "sigma_a": [0, 0, 0], "eta": 1.0)", "[]", 1.f);
    constexpr int kSeeds = 8;
    std::vector<std::array<double, 3>> means;
    for (int k = 0; k < kSeeds; ++k) {
        const Frame f = test::render_uncached(s, test::truth_request("truth", 32, 4, {}, uint64_t(10 + k))).frame;
        std::array<double, 3> m{};
        for (int c = 0; c < 3; ++c) m[size_t(c)] = test::object_mean(f, c).mean;
        ASSERT_GT(test::object_mean(f).pixels, 200);
        means.push_back(m);
    }
    for (int c = 0; c < 3; ++c) {
        double sum = 0.0, sum2 = 0.0;
        for (const auto& m : means) sum += m[size_t(c)], sum2 += m[size_t(c)] * m[size_t(c)];
        const double mean = sum / kSeeds, var = (sum2 - kSeeds * mean * mean) / (kSeeds - 1), se = std::sqrt(var / kSeeds);
        std::printf("channel %d: mean %.4f, standard error %.4f over %d seeds\n", c, mean, se, kSeeds);
        EXPECT_GT(se, 0.0);
        EXPECT_LT(std::abs(mean - 1.0), 4.4 * se) << c;
    }
}

// Absorption takes light away: the same ball with σa = σs′ is darker in every channel, by far.
TEST(TranslucencyTruth, AbsorptionDarkens) {
    const std::string light = R"([{"type": "directional", "direction": [40, 30], "intensity": 3, "color": [1, 1, 1]}])";
    const Frame clear = truth(ball(R"("sigma_s": [1, 1, 1], "sigma_a": [0, 0, 0], "eta": 1.3)", light, 0.f), 24, 8);
    const Frame dark = truth(ball(R"("sigma_s": [1, 1, 1], "sigma_a": [1, 1, 1], "eta": 1.3)", light, 0.f), 24, 8);
    for (int c = 0; c < 3; ++c) EXPECT_LT(test::object_mean(dark, c).mean, 0.7 * test::object_mean(clear, c).mean) << c;
}

TEST(TranslucencyTruth, TheSameBytesAtAnyThreadCount) {
    const Scene s = ball(R"("sigma_s": [1, 2, 4], "sigma_a": [0.1, 0.1, 0.1], "eta": 1.3)",
                         R"([{"type": "point", "position": [2, 1, 2], "intensity": 8, "color": [1, 1, 1]}])", 0.3f);
    Frame one, four;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = truth(s, 16, 3);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 4);
        four = truth(s, 16, 3);
    }
    EXPECT_EQ(one.aov("radiance").data, four.aov("radiance").data);
    float most = 0.f;
    for (float v : one.aov("radiance").data) most = std::max(most, v);
    EXPECT_GT(most, 0.f);
}

// Light travels inside the mesh: a sheet (a plane) is refused, naming the object and saying why; a
// solid with holes (the cylinder has no caps) is closed by a fan over each hole, and the
// index-matched, non-absorbing furnace glows at 1 in it too (within 5%: one seed, the pixels sharing its photons).
TEST(TranslucencyTruth, AnOpenSheetIsRefusedAndHolesAreClosed) {
    const test::ObjectMean can = test::object_mean(truth(ball(R"("sigma_s": [1, 1, 1], "sigma_a": [0, 0, 0], "eta": 1.0)", "[]", 1.f, "cylinder"), 32, 16));
    ASSERT_GT(can.pixels, 100);
    EXPECT_NEAR(can.mean, 1.0, 0.05);
    try {
        truth(ball(R"("sigma_s": [1, 1, 1], "sigma_a": [0, 0, 0], "eta": 1.3)", "[]", 1.f, "plane"), 8, 1);
        ADD_FAILURE() << "an open mesh has no translucency truth";
    } catch (const InputError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("'ball'"), std::string::npos) << m;
        EXPECT_NE(m.find("closed mesh"), std::string::npos) << m;
        EXPECT_NE(m.find("plane is open"), std::string::npos) << m;
    }
}

namespace {
// A closed box of 2 x 2 x 0.5 units, its faces split into squares of 0.05 (welded along the edges):
// at 20 mm a unit, a slab 40 mm wide and 10 mm thick.
std::string write_slab(const std::string& dir) { return test::write_box_obj(dir + "/slab.obj", 40, 10, -0.25, 0.25); }

// The mean of `aov`'s channel c over the central half of the frame.
double central_mean(const Frame& f, const char* aov, int c) {
    const Image& im = f.aov(aov);
    double sum = 0.0;
    int n = 0;
    for (int y = im.height / 4; y < 3 * im.height / 4; ++y)
        for (int x = im.width / 4; x < 3 * im.width / 4; ++x) sum += im.at(x, y)[c], ++n;
    return sum / n;
}
}  // namespace

// Where the dipole is meant to hold: a large flat slab (40 mm wide, 10 mm thick, 20 diffusion
// lengths) lit from straight above, albedo α' = 0.8, η = 1.3. The exitance the real-time model sends
// out (its AOV `exitance`: B times the hemispherical mean of T) against the truth's, over the
// middle of the top face: measured 0.1804 against 0.1768 (64 spp), the dipole 2.0% high. Within
// 4% at 6 spp (the truth's noise on that mean is about 1%).
TEST(TranslucencyTruth, TheDipoleOnALargeFlatSlabIsWithinAFewPercentOfTheTruth) {
    test::TempDir dir("translucency-slab");
    const std::string mesh = write_slab(dir.path);
    const std::string text = R"({"schema": 1, "name": "slab", "camera": {"mode": "orbit", "distance": 3.0, "orbit": [1, -90], "fov": 30},
        "lights": [{"type": "directional", "direction": [0, 0], "intensity": 1, "color": [1, 1, 1]}],
        "env": {"color": [0, 0, 0], "intensity": 0}, "effects": {"environment": false},
        "objects": [{"name": "slab", "geometry": {"type": "mesh", "path": ")" + mesh + R"("}, "material": {"technique": "translucency",
        "material": "custom", "sigma_s": [2, 2, 2], "sigma_a": [0.5, 0.5, 0.5], "eta": 1.3, "mm_per_unit": 20, "vertices": 0}}]})";
    const Scene s = scene_from_json(nlohmann::json::parse(text), "slab", dir.path);
    const RenderResult rt = test::render_uncached(s, test::truth_request("cpu", 32, 6, {"exitance"}));
    const Frame t = test::render_uncached(s, test::truth_request("truth", 32, 6, {"exitance"})).frame;
    const double m_rt = central_mean(rt.frame, "exitance", 1), m_truth = central_mean(t, "exitance", 1);
    std::printf("slab exitance: real-time %.4f, truth %.4f, ratio %.4f\n", m_rt, m_truth, m_rt / m_truth);
    EXPECT_GT(m_truth, 0.1);
    EXPECT_NEAR(m_rt / m_truth, 1.0, 0.04);
}
