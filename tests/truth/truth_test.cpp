// The truth renderer (core/truth/truth.h) on scenes of the basic technique, whose answers are
// known: a white furnace, Lambert's closed form, a shadow, determinism at any thread count,
// honest standard errors, and bad input.
#include "app/truth_figures.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/scene.h"
#include "core/truth/truth.h"
#include "support/cli.h"
#include "support/truth.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <unistd.h>
#include <string>

using namespace mesolab;

namespace {
// A basic scene: `objects` and `lights` as JSON text, constant environment `env`.
Scene scene(const std::string& objects, const std::string& lights, float env, const std::string& camera = R"({"mode": "orbit", "distance": 3.0, "orbit": [50, -60], "fov": 40})") {
    const std::string text = R"({"schema": 1, "name": "truth-test", "camera": )" + camera + R"(, "lights": )" + lights +
                             R"(, "env": {"color": [1, 1, 1], "intensity": )" + std::to_string(env) + R"(}, "effects": {"environment": true}, "objects": )" +
                             objects + "}";
    return scene_from_json(nlohmann::json::parse(text), "truth-test", test::source_path("presets"));
}

Frame truth(const Scene& s, int size, int spp, uint64_t seed = 1) {
    return test::render_uncached(s, test::truth_request("truth", size, spp, {"truth_stderr"}, seed)).frame;
}

using test::shows_object;

const char* kWhiteTorus = R"([{"name": "torus", "geometry": {"type": "torus", "resolution": 48},
    "material": {"technique": "basic", "kd": [1, 1, 1], "ks": [0, 0, 0]}}])";
const char* kWhiteSphere = R"([{"name": "sphere", "geometry": {"type": "sphere", "resolution": 48},
    "material": {"technique": "basic", "kd": [1, 1, 1], "ks": [0, 0, 0]}}])";
}  // namespace

// A white (kd = 1) convex object under a uniform sky of radiance 1: every path's first bounce
// escapes, so every sample is exactly 1 and the standard error 0.
TEST(TruthFurnace, AWhiteSphereUnderAUniformSkyIsExactlyOne) {
    const Frame f = truth(scene(kWhiteSphere, "[]", 1.f), 32, 4);
    int shown = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            const float* L = f.aov("radiance").at(x, y);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(L[c], 1.f, 1e-5f) << x << "," << y;  // background too: the sky is 1
            if (!shows_object(f, x, y)) continue;
            ++shown;
            for (int c = 0; c < 3; ++c) EXPECT_LT(f.aov("truth_stderr").at(x, y)[c], 1e-6f);  // float rounding of f π
        }
    EXPECT_GT(shown, 200);
}

// A concave white object (the torus sees itself) under the same sky: radiance 1 in expectation
// (any number of bounces; Russian roulette keeps the estimate unbiased). The mean over the
// object's pixels, within 4.4 of its standard errors (two-sided 1e-5).
TEST(TruthFurnace, AWhiteTorusUnderAUniformSkyIsOneWithinTheNoise) {
    const Frame f = truth(scene(kWhiteTorus, "[]", 1.f), 48, 32);
    const test::ObjectMean m = test::object_mean(f);
    ASSERT_GT(m.pixels, 300);
    const double mean = m.mean, se_mean = m.stderr_mean;
    std::printf("torus furnace: mean %.5f, standard error %.5f over %d pixels\n", mean, se_mean, m.pixels);
    EXPECT_GT(se_mean, 0.0);  // interreflections are sampled: the estimate does vary
    EXPECT_LT(std::abs(mean - 1.0), 4.4 * se_mean);
}

// A Lambert plane lit by a directional light 60 degrees from its normal, no sky: L = kd / π E cos θ
// at every pixel that shows it (nothing else to bounce off).
TEST(TruthLambert, APlaneUnderADirectionalLightIsTheClosedForm) {
    const Scene s = scene(R"([{"name": "plane", "geometry": {"type": "plane", "resolution": 4},
        "material": {"technique": "basic", "kd": [0.5, 0.25, 0.125], "ks": [0, 0, 0]}}])",
                          R"([{"type": "directional", "direction": [60, 30], "intensity": 2, "color": [1, 1, 1]}])", 0.f,
                          R"({"mode": "orbit", "distance": 2.0, "orbit": [20, -60], "fov": 30})");
    const float E = 2.f * 0.5f;  // cos 60°
    EXPECT_GT(test::expect_object_radiance(truth(s, 32, 2), vec3(0.5f, 0.25f, 0.125f) / kPi * E, 1e-6f), 500);
}

// A black sphere above a white plane, lit straight from above with no sky: a point of the plane
// is kd / π E where it sees the light and exactly 0 in the sphere's shadow (the black sphere
// reflects nothing and a plane cannot see itself). Every sample of a pixel starts through its
// centre, so a pixel is one or the other, also on the shadow's edge.
TEST(TruthShadows, APlaneIsLitOrInTheShadowOfABlackSphere) {
    const Scene s = scene(R"([{"name": "plane", "geometry": {"type": "plane", "resolution": 4, "scale": 6},
          "material": {"technique": "basic", "kd": [0.8, 0.8, 0.8], "ks": [0, 0, 0]}},
        {"name": "ball", "geometry": {"type": "sphere", "resolution": 48, "position": [0, 0, 2]},
          "material": {"technique": "basic", "kd": [0, 0, 0], "ks": [0, 0, 0]}}])",
                          R"([{"type": "directional", "direction": [0, 0], "intensity": 3, "color": [1, 1, 1]}])", 0.f,
                          R"({"mode": "orbit", "distance": 14.0, "orbit": [35, -90], "fov": 40})");
    const Frame f = truth(s, 64, 4);
    const float lit_value = 0.8f / kPi * 3.f;
    int lit = 0, shadow = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            if (!shows_object(f, x, y)) continue;
            const float* n = f.aov("normal").at(x, y);
            if (std::abs(n[2]) < 0.9999f) continue;  // the sphere
            const float L = f.aov("radiance").at(x, y)[1];
            if (L == 0.f) ++shadow;
            else if (std::abs(L - lit_value) < 1e-5f) ++lit;
            else ADD_FAILURE() << "pixel " << x << "," << y << ": " << L << ", neither lit (" << lit_value << ") nor in the shadow";
        }
    std::printf("plane pixels: %d lit, %d in the shadow\n", lit, shadow);
    EXPECT_GT(lit, 500);
    EXPECT_GT(shadow, 20);
}

// The same seed gives the same bytes whatever the number of threads; another seed does not.
TEST(TruthDeterminism, TheSameSeedGivesTheSameBytesAtAnyThreadCount) {
    const Scene s = scene(kWhiteTorus, R"([{"type": "directional", "direction": [40, 10], "intensity": 2, "color": [1, 1, 1]}])", 0.5f);
    Frame one, two;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = truth(s, 24, 8, 7);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 4);
        two = truth(s, 24, 8, 7);
    }
    for (const char* aov : {"radiance", "normal", "truth_stderr"}) EXPECT_EQ(one.aov(aov).data, two.aov(aov).data) << aov;
    EXPECT_NE(truth(s, 24, 8, 8).aov("radiance").data, one.aov("radiance").data);
}

// truth_stderr says how far a pixel's estimate is from its expectation: over 8 seeds, the spread
// of each pixel's estimates matches the standard error reported. The ratio of their mean squares
// over P pixels x 8 seeds follows an F-like law with about 7P degrees of freedom: within 15% at
// P > 400 is many standard deviations wide, and a standard error off by a factor sqrt(2) fails.
TEST(TruthNoise, TheStandardErrorMatchesTheSpreadOverSeeds) {
    const Scene s = scene(R"([{"name": "torus", "geometry": {"type": "torus", "resolution": 48},
        "material": {"technique": "basic", "kd": [0.7, 0.7, 0.7], "ks": [0, 0, 0]}}])",
                          R"([{"type": "directional", "direction": [40, 10], "intensity": 2, "color": [1, 1, 1]}])", 0.5f);
    constexpr int kSeeds = 8, kSize = 32;
    std::vector<Frame> frames;
    for (int k = 0; k < kSeeds; ++k) frames.push_back(truth(s, kSize, 16, uint64_t(100 + k)));
    const test::StderrCheck check = test::stderr_against_spread(frames);
    ASSERT_GT(check.pixels, 400);
    EXPECT_NEAR(check.ratio, 1.0, 0.15);
}

// Bad input is an error naming what is wrong.
TEST(TruthErrors, ZeroSamplesAndAFabricWithoutYarns) {
    const Scene s = scene(kWhiteSphere, "[]", 1.f);
    EXPECT_THROW(truth(s, 8, 0), InputError);
    try {
        truth(s, 8, 0);
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--spp 0"), std::string::npos) << e.what();
    }
    // A fabric given only as samples has no yarns for the truth to trace.
    Scene cloth = load_preset(test::source_path("presets/cloth/stitch-knit.json"));
    apply_set(cloth, "cloth.samples", test::source_path("presets/cloth/stitch-knit.json"));
    try {
        truth(cloth, 8, 1);
        ADD_FAILURE() << "a samples-only fabric has no truth";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.samples"), std::string::npos) << e.what();
    }
}

// truth_error renders the truth beside the real-time frame. A Lambert plane under a directional
// light with no sky is exact on the real-time path (L = kd / π E cos θ): no error, and none the
// truth could resolve. Add a black sphere and its shadow, which the rasteriser leaves out: the
// error is the shadow, far above the truth's noise.
TEST(TruthError, IsZeroWhereTheRealTimePathIsExactAndShowsTheMissingShadow) {
    const std::string plane = R"({"name": "plane", "geometry": {"type": "plane", "resolution": 4, "scale": 6},
          "material": {"technique": "basic", "kd": [0.8, 0.8, 0.8], "ks": [0, 0, 0]}})";
    const std::string ball = R"({"name": "ball", "geometry": {"type": "sphere", "resolution": 48, "position": [0, 0, 2]},
          "material": {"technique": "basic", "kd": [0, 0, 0], "ks": [0, 0, 0]}})";
    const std::string light = R"([{"type": "directional", "direction": [0, 0], "intensity": 3, "color": [1, 1, 1]}])";
    const std::string camera = R"({"mode": "orbit", "distance": 14.0, "orbit": [35, -90], "fov": 40})";
    Workbench wb;
    wb.set_truth_cache("");
    const RenderRequest req = test::truth_request("cpu", 48, 4, {"truth_error"});
    const RenderResult exact = wb.render(scene("[" + plane + "]", light, 0.f, camera), req);
    ASSERT_TRUE(exact.truth);
    ASSERT_TRUE(exact.frame.has("truth_error"));
    EXPECT_LT(exact.truth->rmse_rel, 1e-5);
    EXPECT_TRUE(exact.truth->below_noise);
    const RenderResult shadowed = wb.render(scene("[" + plane + ", " + ball + "]", light, 0.f, camera), req);
    ASSERT_TRUE(shadowed.truth);
    std::printf("missing shadow: rmse_rel %.4f, truth noise %.4f\n", shadowed.truth->rmse_rel, shadowed.truth->noise_rel);
    EXPECT_GT(shadowed.truth->rmse_rel, 0.05);
    EXPECT_FALSE(shadowed.truth->below_noise);
    float most = 0.f;  // the real-time path is brighter than the truth in the shadow, never darker
    float least = 0.f;
    for (float v : shadowed.frame.aov("truth_error").data) most = std::max(most, v), least = std::min(least, v);
    EXPECT_GT(least, -1e-5f);
    EXPECT_GT(most, 0.5f);
    // As a picture: the error's colours over the frame (red where the real-time path is brighter:
    // the shadow it misses), the legend in a strip below.
    ASSERT_TRUE(shadowed.truth_frame);
    const Image fig = error_figure(shadowed.truth->error, *shadowed.truth_frame);
    EXPECT_EQ(fig.width, 48);
    EXPECT_GT(fig.height, 48 + 20);
    int red = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x)
            if (shadowed.frame.aov("truth_error").at(x, y)[1] > 0.5f) {
                EXPECT_GT(fig.at(x, y)[0], 0.8f) << x << "," << y;
                EXPECT_LT(fig.at(x, y)[2], 0.5f) << x << "," << y;
                ++red;
            }
    EXPECT_GT(red, 10);
}

// `capture --aov truth_error` writes the truth and the error as pictures beside the frame.
TEST(TruthError, CaptureWritesTheTruthAndTheErrorAsPictures) {
    test::TempDir dir("truth-capture");
    const test::CliResult r = test::run_mesolab("capture presets/basic/sphere.json --backend cpu --aov truth_error --spp 2 --size 32x32 -o " + dir.path.string());
    ASSERT_EQ(r.status, 0) << r.err;
    const Image truth = read_image(dir / "basic-sphere.truth.png"), error = read_image(dir / "basic-sphere.truth_error.png");
    EXPECT_EQ(truth.width, 32);
    EXPECT_EQ(truth.height, 32);
    EXPECT_EQ(error.width, 32);
    EXPECT_GT(error.height, 32);
}

// A truth continued from fewer samples is the bytes a fresh one of as many samples is; the cache
// on disk gives a truth back without rendering, continues it when asked for more, and keys it by
// everything it depends on (here the light).
TEST(TruthCache, ContinuesAndReusesTruthsKeyedByWhatTheyRead) {
    const Scene s = scene(kWhiteTorus, R"([{"type": "directional", "direction": [40, 10], "intensity": 2, "color": [1, 1, 1]}])", 0.5f);
    const Frame fresh = truth(s, 16, 12, 3);
    const std::string folder = (std::filesystem::temp_directory_path() / ("mesolab-truth-cache-" + std::to_string(::getpid()))).string();
    std::filesystem::remove_all(folder);
    Workbench wb;
    wb.set_truth_cache(folder);
    RenderRequest req;
    req.renderer = "truth";
    req.width = req.height = 16;
    req.truth.seed = 3;
    req.aovs = {"truth_stderr"};
    req.truth.spp = 5;
    const RenderResult five = wb.render(s, req);
    EXPECT_EQ(five.sampled->cached_spp, 0);
    req.truth.spp = 12;
    const RenderResult twelve = wb.render(s, req);
    EXPECT_EQ(twelve.sampled->cached_spp, 5);  // continued from the 5 on disk
    for (const char* aov : {"radiance", "normal", "truth_stderr"}) EXPECT_EQ(twelve.frame.aov(aov).data, fresh.aov(aov).data) << aov;
    const RenderResult again = wb.render(s, req);
    EXPECT_EQ(again.sampled->cached_spp, 12);  // nothing rendered
    EXPECT_EQ(again.frame.aov("radiance").data, fresh.aov("radiance").data);
    Scene moved = s;
    apply_set(moved, "light.direction", "41,10");
    EXPECT_EQ(wb.render(moved, req).sampled->cached_spp, 0);
    req.truth.spp = 4;  // fewer than kept: rendered afresh (the same seed's first 4 samples)
    const RenderResult four = wb.render(s, req);
    EXPECT_EQ(four.sampled->cached_spp, 0);
    EXPECT_EQ(four.frame.aov("radiance").data, truth(s, 16, 4, 3).aov("radiance").data);
    std::filesystem::remove_all(folder);
}

// Texture mode: a texel is the surface point the real-time paths rasterise there, seen from the
// camera's direction. A Lambert plane under a directional light and a constant sky is exact on
// both paths, texel by texel, at the plane's own texture size.
TEST(TruthTexture, APlanesTexelsAreExactOnBothPaths) {
    const Scene s = load_preset(test::source_path("presets/basic/plane-texture.json"));
    const RenderResult r = test::render_uncached(s, test::truth_request("cpu", 64, 2, {"truth_error"}));
    ASSERT_TRUE(r.truth);
    EXPECT_LT(r.truth->rmse_rel, 1e-5);
    int shown = 0;
    for (int y = 0; y < r.frame.height; ++y)
        for (int x = 0; x < r.frame.width; ++x) shown += r.frame.aov("radiance").at(x, y)[0] > 0.f;
    EXPECT_GT(shown, r.frame.width * r.frame.height / 2);
}
