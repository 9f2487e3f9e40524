// bumpsynth §4 goodness of fit: normals drawn through the look-up table from random (r1, r2)
// follow the NDF. Pearson's χ² over a 32 x 32 grid of bins on the disk (aligned with the 128²
// table: 4 x 4 cells per bin), bins with expected count < 5 pooled, 200k samples per test, fixed
// seeds. Expected counts of the analytic lobes come from the independent textbook closed forms
// (stats.h) integrated over each bin (midpoint rule, 32² points per bin), so a test fails for a
// wrong tabulation as well as for a wrong inversion. Level: Šidák-corrected α = 0.01 over the
// kChi2Tests tests of this file; critical values from the regularised incomplete gamma function,
// cross-checked against the Wilson-Hilferty approximation.
#include "core/bumpsynth/lut.h"
#include "core/bumpsynth/ndf.h"
#include "core/bumpsynth/noise.h"
#include "stats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <vector>

using namespace mesolab;
using namespace mesolab::bumpsynth;

namespace {

constexpr int kChi2Tests = 13;       // the χ² tests in this file (for the Šidák correction)
constexpr double kFamilyAlpha = 0.01;
constexpr long kSamples = 200000;
constexpr int kBins = 32;            // per axis
constexpr int kResolution = 128;     // NDF table (a multiple of kBins)
constexpr int kSub = 32;             // midpoint points per bin and axis for the expected counts

int bin_of(vec3 m) {
    const int bx = std::clamp(int(std::floor((double(m.x) + 1.0) * 0.5 * kBins)), 0, kBins - 1);
    const int by = std::clamp(int(std::floor((double(m.y) + 1.0) * 0.5 * kBins)), 0, kBins - 1);
    return by * kBins + bx;
}

// Bin probabilities of a density f(x, y) over the disk (midpoint rule); `total` gets ∫ f before
// the normalisation (1 for a normalised closed form).
std::vector<double> bin_probabilities(const std::function<double(double, double)>& f, double& total) {
    std::vector<double> p(size_t(kBins) * kBins, 0.0);
    const double bw = 2.0 / kBins, sw = bw / kSub;
    total = 0.0;
    for (int by = 0; by < kBins; ++by)
        for (int bx = 0; bx < kBins; ++bx) {
            double s = 0.0;
            for (int sy = 0; sy < kSub; ++sy)
                for (int sx = 0; sx < kSub; ++sx) {
                    const double x = -1.0 + bx * bw + (sx + 0.5) * sw, y = -1.0 + by * bw + (sy + 0.5) * sw;
                    if (x * x + y * y < 1.0) s += f(x, y);
                }
            p[size_t(by) * kBins + size_t(bx)] = s * sw * sw;
            total += s * sw * sw;
        }
    for (double& v : p) v /= total;
    return p;
}

// Bin probabilities straight from the table's cell masses (for NDFs without a closed form).
std::vector<double> bin_probabilities(const Ndf& ndf) {
    std::vector<double> p(size_t(kBins) * kBins, 0.0);
    const int c = ndf.resolution() / kBins;
    for (int j = 0; j < ndf.resolution(); ++j)
        for (int i = 0; i < ndf.resolution(); ++i) p[size_t(j / c) * kBins + size_t(i / c)] += ndf.mass(i, j);
    return p;
}

// Histogram of kSamples normals sample(r) for inputs r from `input`.
std::vector<long> histogram(const Lut& lut, const std::function<double(test::Rng&)>& input, uint64_t seed) {
    test::Rng rng(seed);
    std::vector<long> h(size_t(kBins) * kBins, 0);
    for (long k = 0; k < kSamples; ++k) {
        const float r1 = float(input(rng)), r2 = float(input(rng));
        ++h[size_t(bin_of(lut.sample(vec2(r1, r2)).m))];
    }
    return h;
}

double uniform_input(test::Rng& rng) { return rng.uniform(); }

void expect_fit(const char* name, const std::vector<double>& prob, const std::vector<long>& counts) {
    const double alpha = test::sidak(kFamilyAlpha, kChi2Tests);
    const test::Chi2Result r = test::chi2_test(prob, counts, kSamples, alpha);
    std::printf("  chi2 %-44s N=%ld bins=%d (pooled %d) dof=%d chi2=%.1f p=%.3f critical(alpha=%.2e)=%.1f [Wilson-Hilferty %.1f]\n", name,
                kSamples, r.bins, r.pooled_bins, r.dof, r.chi2, r.p, alpha, r.critical, r.critical_wh);
    EXPECT_EQ(r.observed_in_empty, 0) << name << ": samples in bins of zero probability";
    EXPECT_LT(r.chi2, r.critical) << name << ": p = " << r.p;
    EXPECT_NEAR(r.critical_wh / r.critical, 1.0, 5e-3);  // the two critical values agree
}

// A closed-form lobe as a density over (x, y): D(θ, φ) in the lobe frame.
std::function<double(double, double)> reference(double (*D)(double, double, double, double), double ax, double ay, double rot_deg) {
    return [=](double x, double y) {
        double th = 0.0, ph = 0.0;
        test::to_lobe_angles(x, y, rot_deg, th, ph);
        return D(th, ph, ax, ay);
    };
}

void expect_lobe_fit(const char* name, const Lobe& lobe, double (*ref)(double, double, double, double), uint64_t seed) {
    double total = 0.0;
    const std::vector<double> prob = bin_probabilities(reference(ref, lobe.alpha_x(), lobe.alpha_y(), lobe.rotation_deg()), total);
    EXPECT_NEAR(total, 1.0, 2e-3) << name << ": the textbook closed form integrates to " << total;
    const Lut lut = build_lut(Ndf::from_lobe(lobe, kResolution));
    expect_fit(name, prob, histogram(lut, uniform_input, seed));
}
}  // namespace

TEST(BumpsynthChi2, UniformInputsFollowIsotropicBeckmann) {
    expect_lobe_fit("beckmann 0.3 x 0.3, uniform r", Lobe::beckmann(0.3f, 0.3f), test::ref_beckmann, 101);
}

TEST(BumpsynthChi2, UniformInputsFollowAnisotropicRotatedBeckmann) {
    expect_lobe_fit("beckmann 0.15 x 0.5 @30deg, uniform r", Lobe::beckmann(0.15f, 0.5f, 30.f), test::ref_beckmann, 102);
}

TEST(BumpsynthChi2, UniformInputsFollowIsotropicGgx) {
    expect_lobe_fit("ggx 0.3 x 0.3, uniform r", Lobe::ggx(0.3f, 0.3f), test::ref_ggx, 103);
}

TEST(BumpsynthChi2, UniformInputsFollowAnisotropicRotatedGgx) {
    expect_lobe_fit("ggx 0.15 x 0.5 @30deg, uniform r", Lobe::ggx(0.15f, 0.5f, 30.f), test::ref_ggx, 104);
}

TEST(BumpsynthChi2, UniformInputsFollowAnisotropicRotatedWard) {
    const Lobe lobe = Lobe::ward(0.2f, 0.4f, -45.f);
    double total = 0.0;
    const std::vector<double> prob = bin_probabilities(reference(test::ref_ward_unnormalised, 0.2, 0.4, -45.0), total);
    EXPECT_NEAR(total * lobe.ward_constant(), 1.0, 2e-3);  // K normalises the Gaussian
    expect_fit("ward 0.2 x 0.4 @-45deg, uniform r", prob, histogram(build_lut(Ndf::from_lobe(lobe, kResolution)), uniform_input, 105));
}

TEST(BumpsynthChi2, UniformInputsFollowASumOfLobes) {
    const std::vector<Lobe> lobes{Lobe::blinn_phong(50.f, 0.3f), Lobe::ggx(0.4f, 0.7f, 60.f, 0.7f)};
    double total = 0.0;
    const std::vector<double> prob = bin_probabilities(
        [](double x, double y) {
            double th = 0.0, ph = 0.0;
            test::to_lobe_angles(x, y, 60.0, th, ph);
            return 0.3 * test::ref_phong(th, 50.0) + 0.7 * test::ref_ggx(th, ph, 0.4, 0.7);
        },
        total);
    EXPECT_NEAR(total, 1.0, 2e-3);
    expect_fit("0.3 phong 50 + 0.7 ggx 0.4 x 0.7 @60deg, uniform r", prob,
               histogram(build_lut(Ndf::from_lobes(lobes, kResolution)), uniform_input, 106));
}

TEST(BumpsynthChi2, SquaredInputsThroughTheirKnownCdfFollowAnisotropicGgx) {
    // r = u² has G(r) = sqrt(r): knots at r_k = (k/n)², G_k = k/n (exact at the knots).
    const int n = 4096;
    std::vector<double> r(n + 1), g(n + 1);
    for (int k = 0; k <= n; ++k) {
        g[size_t(k)] = double(k) / n;
        r[size_t(k)] = g[size_t(k)] * g[size_t(k)];
    }
    const Lobe lobe = Lobe::ggx(0.15f, 0.5f, 30.f);
    double total = 0.0;
    const std::vector<double> prob = bin_probabilities(reference(test::ref_ggx, 0.15, 0.5, 30.0), total);
    const Lut lut = build_lut(Ndf::from_lobe(lobe, kResolution), Lut::kDefaultSize, InputCdf::from_knots(r, g));
    expect_fit("ggx 0.15 x 0.5 @30deg, r = u^2, known G", prob,
               histogram(lut, [](test::Rng& rng) { const double u = rng.uniform(); return u * u; }, 107));
}

TEST(BumpsynthChi2, TriangularInputsThroughAMeasuredCdfFollowAnisotropicBeckmann) {
    // r = (u + v)/2, a bell-shaped density like the paper's turbulence; G measured numerically from
    // 2M independent samples (measure_input_cdf defaults: 4096 bins, combined knots). With equal-count
    // knots alone (sparse in the fading tails) this test sees a bias: mean χ² - dof about +60.
    const auto triangular = [](test::Rng& rng) { return 0.5 * (rng.uniform() + rng.uniform()); };
    test::Rng rng(999);
    std::vector<float> samples(2000000);
    for (float& s : samples) s = float(triangular(rng));
    const InputCdf G = measure_input_cdf(samples);
    const Lobe lobe = Lobe::beckmann(0.15f, 0.5f, 30.f);
    double total = 0.0;
    const std::vector<double> prob = bin_probabilities(reference(test::ref_beckmann, 0.15, 0.5, 30.0), total);
    const Lut lut = build_lut(Ndf::from_lobe(lobe, kResolution), Lut::kDefaultSize, G);
    expect_fit("beckmann 0.15 x 0.5 @30deg, r = (u+v)/2, measured G", prob, histogram(lut, triangular, 108));
}

TEST(BumpsynthChi2, UniformInputsFollowARingNdfAndNeverItsZeroRegions) {
    const int n = 256;
    std::vector<float> img(size_t(n) * n, 0.f);
    for (int py = 0; py < n; ++py)
        for (int px = 0; px < n; ++px) {
            const double x = -1.0 + (px + 0.5) * 2.0 / n, y = 1.0 - (py + 0.5) * 2.0 / n, r = std::hypot(x, y);
            if (r >= 0.5 && r <= 0.7) img[size_t(py) * n + size_t(px)] = float(1.0 + x);  // uneven around the ring
        }
    const Ndf ndf = Ndf::from_image(img, n, n, kResolution);
    expect_fit("ring 0.5..0.7 (image), uniform r", bin_probabilities(ndf), histogram(build_lut(ndf), uniform_input, 109));
}

// [SECTION] The real noise-driven inputs (§4, §5.1): synthesised normals taken uniformly over the
// surface (uniform random uv on the noise's periodic square) at full detail (all K octaves), through
// the measured G_K and the table's exact map. The normals of one surface are spatially correlated,
// but points drawn independently and uniformly over the periodic square give independent draws from
// the field's own distribution, which G_K was measured on (stratified, per channel): the χ² test
// applies. What is left is the dependence between the two channels over a finite square (~1/sqrt of
// the lattice cells, noise.h), kept below what 200k samples resolve by a first octave of 256² cells.
namespace {
void expect_noise_fit(const char* name, const Lobe& lobe, double (*ref)(double, double, double, double), uint64_t seed) {
    NoiseParams np;
    np.base_frequency = 256;
    np.octaves_max = 4;
    np.seed = uint32_t(seed);
    const NoiseCdfs cdfs = measure_noise_cdfs(np, 1024);
    double total = 0.0;
    const std::vector<double> prob = bin_probabilities(reference(ref, lobe.alpha_x(), lobe.alpha_y(), lobe.rotation_deg()), total);
    const Lut lut = build_lut(Ndf::from_lobe(lobe, kResolution));
    test::Rng rng(seed);
    std::vector<long> h(size_t(kBins) * kBins, 0);
    for (long k = 0; k < kSamples; ++k) {
        const vec2 uv(float(rng.uniform()), float(rng.uniform()));
        const vec2 u = noise_inputs(cdfs, uv, np.octaves_max);
        ++h[size_t(bin_of(lut.sample(u).m))];
    }
    expect_fit(name, prob, h);
}
}  // namespace

TEST(BumpsynthChi2, NoiseInputsFollowIsotropicBeckmann) {
    expect_noise_fit("beckmann 0.3 x 0.3, noise r", Lobe::beckmann(0.3f, 0.3f), test::ref_beckmann, 201);
}

TEST(BumpsynthChi2, NoiseInputsFollowAnisotropicRotatedBeckmann) {
    expect_noise_fit("beckmann 0.15 x 0.5 @30deg, noise r", Lobe::beckmann(0.15f, 0.5f, 30.f), test::ref_beckmann, 202);
}

TEST(BumpsynthChi2, NoiseInputsFollowIsotropicGgx) {
    expect_noise_fit("ggx 0.3 x 0.3, noise r", Lobe::ggx(0.3f, 0.3f), test::ref_ggx, 203);
}

TEST(BumpsynthChi2, NoiseInputsFollowAnisotropicRotatedGgx) {
    expect_noise_fit("ggx 0.15 x 0.5 @30deg, noise r", Lobe::ggx(0.15f, 0.5f, 30.f), test::ref_ggx, 204);
}
