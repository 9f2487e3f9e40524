// The sweep metric bumpsynth.ndf_histogram (core/bumpsynth/sweep_metric.h): the NDF's exact
// rebinning, the multinomial noise floor against its closed forms and a simulation, and the metric
// on the Fig. 1 preset (anisotropic Beckmann 0.08 x 0.35, 30°): it falls as the look-up table grows,
// reaches the floor for a large table, and is large against a wrong reference. Then `mesolab sweep
// --metric` end to end, and its errors. No timing assertions.
#include "core/bumpsynth/sweep_metric.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/technique.h"
#include "stats.h"
#include "support/cli.h"
#include "support/errors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::bumpsynth;

namespace {

using Sets = std::vector<std::pair<std::string, std::string>>;

SweepMetricDecl ndf_metric() {
    for (auto& m : Registry::instance().technique("bumpsynth")->sweep_metrics())
        if (m.name == "bumpsynth.ndf_histogram") return m;
    ADD_FAILURE() << "bumpsynth declares no metric bumpsynth.ndf_histogram";
    return {};
}

Scene fig1(const Sets& sets) {
    Scene s = load_preset(test::source_path("presets/bumpsynth/fig1-sphere-distances.json"));
    for (const auto& [k, v] : sets) apply_set(s, k, v);
    return s;
}

Evaluation evaluate(const Scene& s) {
    Session session;
    return session.evaluate_frame(s);
}

// The metric of `point` against `ref` (and the reference's measure, for its floors).
double metric_of(const Scene& point, const SweepMeasure& m) { return m.error(point, evaluate(point)); }
SweepMeasure measure_against(const Scene& ref) { return ndf_metric().prepare(ref, evaluate(ref)); }
double level(const SweepMeasure& m, const std::string& label) {
    for (const auto& [l, v] : m.levels)
        if (l == label) return v;
    ADD_FAILURE() << "no level " << label;
    return 0.0;
}

// n independent draws from q, as bin masses.
std::vector<double> multinomial_sample(const std::vector<double>& q, int n, test::Rng& rng) {
    std::vector<double> cdf(q.size());
    std::partial_sum(q.begin(), q.end(), cdf.begin());
    std::vector<double> p(q.size(), 0.0);
    for (int k = 0; k < n; ++k) {
        const size_t b = size_t(std::upper_bound(cdf.begin(), cdf.end(), rng.uniform() * cdf.back()) - cdf.begin());
        p[std::min(b, q.size() - 1)] += 1.0 / n;
    }
    return p;
}
}  // namespace

// [SECTION] Rebinning and the noise floor
TEST(SweepMetric, NdfBinMassesAreExactAtEveryResolution) {
    const Lobe lobe = Lobe::beckmann(0.08f, 0.35f, 30.f);
    const std::vector<double> q64 = ndf_bin_masses(Ndf::from_lobe(lobe, 64)), q512 = ndf_bin_masses(Ndf::from_lobe(lobe, 512));
    ASSERT_EQ(q64.size(), size_t(kHistogramBins * kHistogramBins));
    EXPECT_NEAR(std::accumulate(q64.begin(), q64.end(), 0.0), 1.0, 1e-12);
    // Cell masses are integrals of D: summed into the same bins they agree whatever the resolution.
    EXPECT_LT(total_variation(q64, q512), 1e-6);
    EXPECT_THROW(ndf_bin_masses(Ndf::from_lobe(lobe, 64), 48), std::invalid_argument);
    EXPECT_THROW(total_variation(q64, std::vector<double>(3, 0.0)), std::invalid_argument);
}

TEST(SweepMetric, MultinomialFloorMatchesClosedFormsAndSimulation) {
    // One sample: E TV = Σ q (1 - q) = 1 - Σ q².
    EXPECT_NEAR(multinomial_tv_floor({0.5, 0.3, 0.2}, 1), 1.0 - (0.25 + 0.09 + 0.04), 1e-12);
    // Mass on every bin, many samples per bin: the normal approximation sqrt(B² (1 - 1/B²) / (2π N)).
    const int B = kHistogramBins;
    const int64_t N = int64_t(1) << 20;
    const std::vector<double> uniform(size_t(B * B), 1.0 / (B * B));
    const double approx = std::sqrt(double(B * B - 1) / (2.0 * std::numbers::pi * double(N)));
    EXPECT_NEAR(multinomial_tv_floor(uniform, N), approx, 0.002 * approx);
    // The Fig. 1 lobe, 1000 samples (many bins with fewer than one expected sample): simulate.
    const std::vector<double> q = ndf_bin_masses(Ndf::from_lobe(Lobe::beckmann(0.08f, 0.35f, 30.f), 128));
    test::Rng rng(7);
    const int trials = 400, n = 1000;
    double mean = 0.0;
    for (int t = 0; t < trials; ++t) mean += total_variation(multinomial_sample(q, n, rng), q) / trials;
    const double floor = multinomial_tv_floor(q, n);
    std::printf("  Fig. 1 lobe, n = %d: floor %.4f, simulated %.4f\n", n, floor, mean);
    EXPECT_NEAR(mean, floor, 0.03 * floor);
}

// [SECTION] The metric on the Fig. 1 preset
TEST(SweepMetric, FallsAsTheLookUpTableGrows) {
    const SweepMeasure m = measure_against(fig1({{"bumpsynth.lut_size", "2048"}}));
    double previous = 1.0;
    for (const char* size : {"16", "64", "256"}) {
        const double tv = metric_of(fig1({{"bumpsynth.lut_size", size}}), m);
        std::printf("  LUT %s: TV %.4f\n", size, tv);
        EXPECT_LT(tv, 0.7 * previous) << size;
        previous = tv;
    }
    EXPECT_GT(metric_of(fig1({{"bumpsynth.lut_size", "16"}}), m), 0.08);  // 256 distinct normals for a lobe over ~100 bins
    EXPECT_LT(previous, 0.03);
}

// With the preset's noise (16 lattice cells per uv unit) the floor is the noise's: one realisation over
// the uv square, its two channels slightly dependent. A large table sits on it. With 256 cells per uv
// unit the noise is nearly independent uniform inputs, and a large table is near the i.i.d. floor.
TEST(SweepMetric, LargeTableReachesTheNoiseFloor) {
    {
        const SweepMeasure m = measure_against(fig1({{"bumpsynth.lut_size", "2048"}}));
        const double tv = metric_of(fig1({{"bumpsynth.lut_size", "1024"}}), m), self = level(m, "reference setting itself");
        std::printf("  noise 16: LUT 1024 %.4f, reference itself %.4f, iid floor %.4f\n", tv, self, level(m, "iid sampling floor"));
        EXPECT_NEAR(tv, self, 0.1 * self);
        EXPECT_GT(self, level(m, "iid sampling floor"));
    }
    {
        const Sets fine{{"bumpsynth.noise_frequency", "256"}};
        Sets ref = fine, point = fine;
        ref.push_back({"bumpsynth.lut_size", "2048"});
        point.push_back({"bumpsynth.lut_size", "1024"});
        const SweepMeasure m = measure_against(fig1(ref));
        const double tv = metric_of(fig1(point), m), floor = level(m, "iid sampling floor");
        std::printf("  noise 256: LUT 1024 %.4f, iid floor %.4f\n", tv, floor);
        EXPECT_GT(floor, 0.002);
        EXPECT_LT(floor, 0.0125);  // sqrt(B² / (2π N)): mass on every bin
        EXPECT_LT(tv, 2.0 * floor);
        EXPECT_GT(tv, 0.5 * floor);
    }
}

TEST(SweepMetric, LargeAgainstAWrongReference) {
    // The same lobe turned by 90°: its long axis where the synthesised normals' short axis is.
    const SweepMeasure m = measure_against(fig1({{"bumpsynth.rotation", "120"}}));
    const double tv = metric_of(fig1({}), m);
    std::printf("  reference turned 90 degrees: TV %.3f\n", tv);
    EXPECT_GT(tv, 0.3);
}

TEST(SweepMetric, NeedsABumpsynthObject) {
    const Scene basic = load_preset(test::source_path("presets/basic/sphere.json"));
    test::expect_input_error([&] { ndf_metric().check(basic); }, {"no object uses technique bumpsynth", "bumpsynth.ndf_histogram"});
    EXPECT_NO_THROW(ndf_metric().check(fig1({})));
}

// [SECTION] mesolab sweep --metric
TEST(SweepMetricCli, WritesTheTableTheFloorAndThePlot) {
    test::TempDir dir("sweep-metric");
    const test::CliResult r = test::run_mesolab(
        "sweep presets/bumpsynth/fig1-sphere-distances.json --knob bumpsynth.lut_size=16,64 --reference bumpsynth.lut_size=256 "
        "--metric bumpsynth.ndf_histogram --size 16x16 --repeat 1 -o '" + dir.path.string() + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string stem = dir / "bumpsynth-fig1-sphere-distances.bumpsynth.lut_size.bumpsynth.ndf_histogram";
    const std::string md = test::slurp(stem + ".md");
    for (const char* s : {"| bumpsynth.lut_size | time (ms) | of which knob's stages (ms) | TV distance |", "| 16 |", "| 64 |", "Noise floor",
                          "stages the knob changes (bumpsynth.lut; the plot's time axis)"})
        EXPECT_NE(md.find(s), std::string::npos) << "missing: " << s << "\n" << md;
    EXPECT_TRUE(std::filesystem::exists(stem + ".png"));
    EXPECT_TRUE(std::filesystem::exists(stem + ".csv"));
    const std::string svg = test::slurp(stem + ".svg");  // the same plot, text as text
    EXPECT_NE(svg.find("<text"), std::string::npos) << svg.substr(0, 500);
    EXPECT_NE(svg.find(">TV distance vs reference</text>"), std::string::npos) << svg.substr(0, 500);
}

TEST(SweepMetricCli, BumpsynthMetricOnAPresetWithoutBumpsynthIsAnInputError) {
    const test::CliResult r = test::run_mesolab("sweep presets/basic/sphere.json --knob geometry.resolution=8 --metric bumpsynth.ndf_histogram -o /tmp/mesolab-never");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("presets/basic/sphere.json"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("no object uses technique bumpsynth"), std::string::npos) << r.err;
}
