// cloth's truth (core/cloth/truth.h): the stitch's yarns instanced over the garment and path traced.
// White yarn under a uniform white sky is 1 wherever it is seen (no light lost between the
// instanced tiles, through the holes or between the yarns); the truth reads none of the
// acquisition's or the fit's knobs; a fabric given only as samples, and one too large for memory,
// are refused by name.
#include "app/workbench.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/truth/truth.h"
#include "support/cli.h"
#include "support/truth.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <string>

using namespace mesolab;

namespace {
// A flat fabric of `material` (JSON members added to the technique's) seen from 40 degrees.
Scene scene(const std::string& material, float sky = 0.f) {
    const std::string text = R"({"schema": 1, "name": "cloth-truth", "camera": {"mode": "orbit", "distance": 2.6, "orbit": [40, -90], "fov": 40},
        "lights": [], "env": {"color": [1, 1, 1], "intensity": )" + std::to_string(sky) +
                             R"(}, "effects": {"environment": true}, "objects": [{"name": "fabric", "geometry": {"type": "plane"}, "material": {"technique": "cloth", "garment": "geometry", )" +
                             material + "}}]}";
    return scene_from_json(nlohmann::json::parse(text), "cloth-truth", test::source_path("presets"));
}
}  // namespace

// Furnace: yarn of albedo 1 under a sky of radiance 1 sends out 1 in expectation wherever the camera
// sees it, however often light bounces between the yarns; the holes show the sky (1 as well). The
// mean over the object's pixels is 1 within 4 standard errors (and 0.3%: Russian roulette and float).
TEST(ClothTruth, WhiteYarnUnderAUniformSkyIsOne) {
    for (const char* stitch : {"knit", "weave"}) {
        const Scene s = scene(std::string(R"("stitch": ")") + stitch + R"(", "repeat": 3, "color_a": [1, 1, 1], "color_b": [1, 1, 1])", 1.f);
        const Frame f = test::render_uncached(s, test::truth_request("truth", 32, 16)).frame;
        const test::ObjectMean m = test::object_mean(f);
        std::printf("%s: %.5f +- %.5f over %d pixels\n", stitch, m.mean, m.stderr_mean, m.pixels);
        ASSERT_GT(m.pixels, 200) << stitch;
        EXPECT_NEAR(m.mean, 1.0, 4.0 * m.stderr_mean + 3e-3) << stitch;
    }
}

// One truth serves a sweep over the acquisition and the fit: the truth's key ignores them and the
// real-time polygonisation, and follows the yarns and how often they repeat.
TEST(ClothTruth, ReadsNoAccuracyKnob) {
    const Scene s = scene(R"("stitch": "knit")");
    test::expect_truth_key(s, {"cloth.spatial=16", "cloth.directions=16", "cloth.lobes=1", "cloth.stitch_resolution=32", "cloth.mip=off", "cloth.lookup_table=false"},
                           {"cloth.repeat=4", "cloth.stitch=purl", "cloth.color_a=[0.2,0.3,0.4]", "cloth.yarn_radius=0.1"});
}

// A fabric given only as acquired samples has no yarns to trace; a fabric repeated beyond the
// memory there is: both exit with status 2 naming the key.
TEST(ClothTruth, RefusesSamplesOnlyAndTooLargeFabrics) {
    Scene s = scene(R"("stitch": "knit", "samples": "cloth/stitch-knit.json")");
    try {
        test::render_uncached(s, test::truth_request("truth", 8, 1));
        ADD_FAILURE() << "a samples-only fabric has no truth";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.samples"), std::string::npos) << e.what();
    }
    const test::CliResult big = test::run_mesolab("capture presets/cloth/stitch-knit.json --backend truth --spp 1 --size 16x16 --set objects.0.material.repeat=5000 -o /tmp/mesolab-never");
    EXPECT_EQ(big.status, 2);
    EXPECT_NE(big.err.find("cloth.repeat"), std::string::npos) << big.err;
}
