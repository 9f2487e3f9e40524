// translucency's truth (core/translucency/truth.cpp): volumetric light transport inside the
// closed mesh, traced from the lights. A non-absorbing medium behind an index-matched boundary
// (η = 1) lets every bit of entered power out, so under a uniform sky of radiance 1 it glows at
// exactly 1; absorption darkens it; the photons' sums are the same bytes at any thread count; an
// open mesh is refused by name.
#include "app/truth_cache.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/truth/truth.h"
#include "support/cli.h"
#include "support/truth.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <array>
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
    return test::render_uncached(s, test::truth_request(Backend::Truth, size, spp, {"truth_stderr"})).frame;
}
}  // namespace

// σa = 0 and η = 1: the photons that enter all leave, and in a uniform sky of radiance 1 every
// point sends out what it receives, π per unit area: L = M / π = 1. Neighbouring pixels share
// vertices, so the mean over the ball's pixels is judged by its spread over 8 seeds: per channel,
// the grand mean within 4.4 of its standard error (three tests: 1e-5 each, Šidák).
TEST(TranslucencyTruth, ANonAbsorbingIndexMatchedBallInAUniformSkyGlowsAtOne) {
    const Scene s = ball(R"("sigma_s": [1, 2, 4], "sigma_a": [0, 0, 0], "eta": 1.0)", "[]", 1.f);
    constexpr int kSeeds = 8;
    std::vector<std::array<double, 3>> means;
    for (int k = 0; k < kSeeds; ++k) {
        const Frame f = test::render_uncached(s, test::truth_request(Backend::Truth, 32, 4, {}, uint64_t(10 + k))).frame;
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
// index-matched, non-absorbing furnace glows at 1 in it too (within 5%: one seed, shared vertices).
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
