// bumpsynth's truth (core/bumpsynth/truth.cpp): per pixel, the footprint integrated over the finest
// synthesised bumps, each shaded with the micro-BRDF of the real-time path at full detail. Diffuse
// bumps average the cosine of their NDF (the paper's claim, which the NDF-alone shading does not
// meet for the diffuse term); the real-time synthesis at full detail converges to the truth as its
// look-up table grows; the truth reads none of the accuracy knobs.
#include "app/workbench.h"
#include "core/bumpsynth/ndf.h"
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
// A plane of bumpsynth `material` (JSON members added to the technique's) under one directional
// light `light` ([θ from the normal, φ] in degrees) of irradiance 2, no sky.
Scene scene(const std::string& material, const std::string& camera, const std::string& light = "[0, 0]") {
    const std::string text = R"({"schema": 1, "name": "bumpsynth-truth", "camera": )" + camera +
                             R"(, "lights": [{"type": "directional", "direction": )" + light +
                             R"(, "intensity": 2, "color": [1, 1, 1]}], "env": {"color": [0, 0, 0], "intensity": 0}, "effects": {"environment": false},
                             "objects": [{"name": "bumps", "geometry": {"type": "plane", "resolution": 4}, "material": {"technique": "bumpsynth", )" +
                             material + "}}]}";
    return scene_from_json(nlohmann::json::parse(text), "bumpsynth-truth", test::source_path("presets"));
}
const char* kOrbit = R"({"mode": "orbit", "distance": 3.0, "orbit": [1, -90], "fov": 30})";
const char* kTexture = R"({"mode": "texture", "distance": 3.0, "orbit": [30, -90], "fov": 30})";
}  // namespace

// Lambertian bumps (ks = 0) lit along the macro normal: each bump reflects kd/π E m_z, so the
// footprint's mean is kd/π E E[m_z], with E[m_z] the NDF's mean cosine (0.960 for Beckmann 0.3), not
// the kd/π E of a flat surface. Over the plane's pixels (many noise cells, 64 samples each) the
// truth's mean is that within 4 standard errors and 0.5% (the noise CDF G is measured, not exact).
TEST(BumpsynthTruth, DiffuseBumpsAverageTheCosineOfTheirNdf) {
    const Scene s = scene(R"("ndf": "beckmann", "alpha_x": 0.3, "alpha_y": 0.3, "octaves_max": 4, "ks": [0, 0, 0], "kd": [0.5, 0.5, 0.5])", kOrbit);
    const Frame f = test::render_uncached(s, test::truth_request(Backend::Truth, 32, 64)).frame;
    const bumpsynth::Ndf ndf = bumpsynth::Ndf::from_lobe(bumpsynth::Lobe::anisotropic(bumpsynth::LobeKind::beckmann, 0.3f, 0.3f), 512);
    double mean_mz = 0.0;
    for (int j = 0; j < ndf.resolution(); ++j)
        for (int i = 0; i < ndf.resolution(); ++i) {
            const vec2 c = ndf.cell_centre(i, j);
            mean_mz += ndf.mass(i, j) * std::sqrt(std::max(0.0, 1.0 - double(glm::dot(c, c))));
        }
    const test::ObjectMean m = test::object_mean(f);
    const double expected = 0.5 / kPi * 2.0 * mean_mz;
    std::printf("E[m_z] %.4f: truth %.5f +- %.5f over %d pixels, expected %.5f (flat: %.5f)\n", mean_mz, m.mean, m.stderr_mean, m.pixels, expected,
                0.5 / kPi * 2.0);
    ASSERT_GT(m.pixels, 500);
    EXPECT_LT(mean_mz, 0.97);  // the flat surface's 1 would be out by 4%
    EXPECT_NEAR(m.mean, expected, 4.0 * m.stderr_mean + 0.005 * expected);
}

// The real-time synthesis at full detail (texture mode: every octave) picks each texel's normal from
// the nearest entry of its look-up table; the truth inverts the NDF exactly. With 16 entries a side
// the quantised normals are visibly wrong; with 4096 the error is within the truth's noise. One truth
// serves both (lut_size is an accuracy knob).
TEST(BumpsynthTruth, TheRealTimeSynthesisConvergesToTheTruthAsItsTableGrows) {
    Scene s = scene(R"("ndf": "beckmann", "alpha_x": 0.3, "alpha_y": 0.3, "octaves_max": 3, "ks": [0.5, 0.5, 0.5], "kd": [0.3, 0.3, 0.3])", kTexture,
                    "[30, 0]");
    Workbench wb;
    wb.set_truth_cache(TruthCache(""));
    const RenderRequest req = test::truth_request(Backend::Cpu, 64, 16, {"truth_error"});
    std::vector<TruthComparison> r;
    for (int lut : {16, 4096}) {
        apply_set(s, "bumpsynth.lut_size", std::to_string(lut));
        const RenderResult res = wb.render(s, req);
        ASSERT_TRUE(res.truth);
        std::printf("lut_size %d: rmse_rel %.4f (truth noise %.4f)\n", lut, res.truth->rmse_rel, res.truth->noise_rel);
        r.push_back(*res.truth);
    }
    EXPECT_LT(r[0].noise_rel, 0.01);
    EXPECT_GT(r[0].rmse_rel, 0.05);
    EXPECT_FALSE(r[0].below_noise);
    EXPECT_TRUE(r[1].below_noise) << r[1].rmse_rel;
}

// One truth serves a sweep: the truth's key ignores bumpsynth's accuracy knobs (the tables' sizes,
// how the noise is evaluated, how many octaves the distance lets in) and follows the surface.
TEST(BumpsynthTruth, ReadsNoAccuracyKnob) {
    const Scene s = scene(R"("ndf": "beckmann")", kOrbit);
    test::expect_truth_key(s, {"bumpsynth.lut_size=1024", "bumpsynth.ndf_resolution=256", "bumpsynth.noise=texture", "bumpsynth.detail_distance=100"},
                           {"bumpsynth.ks=[0.5,0.5,0.5]", "bumpsynth.alpha_x=0.1", "bumpsynth.octaves_max=5", "bumpsynth.noise_seed=7", "bumpsynth.masking=true"});
}
