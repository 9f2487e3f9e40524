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
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

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
    const Frame f = test::render_uncached(s, test::truth_request("truth", 32, 64)).frame;
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
    wb.set_truth_cache("");
    const RenderRequest req = test::truth_request("cpu", 64, 16, {"truth_error"});
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

// [SECTION] Next-event estimation over the footprint (truth.cpp, TruthMaterial::fcos_light)
namespace {
// A glossy bumpy plane (Beckmann 0.1, 6 octaves from 8 cells per unit of uv: ~8 of the finest
// bumps across a pixel of 24²) seen at 30° with the light in the mirror direction: each pixel's
// footprint holds many narrow highlights.
Scene glossy_bumps() {
    return scene(R"("ndf": "beckmann", "alpha_x": 0.1, "alpha_y": 0.1, "octaves_max": 6, "noise_frequency": 8, "detail_distance": 100,
                 "ks": [0.6, 0.6, 0.6], "kd": [0.2, 0.2, 0.2])",
                 R"({"mode": "orbit", "distance": 3.0, "orbit": [30, -90], "fov": 30})", "[30, 90]");
}

}  // namespace

// The footprint's points change the variance, not the mean: per pixel, the new estimator's mean
// (64 spp) and the plain one's (256 spp, another seed) differ by no more than the Šidák-corrected
// two-sided z of the family of pixels at a 1% false-alarm rate, in units of their combined standard
// error; and so do their means over the object. The new estimator's noise per sample is far lower.
TEST(BumpsynthTruth, FootprintSplittingKeepsThePlainEstimatorsMean) {
    const Scene s = glossy_bumps();
    constexpr int kSize = 24;
    Workbench wb;
    wb.set_truth_cache("");
    Frame plain;
    {
        test::PlainEstimator p;
        plain = wb.render(s, test::truth_request("truth", kSize, 256, {"truth_stderr"}, 11)).frame;
    }
    const Frame split = wb.render(s, test::truth_request("truth", kSize, 64, {"truth_stderr"}, 12)).frame;
    std::vector<double> z;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            if (!test::shows_object(plain, x, y)) continue;
            for (int c = 0; c < 3; ++c) {
                const double d = double(split.aov("radiance").at(x, y)[c]) - plain.aov("radiance").at(x, y)[c];
                const double e = std::hypot(double(split.aov("truth_stderr").at(x, y)[c]), double(plain.aov("truth_stderr").at(x, y)[c]));
                if (c == 1) z.push_back(e > 0.0 ? d / e : (d == 0.0 ? 0.0 : 1e30));
            }
        }
    const double zmax_allowed = test::sidak_z(0.01, int(z.size()));
    double zmax = 0.0;
    for (double v : z) zmax = std::max(zmax, std::fabs(v));
    const test::ObjectMean a = test::object_mean(split), b = test::object_mean(plain);
    const double noise_split = truth_noise_rel(split) * std::sqrt(64.0), noise_plain = truth_noise_rel(plain) * std::sqrt(256.0);
    std::printf("%zu pixels: max |z| %.2f (Šidák bound %.2f); object mean %.5f +- %.5f (split) vs %.5f +- %.5f (plain); noise per sample %.3f vs %.3f\n",
                z.size(), zmax, zmax_allowed, a.mean, a.stderr_mean, b.mean, b.stderr_mean, noise_split, noise_plain);
    ASSERT_GT(z.size(), 300u);
    EXPECT_LT(zmax, zmax_allowed);
    EXPECT_NEAR(a.mean, b.mean, 3.0 * std::hypot(a.stderr_mean, b.stderr_mean));
    EXPECT_LT(noise_split, 0.5 * noise_plain);
}

// The number of points is a deterministic function of the footprint (its pilot), so the truth stays
// the same bytes at any thread count, and its samples independent: over 6 seeds, the spread of each
// pixel's estimate matches the standard error it reports (as in tests/truth, within 15%).
TEST(BumpsynthTruth, FootprintSplittingIsDeterministicAndItsStandardErrorHonest) {
    const Scene s = glossy_bumps();
    constexpr int kSize = 16, kSeeds = 6;
    Workbench wb;  // one for every truth here: the stages once, no truth from the cache
    wb.set_truth_cache("");
    auto truth = [&](uint64_t seed) { return wb.render(s, test::truth_request("truth", kSize, 4, {"truth_stderr"}, seed)).frame; };
    Frame one, four;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = truth(5);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 4);
        four = truth(5);
    }
    for (const char* aov : {"radiance", "truth_stderr"}) EXPECT_EQ(one.aov(aov).data, four.aov(aov).data) << aov;
    std::vector<Frame> frames;
    for (int k = 0; k < kSeeds; ++k) frames.push_back(truth(uint64_t(200 + k)));
    const test::StderrCheck check = test::stderr_against_spread(frames);
    ASSERT_GT(check.pixels, 200);
    EXPECT_NEAR(check.ratio, 1.0, 0.15);
}
