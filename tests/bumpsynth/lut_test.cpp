// bumpsynth look-up table (Kautz et al. 2001, §4, §7): the entries, the tangent frames, hard NDFs
// (α = 1e-4 and 1, delta-like, zero regions) with no NaN and no normal outside the support, the
// §7 round trip normal -> (r1, r2) -> normal, and the input CDF G.
#include "core/bumpsynth/lut.h"
#include "core/bumpsynth/ndf.h"
#include "core/error.h"
#include "stats.h"

#include "support/errors.h"
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

using namespace mesolab;
using mesolab::test::expect_input_error;
using mesolab::test::ring_image;
using namespace mesolab::bumpsynth;

namespace {

bool finite(vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Whether the normal lies in a cell of positive mass (or within 1e-6 of one).
bool in_support(const Ndf& ndf, vec3 m) {
    const int R = ndf.resolution();
    for (double dx : {-1e-6, 1e-6})
        for (double dy : {-1e-6, 1e-6}) {
            const int i = std::clamp(int(std::floor((double(m.x) + dx + 1.0) * R / 2)), 0, R - 1);
            const int j = std::clamp(int(std::floor((double(m.y) + dy + 1.0) * R / 2)), 0, R - 1);
            if (ndf.mass(i, j) > 0.0) return true;
        }
    return false;
}

// Every entry: finite, unit m with m_z > 0 inside the NDF's support, orthonormal right-handed frame.
void expect_well_formed(const Lut& lut, const Ndf& ndf, const char* name) {
    ASSERT_GT(lut.size(), 0) << name;
    ASSERT_EQ(lut.entries().size(), size_t(lut.size()) * size_t(lut.size())) << name;
    size_t bad = 0, outside = 0;
    for (const LutEntry& e : lut.entries()) {
        const bool ok = finite(e.m) && finite(e.t) && finite(e.b) && std::fabs(glm::length(e.m) - 1.f) < 1e-5f && e.m.z > 0.f &&
                        std::fabs(glm::length(e.t) - 1.f) < 1e-5f && std::fabs(glm::length(e.b) - 1.f) < 1e-5f &&
                        std::fabs(glm::dot(e.t, e.m)) < 1e-5f && std::fabs(glm::dot(e.b, e.m)) < 1e-5f && std::fabs(glm::dot(e.t, e.b)) < 1e-5f &&
                        glm::length(glm::cross(e.t, e.b) - e.m) < 1e-5f;
        bad += !ok;
        outside += !in_support(ndf, e.m);
    }
    EXPECT_EQ(bad, 0u) << name << ": malformed entries (NaN, not unit, m_z <= 0 or a bad frame)";
    EXPECT_EQ(outside, 0u) << name << ": normals in cells of zero mass";
}

// G for r = u²: G(r) = sqrt(r), knots exact.
InputCdf sqrt_cdf(int n = 1024) {
    std::vector<double> r(size_t(n) + 1), g(size_t(n) + 1);
    for (int k = 0; k <= n; ++k) {
        g[size_t(k)] = double(k) / n;
        r[size_t(k)] = g[size_t(k)] * g[size_t(k)];
    }
    return InputCdf::from_knots(r, g);
}

struct NamedNdf {
    std::string name;
    Ndf ndf;
};

// The hard cases: extreme widths, a delta, zero regions (ring, two separate blobs), a histogram.
std::vector<NamedNdf> hard_cases() {
    std::vector<NamedNdf> v;
    v.push_back({"beckmann 1e-4", Ndf::from_lobe(Lobe::beckmann(1e-4f, 1e-4f))});
    v.push_back({"ggx 1e-4 x 1e-3 @25", Ndf::from_lobe(Lobe::ggx(1e-4f, 1e-3f, 25.f))});
    v.push_back({"ward 1e-4", Ndf::from_lobe(Lobe::ward(1e-4f, 1e-4f))});
    v.push_back({"phong 2e8", Ndf::from_lobe(Lobe::blinn_phong(2e8f))});
    v.push_back({"beckmann 1", Ndf::from_lobe(Lobe::beckmann(1.f, 1.f))});
    v.push_back({"ggx 1", Ndf::from_lobe(Lobe::ggx(1.f, 1.f))});
    v.push_back({"phong 0", Ndf::from_lobe(Lobe::blinn_phong(0.f))});
    v.push_back({"sum sharp + broad", Ndf::from_lobes({Lobe::beckmann(1e-4f, 1e-4f, 0.f, 0.9f), Lobe::ggx(1.f, 1.f, 0.f, 0.1f)})});
    std::vector<float> delta(size_t(512) * 512, 0.f);
    delta[size_t(200) * 512 + 300] = 1.f;  // one pixel at x ~ 0.17, y ~ 0.22
    v.push_back({"delta image", Ndf::from_image(delta, 512, 512)});
    v.push_back({"ring image 0.5..0.7", Ndf::from_image(ring_image(256, 0.5, 0.7), 256, 256)});
    v.push_back({"rim ring 0.97..1", Ndf::from_image(ring_image(512, 0.97, 1.0), 512, 512)});
    std::vector<float> blobs(size_t(64) * 64, 0.f);
    blobs[size_t(10) * 64 + 12] = 1.f;
    blobs[size_t(50) * 64 + 40] = 3.f;
    v.push_back({"two blobs", Ndf::from_image(blobs, 64, 64)});
    v.push_back({"normals histogram",
                 Ndf::from_normals({vec3(0.f, 0.f, 1.f), glm::normalize(vec3(0.5f, -0.2f, 1.f)), vec3(0.f, 1.f, 0.f)})});
    return v;
}

// Position of the normal's cell: its marginal and conditional densities per unit length (to
// restrict the round trip to where float inputs can resolve the CDFs).
void densities(const Ndf& ndf, vec3 m, double& marginal, double& conditional) {
    const int R = ndf.resolution();
    const double h = 2.0 / R;
    const int i = std::clamp(int(std::floor((m.x + 1.0) / h)), 0, R - 1), j = std::clamp(int(std::floor((m.y + 1.0) / h)), 0, R - 1);
    double col = 0.0;
    for (int jj = 0; jj < R; ++jj) col += ndf.mass(i, jj);
    marginal = col / h;
    conditional = col > 0.0 ? ndf.mass(i, j) / col / h : 0.0;
}
}  // namespace

// [SECTION] Entries
TEST(BumpsynthLut, EntriesAreTheMapAtTexelCentres) {
    const Lut lut = build_lut(Ndf::from_lobe(Lobe::ggx(0.15f, 0.5f, 30.f)), 64, sqrt_cdf());
    ASSERT_EQ(lut.size(), 64);
    ASSERT_EQ(lut.entries().size(), size_t(64 * 64));
    for (int b = 0; b < 64; ++b)
        for (int a = 0; a < 64; ++a) {
            const vec2 r((a + 0.5f) / 64.f, (b + 0.5f) / 64.f);
            const LutEntry s = lut.sample(r);
            EXPECT_EQ(lut.at(a, b).m, s.m);
            EXPECT_EQ(lut.at(a, b).t, s.t);
            EXPECT_EQ(lut.lookup(r).m, s.m);
        }
    EXPECT_EQ(lut.lookup(vec2(0.f, 1.f)).m, lut.at(0, 63).m);  // r = 1 clamps to the last texel
}

TEST(BumpsynthLut, FrameIsTheMacroFrameTurnedOntoTheNormal) {
    const LutEntry n = microfacet_frame(vec3(0.f, 0.f, 1.f));
    EXPECT_EQ(n.t, vec3(1.f, 0.f, 0.f));
    EXPECT_EQ(n.b, vec3(0.f, 1.f, 0.f));
    test::Rng rng(5);
    for (int k = 0; k < 1000; ++k) {
        const vec3 m = direction_from_degrees(float(89.9 * rng.uniform()), float(360.0 * rng.uniform()));
        const LutEntry e = microfacet_frame(m), e2 = microfacet_frame(glm::normalize(m + vec3(1e-3f, -1e-3f, 0.f)));
        EXPECT_NEAR(glm::dot(e.t, m), 0.f, 1e-6f);
        EXPECT_NEAR(glm::dot(e.b, m), 0.f, 1e-6f);
        EXPECT_NEAR(glm::length(glm::cross(e.t, e.b) - m), 0.f, 1e-6f);
        // The tangent stays in the plane of the macro tangent's rotation: no twist about n.
        EXPECT_NEAR(e.t.y * (1.f + m.z), -m.x * m.y, 1e-6f);
        EXPECT_LT(glm::length(e.t - e2.t), 1e-2f);  // continuous
    }
}

// [SECTION] Hard cases
TEST(BumpsynthLut, HardCasesHaveNoNanAndNoNormalOutsideTheSupport) {
    for (const NamedNdf& c : hard_cases()) {
        for (bool with_g : {false, true}) {
            const Lut lut = build_lut(c.ndf, Lut::kDefaultSize, with_g ? sqrt_cdf() : InputCdf());
            const std::string name = c.name + (with_g ? " (G = sqrt)" : "");
            expect_well_formed(lut, c.ndf, name.c_str());
            // Random and extreme inputs through the exact map.
            test::Rng rng(11);
            size_t bad = 0;
            const float r1_extreme[6] = {0.f, 1.f, 0.f, 1.f, -3.f, std::nanf("")}, r2_extreme[6] = {0.f, 1.f, 1.f, 0.f, 7.f, 0.5f};
            for (int k = 0; k < 20000; ++k) {
                const vec2 r = k < 6 ? vec2(r1_extreme[k], r2_extreme[k]) : vec2(float(rng.uniform()), float(rng.uniform()));
                const LutEntry e = lut.sample(r);
                bad += !(finite(e.m) && finite(e.t) && finite(e.b) && e.m.z > 0.f && in_support(c.ndf, e.m));
            }
            EXPECT_EQ(bad, 0u) << name;
        }
    }
}

TEST(BumpsynthLut, SharpLobeNormalsStayInTheCentreCells) {
    // α = 1e-4 is far below the table's resolution: every normal lies in the four cells around n.
    const Lut lut = build_lut(Ndf::from_lobe(Lobe::beckmann(1e-4f, 1e-4f)));
    const float h = 2.f / Ndf::kDefaultResolution;
    ASSERT_EQ(lut.entries().size(), size_t(Lut::kDefaultSize) * size_t(Lut::kDefaultSize));
    for (const LutEntry& e : lut.entries()) {
        EXPECT_LE(std::fabs(e.m.x), h);
        EXPECT_LE(std::fabs(e.m.y), h);
    }
}

TEST(BumpsynthLut, ZeroMassRegionsAreNeverSampled) {
    const Ndf ring = Ndf::from_image(ring_image(256, 0.5, 0.7), 256, 256);
    const Lut lut = build_lut(ring);
    const double slack = 2.0 / Ndf::kDefaultResolution * std::sqrt(2.0);  // a cell the ring's edge cuts
    ASSERT_EQ(lut.entries().size(), size_t(Lut::kDefaultSize) * size_t(Lut::kDefaultSize));
    for (const LutEntry& e : lut.entries()) {
        const double r = std::hypot(double(e.m.x), double(e.m.y));
        EXPECT_GE(r, 0.5 - slack);
        EXPECT_LE(r, 0.7 + slack);
    }
    // Zero intervals of M: between the two blobs nothing is drawn.
    std::vector<float> blobs(size_t(64) * 64, 0.f);
    blobs[size_t(10) * 64 + 12] = 1.f;  // x in [-0.625, -0.59375], y in [0.65625, 0.6875]
    blobs[size_t(50) * 64 + 40] = 3.f;  // x in [0.25, 0.28125],     y in [-0.59375, -0.5625]
    const Ndf two = Ndf::from_image(blobs, 64, 64);
    const Lut lut2 = build_lut(two);
    ASSERT_FALSE(lut2.entries().empty());
    size_t first = 0;
    for (const LutEntry& e : lut2.entries()) {
        const bool a = e.m.x >= -0.625f - 1e-6f && e.m.x <= -0.59375f + 1e-6f && e.m.y >= 0.65625f - 1e-6f && e.m.y <= 0.6875f + 1e-6f;
        const bool b = e.m.x >= 0.25f - 1e-6f && e.m.x <= 0.28125f + 1e-6f && e.m.y >= -0.59375f - 1e-6f && e.m.y <= -0.5625f + 1e-6f;
        EXPECT_TRUE(a || b) << e.m.x << "," << e.m.y;
        first += a;
    }
    EXPECT_NEAR(double(first) / double(lut2.entries().size()), 0.25, 0.01);  // mass 1 : 3
}

// [SECTION] Inverse map (§7)
TEST(BumpsynthLut, RoundTripNormalToIndexToNormal) {
    std::vector<NamedNdf> cases;
    cases.push_back({"beckmann 0.15x0.5 @30", Ndf::from_lobe(Lobe::beckmann(0.15f, 0.5f, 30.f))});
    cases.push_back({"ggx 0.3", Ndf::from_lobe(Lobe::ggx(0.3f, 0.3f))});
    cases.push_back({"ggx 1 (mass at the rim)", Ndf::from_lobe(Lobe::ggx(1.f, 1.f))});
    cases.push_back({"ring image", Ndf::from_image(ring_image(256, 0.5, 0.7), 256, 256)});
    cases.push_back({"beckmann 1e-4", Ndf::from_lobe(Lobe::beckmann(1e-4f, 1e-4f))});
    cases.push_back({"sum", Ndf::from_lobes({Lobe::blinn_phong(50.f, 0.3f), Lobe::ggx(0.4f, 0.7f, 60.f, 0.7f)})});
    for (const NamedNdf& c : cases)
        for (bool with_g : {false, true}) {
            const Lut lut = build_lut(c.ndf, Lut::kDefaultSize, with_g ? sqrt_cdf() : InputCdf());
            test::Rng rng(21);
            double worst_xy = 0.0, worst_m = 0.0;
            int tested = 0;
            // (a) normals the table produces; (b) normals spread over the disk where the NDF is positive
            // and its CDFs resolvable with float inputs (marginal and conditional density >= 1e-3 per unit).
            for (int k = 0; k < 40000; ++k) {
                vec3 m;
                if (k % 2 == 0) {
                    m = lut.sample(vec2(float(rng.uniform()), float(rng.uniform()))).m;
                } else {
                    const double x = 2.0 * rng.uniform() - 1.0, y = 2.0 * rng.uniform() - 1.0;
                    if (x * x + y * y > 0.9999) continue;
                    m = vec3(float(x), float(y), float(std::sqrt(1.0 - x * x - y * y)));
                    double md = 0.0, cd = 0.0;
                    densities(c.ndf, m, md, cd);
                    if (!(md >= 1e-3 && cd >= 1e-3)) continue;
                }
                const vec2 r = lut.index(m);
                ASSERT_TRUE(r.x >= 0.f && r.x <= 1.f && r.y >= 0.f && r.y <= 1.f) << c.name;
                const vec3 m2 = lut.sample(r).m;
                worst_xy = std::max(worst_xy, double(glm::length(vec2(m2) - vec2(m))));
                // m_z = sqrt(1 - x² - y²) amplifies projected errors by 1/m_z at the horizon.
                if (m.z >= 0.01f) worst_m = std::max(worst_m, double(glm::length(m2 - m)));
                ++tested;
            }
            EXPECT_LT(worst_xy, 1e-4) << c.name << (with_g ? " (G = sqrt)" : "");
            EXPECT_LT(worst_m, 1e-3) << c.name << (with_g ? " (G = sqrt)" : "");
            std::printf("  round trip %-26s %-8s %5d normals: worst |(x,y)' - (x,y)| = %.1e, worst |m' - m| (m_z >= 0.01) = %.1e\n", c.name.c_str(),
                        with_g ? "G = sqrt" : "G = id", tested, worst_xy, worst_m);
        }
}

TEST(BumpsynthLut, IndexOfTheMacroNormalIsTheCentreForSymmetricNdfs) {
    const Lut lut = build_lut(Ndf::from_lobe(Lobe::ggx(0.3f, 0.3f)));
    const vec2 r = lut.index(vec3(0.f, 0.f, 1.f));
    EXPECT_NEAR(r.x, 0.5f, 1e-6f);
    EXPECT_NEAR(r.y, 0.5f, 1e-6f);
    // With G = sqrt: G⁻¹(1/2) = 1/4.
    const Lut lut_g = build_lut(Ndf::from_lobe(Lobe::ggx(0.3f, 0.3f)), Lut::kDefaultSize, sqrt_cdf());
    EXPECT_NEAR(lut_g.index(vec3(0.f, 0.f, 1.f)).x, 0.25f, 1e-6f);
}

TEST(BumpsynthLut, IndexIsFiniteForAnyInput) {
    const Lut lut = build_lut(Ndf::from_image(ring_image(256, 0.5, 0.7), 256, 256), Lut::kDefaultSize, sqrt_cdf());
    test::Rng rng(8);
    std::vector<vec3> ms{vec3(0.f), vec3(std::nanf(""), 0.f, 1.f), vec3(0.f, 0.f, -1.f), vec3(0.3f, 0.4f, -0.5f), vec3(1.f, 0.f, 0.f), vec3(0.f, 0.f, 1.f)};
    for (int k = 0; k < 10000; ++k) ms.push_back(vec3(float(2 * rng.uniform() - 1), float(2 * rng.uniform() - 1), float(2 * rng.uniform() - 1)));
    for (const vec3& m : ms) {
        const vec2 r = lut.index(m);
        ASSERT_TRUE(r.x >= 0.f && r.x <= 1.f && r.y >= 0.f && r.y <= 1.f) << m.x << "," << m.y << "," << m.z;
        const LutEntry e = lut.sample(r);
        ASSERT_TRUE(finite(e.m) && e.m.z > 0.f);
    }
}

// [SECTION] Quantised table
TEST(BumpsynthLut, NearestLookupQuantisationShrinksWithTheTableSize) {
    // With nearest lookup each entry stands for a 1/S x 1/S square of inputs. Binned on B x B bins,
    // an entry whose square straddles a bin edge is counted on one side only, so each of the B - 1
    // x edges moves at most 1/(2S) of the mass, and each of the B - 1 y edges at most 1/(2S) of
    // every column: the total variation distance to the NDF's bin masses is <= (B - 1)/S, and falls
    // like 1/S. (Visible to a 200k-sample χ² at S = 256, which is why the χ² tests use sample().)
    const int B = 16;
    for (const Lobe& lobe : {Lobe::beckmann(0.3f, 0.3f), Lobe::ggx(0.15f, 0.5f, 30.f)}) {
        const Ndf ndf = Ndf::from_lobe(lobe);
        const int c = ndf.resolution() / B;
        std::vector<double> p(size_t(B) * B, 0.0);
        for (int j = 0; j < ndf.resolution(); ++j)
            for (int i = 0; i < ndf.resolution(); ++i) p[size_t(j / c) * B + size_t(i / c)] += ndf.mass(i, j);
        double tv[2] = {0.0, 0.0};
        const int sizes[2] = {256, 1024};
        for (int s = 0; s < 2; ++s) {
            const Lut lut = build_lut(ndf, sizes[s]);
            std::vector<double> q(size_t(B) * B, 0.0);
            for (const LutEntry& e : lut.entries()) {
                const int bx = std::clamp(int((e.m.x + 1.f) * 0.5f * B), 0, B - 1), by = std::clamp(int((e.m.y + 1.f) * 0.5f * B), 0, B - 1);
                q[size_t(by) * B + size_t(bx)] += 1.0 / double(lut.entries().size());
            }
            for (size_t k = 0; k < p.size(); ++k) tv[s] += 0.5 * std::fabs(p[k] - q[k]);
            EXPECT_LE(tv[s], double(B - 1) / sizes[s]);
        }
        std::printf("  nearest lookup, kind %d, %d^2 bins: total variation %.2e (S = 256), %.2e (S = 1024)\n", int(lobe.kind()), B, tv[0], tv[1]);
        EXPECT_LT(tv[1], 0.5 * tv[0]);
    }
}

// [SECTION] Input CDF G
TEST(BumpsynthInputCdf, IdentityByDefault) {
    const InputCdf G;
    EXPECT_TRUE(G.is_identity());
    for (double r : {0.0, 0.25, 0.7, 1.0}) {
        EXPECT_EQ(G(r), r);
        EXPECT_EQ(G.inverse(r), r);
    }
    EXPECT_EQ(G(-1.0), 0.0);
    EXPECT_EQ(G(2.0), 1.0);
    EXPECT_EQ(G(std::nan("")), 0.0);
}

TEST(BumpsynthInputCdf, MeasuredFromSquaredUniformsApproachesSqrt) {
    test::Rng rng(31);
    std::vector<float> s(1000000);
    for (float& v : s) {
        const double u = rng.uniform();
        v = float(u * u);
    }
    const InputCdf combined = measure_input_cdf(s);
    const InputCdf count = measure_input_cdf(s, 1024, CdfBinning::equal_count);
    const InputCdf width = measure_input_cdf(s, 1024, CdfBinning::equal_width);
    double worst_combined = 0.0, worst_count = 0.0, worst_width = 0.0;
    for (int k = 0; k <= 10000; ++k) {
        const double r = k / 10000.0;
        worst_combined = std::max(worst_combined, std::fabs(combined(r) - std::sqrt(r)));
        worst_count = std::max(worst_count, std::fabs(count(r) - std::sqrt(r)));
        if (r >= 0.01) worst_width = std::max(worst_width, std::fabs(width(r) - std::sqrt(r)));
        // G⁻¹ inverts G.
        EXPECT_NEAR(combined(combined.inverse(r)), r, 1e-9);
    }
    std::printf("  measured G for r = u^2 (1M samples): max |G - sqrt| = %.2e (combined, 4096 bins), %.2e (equal count, 1024), %.2e (equal width, 1024, r >= 0.01)\n",
                worst_combined, worst_count, worst_width);
    EXPECT_LT(worst_combined, 3e-3);  // the Kolmogorov-Smirnov scale 1.36/sqrt(N) = 1.4e-3 at the 5% level
    EXPECT_LT(worst_count, 3e-3);
    EXPECT_LT(worst_width, 3e-3);
}

TEST(BumpsynthInputCdf, InverseTakesTheMiddleOfAFlatPart) {
    // Inputs never in [0.4, 0.6]: G is flat there at 0.5.
    const InputCdf G = InputCdf::from_knots({0.0, 0.4, 0.6, 1.0}, {0.0, 0.5, 0.5, 1.0});
    EXPECT_NEAR(G.inverse(0.5), 0.5, 1e-12);
    EXPECT_NEAR(G.inverse(0.25), 0.2, 1e-12);
    EXPECT_NEAR(G(G.inverse(0.75)), 0.75, 1e-12);
    const InputCdf T = InputCdf::tabulated({0.f, 0.1f, 0.9f, 1.f});
    EXPECT_NEAR(T(1.0 / 3.0), 0.1, 1e-7);
    EXPECT_NEAR(T.inverse(0.5), 0.5, 1e-7);
}

TEST(BumpsynthInputCdf, BadCdfsAreInputErrors) {
    expect_input_error([] { InputCdf::tabulated({0.f, 0.6f, 0.5f, 1.f}); }, {"bumpsynth.input_cdf", "non-decreasing"});
    expect_input_error([] { InputCdf::tabulated({0.f, 0.5f, 0.9f}); }, {"bumpsynth.input_cdf", "end at 1"});
    expect_input_error([] { InputCdf::tabulated({0.f}); }, {"bumpsynth.input_cdf", "at least 2"});
    expect_input_error([] { InputCdf::tabulated({0.f, std::nanf(""), 1.f}); }, {"bumpsynth.input_cdf", "not finite"});
    expect_input_error([] { InputCdf::from_knots({0.0, 0.5, 0.5, 1.0}, {0.0, 0.2, 0.4, 1.0}); }, {"bumpsynth.input_cdf", "abscissa"});
    expect_input_error([] { InputCdf::from_knots({0.1, 1.0}, {0.0, 1.0}); }, {"bumpsynth.input_cdf", "span [0, 1]"});
    expect_input_error([] { measure_input_cdf({}); }, {"bumpsynth.input_samples"});
    expect_input_error([] { measure_input_cdf({0.5f, std::nanf("")}); }, {"bumpsynth.input_samples", "sample 1"});
    expect_input_error([] { measure_input_cdf({0.5f}, 0); }, {"bumpsynth.input_cdf_bins"});
    expect_input_error([] { build_lut(Ndf::from_lobe(Lobe::ggx(0.3f, 0.3f)), 1); }, {"bumpsynth.lut_size: value 1 must be in [2, 4096]"});
}
