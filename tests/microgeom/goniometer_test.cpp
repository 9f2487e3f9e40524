// The virtual goniometer (microgeom, Heidrich et al. 2000 §6): the simulated BRDF of a flat
// field is Lambert, a white furnace stays white, the table look-up, the fast tabulation against
// single goniometer images, reciprocity, the spherical-harmonics fit, BTF slices, bad settings.
#include "core/error.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/ellipse.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/scatter.h"
#include "support/threads.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

// A procedural field, optionally with one albedo everywhere (the colour rules replaced).
Heightfield field(const char* name, int res, vec3 albedo = vec3(-1.f)) {
    ProceduralParams p;
    p.name = name;
    p.resolution = res;
    Heightfield hf = make_procedural(p);
    if (albedo.x >= 0.f) hf.albedo.assign(hf.albedo.size(), albedo);
    return hf;
}

struct Setup {
    Heightfield hf;
    DirectionSet dirs;
    Visibility vis;
};

std::unique_ptr<Setup> setup(const char* name, int res, int n_dirs, vec3 albedo = vec3(-1.f)) {
    auto s = std::make_unique<Setup>();
    s->hf = field(name, res, albedo);
    s->dirs = make_direction_set(n_dirs);
    s->vis = compute_visibility(s->hf, s->dirs);
    return s;
}

float rel_diff(vec3 a, vec3 b) {
    const float d = glm::length(a - b), m = std::max(glm::length(a), glm::length(b));
    return m > 0.f ? d / m : 0.f;
}

// Bricks 32x32, 64 directions, depth 1, a 6x6 node table with a Blinn-Phong lobe: shared by the
// look-up tests.
struct BricksTable {
    std::unique_ptr<Setup> s;
    GonioSettings g;
    SimulatedBrdf brdf;
};

const BricksTable& bricks_table() {
    static const BricksTable t = [] {
        BricksTable b;
        b.s = setup("bricks", 32, 64);
        b.g.scatter.depth = 1;
        b.g.resolution = 6;
        b.g.phong = true;
        b.g.ks = vec3(0.3f);
        b.g.shininess = 20.f;
        b.brdf = simulate_brdf(b.s->hf, b.s->dirs, b.s->vis, b.g);
        return b;
    }();
    return t;
}
}  // namespace

// [SECTION] Analytic cases
TEST(Goniometer, FlatFieldIsLambertTimesCosineAndEnvIsAlbedo) {
    const vec3 rho(0.5f, 0.4f, 0.3f);
    const auto s = setup("flat", 16, 64, rho);
    GonioSettings g;
    g.scatter.depth = 2;
    g.scatter.shadows = false;  // §4's interpolation shadows a flat field near grazing (coarse triangles straddle the horizon)
    g.resolution = 8;
    std::vector<double> reported;
    const SimulatedBrdf b = simulate_brdf(s->hf, s->dirs, s->vis, g, [&](double f) { reported.push_back(f); });
    ASSERT_FALSE(reported.empty());
    EXPECT_TRUE(std::is_sorted(reported.begin(), reported.end())) << "progress never goes back";
    EXPECT_DOUBLE_EQ(reported.back(), 1.0);
    ASSERT_EQ(b.n_theta, 8);
    ASSERT_EQ(b.n_phi, 8);
    ASSERT_EQ(b.table.size(), size_t(64 * 64));
    EXPECT_EQ(b.images, 1 + 1 + 7 * 8) << "one solve for env, one for the pole, one per other light node";
    // Node (i, j) lies at theta = i/(n_theta - 1) 90 degrees, phi = j 360/n_phi degrees.
    for (int i = 0; i < b.n_theta; ++i)
        for (int j = 0; j < b.n_phi; ++j) {
            const vec3 want = direction_from_degrees(float(i) * 90.f / float(b.n_theta - 1), float(j) * 360.f / float(b.n_phi));
            ASSERT_LT(glm::distance(b.node_direction(i, j), want), 1e-6f) << i << "," << j;
        }
    for (int a = 0; a < b.nodes(); ++a)
        for (int v = 0; v < b.nodes(); ++v) {
            const double cos_l = std::cos(0.5 * 3.14159265358979323846 * double(a / b.n_phi) / double(b.n_theta - 1));
            const vec3 want = rho * kInvPi * float(cos_l), got = b.table[size_t(a) * size_t(b.nodes()) + size_t(v)];
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(got[c], want[c], 1e-4f * want[c] + 1e-7f) << "light node " << a << " view node " << v;
        }
    for (int v = 0; v < b.nodes(); ++v)
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(b.env[size_t(v)][c], rho[c], 1e-4f * rho[c]) << "view node " << v;
    // Between the nodes: bilinear in theta of cos(theta) is within h^2/8 = 0.0063 (h = 12.9 deg).
    for (int k = 0; k < 50; ++k) {
        const vec3 wi = direction_from_degrees(float(k * 37 % 89) + 0.3f, float(k * 71 % 360) + 0.7f);
        const vec3 wo = direction_from_degrees(float(k * 53 % 89) + 0.1f, float(k * 29 % 360) + 0.2f);
        const vec3 got = b.eval(wi, wo), want = rho * kInvPi * wi.z;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(got[c], want[c], 0.007f * rho[c] * kInvPi) << k;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(b.eval_env(wo)[c], rho[c], 1e-4f * rho[c]) << k;
    }
}

TEST(Goniometer, WhiteFurnaceEnvironmentStaysWhite) {
    const auto s = setup("bumps", 32, 100, vec3(1.f));
    GonioSettings g;
    g.scatter.depth = 8;
    g.resolution = 8;
    const SimulatedBrdf b = simulate_brdf(s->hf, s->dirs, s->vis, g);
    float worst = 0.f;
    for (int i = 0; i < b.n_theta; ++i)
        for (int j = 0; j < b.n_phi; ++j) {
            if (float(i) / float(b.n_theta - 1) * 90.f >= 80.f) continue;
            const float e = b.env[size_t(i * b.n_phi + j)].x;
            worst = std::max(worst, std::abs(e - 1.f));
            EXPECT_NEAR(e, 1.f, 0.02f) << "theta node " << i << " phi node " << j;
        }
    std::printf("furnace: max |T_env - 1| = %.2e\n", double(worst));
}

// [SECTION] Look-up
TEST(Goniometer, EvalReproducesTableAtNodes) {
    const BricksTable& t = bricks_table();
    const SimulatedBrdf& b = t.brdf;
    const int N = b.nodes();
    for (int a = 0; a < N; ++a)
        for (int v = 0; v < N; ++v) {
            const vec3 wi = b.node_direction(a / b.n_phi, a % b.n_phi), wo = b.node_direction(v / b.n_phi, v % b.n_phi);
            const vec3 want = b.table[size_t(a) * size_t(N) + size_t(v)];
            ASSERT_LE(glm::length(b.eval(wi, wo) - want), 1e-5f * glm::length(want) + 1e-7f) << a << "," << v;
        }
    for (int v = 0; v < N; ++v) {
        const vec3 wo = b.node_direction(v / b.n_phi, v % b.n_phi);
        ASSERT_LE(glm::length(b.eval_env(wo) - b.env[size_t(v)]), 1e-5f * glm::length(b.env[size_t(v)])) << v;
    }
}

TEST(Goniometer, EvalIsContinuousAcrossPhiZero) {
    const SimulatedBrdf& b = bricks_table().brdf;
    float max_value = 0.f;
    for (const vec3& x : b.table) max_value = std::max(max_value, std::max(x.x, std::max(x.y, x.z)));
    for (float theta_i : {10.f, 37.f, 71.f})
        for (float theta_o : {5.f, 44.f, 83.f}) {
            const float eps = 1e-3f;
            const vec3 below = b.eval(direction_from_degrees(theta_i, 360.f - eps), direction_from_degrees(theta_o, 360.f - eps));
            const vec3 above = b.eval(direction_from_degrees(theta_i, eps), direction_from_degrees(theta_o, eps));
            const vec3 at = b.eval(direction_from_degrees(theta_i, 0.f), direction_from_degrees(theta_o, 0.f));
            EXPECT_LE(glm::length(below - above), 1e-4f * max_value) << theta_i << "," << theta_o;
            EXPECT_LE(glm::length(at - above), 1e-4f * max_value) << theta_i << "," << theta_o;
            EXPECT_LE(glm::length(b.eval_env(direction_from_degrees(theta_o, 360.f - eps)) - b.eval_env(direction_from_degrees(theta_o, eps))),
                      1e-4f);
        }
}

TEST(Goniometer, BelowHorizonIsZeroAndGrazingIsFinite) {
    const BricksTable& t = bricks_table();
    const SimulatedBrdf& b = t.brdf;
    const vec3 up(0.f, 0.f, 1.f), down(0.3f, 0.f, -0.01f), flat_dir(1.f, 0.f, 0.f);
    for (const vec3& w : {down, flat_dir, vec3(0.f)}) {
        EXPECT_EQ(b.eval(w, up), vec3(0.f));
        EXPECT_EQ(b.eval(up, w), vec3(0.f));
        EXPECT_EQ(b.eval_env(w), vec3(0.f));
        EXPECT_EQ(goniometer_average(t.s->hf, t.s->dirs, t.s->vis, t.g, w, up), vec3(0.f));
    }
    const vec3 grazing = direction_from_degrees(89.9f, 123.f), light = direction_from_degrees(30.f, 10.f);
    for (const vec3& r : {b.eval(grazing, light), b.eval(light, grazing), b.eval(grazing, grazing), b.eval_env(grazing),
                          goniometer_average(t.s->hf, t.s->dirs, t.s->vis, t.g, light, grazing),
                          goniometer_average(t.s->hf, t.s->dirs, t.s->vis, t.g, grazing, grazing)})
        for (int c = 0; c < 3; ++c) {
            EXPECT_TRUE(std::isfinite(r[c]));
            EXPECT_GE(r[c], 0.f);
        }
    EXPECT_GT(b.eval(light, grazing).x, 0.f) << "the grazing limit, not 0/0";
}

// [SECTION] Tabulation against single goniometer images
TEST(Goniometer, TableEqualsSingleImageAveragesAtNodes) {
    const BricksTable& t = bricks_table();
    const SimulatedBrdf& b = t.brdf;
    // Light and view nodes off the horizon (the view horizon is simulated kGonioHorizonEps above).
    for (const auto& [il, jl, iv, jv] : {std::array<int, 4>{0, 0, 0, 0}, {1, 2, 3, 5}, {4, 1, 2, 0}, {2, 3, 4, 3}, {3, 0, 1, 4}, {0, 3, 4, 1}}) {
        const vec3 wi = b.node_direction(il, jl), wo = b.node_direction(iv, jv);
        const vec3 want = goniometer_average(t.s->hf, t.s->dirs, t.s->vis, t.g, wi, wo);
        const vec3 got = b.table[size_t(il * b.n_phi + jl) * size_t(b.nodes()) + size_t(iv * b.n_phi + jv)];
        EXPECT_LE(rel_diff(got, want), 1e-4f) << il << "," << jl << " -> " << iv << "," << jv;
    }
}

TEST(Goniometer, StraightDownViewIsThePlainMeanOfTheLightImage) {
    const auto s = setup("bricks", 32, 100);
    GonioSettings g;
    g.scatter.depth = 1;
    const vec3 wi = direction_from_degrees(40.f, 30.f);
    ScatterSettings ss = g.scatter;
    ss.light_dir = wi;
    ss.light_E = vec3(1.f);
    const ScatterResult r = scatter(s->hf, s->dirs, s->vis, ss);
    double mean[3] = {0, 0, 0};
    for (size_t p = 0; p < r.direct.size(); ++p) {
        const vec3 L = r.direct[p] + s->hf.albedo[p] * kInvPi * r.E_indirect[p];
        for (int c = 0; c < 3; ++c) mean[c] += double(L[c]) / double(r.direct.size());
    }
    const vec3 got = goniometer_average(s->hf, s->dirs, s->vis, g, wi, vec3(0.f, 0.f, 1.f));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(double(got[c]), mean[c], 1e-3 * mean[c]) << c;
}

TEST(Goniometer, ImageMaskedMeanEqualsGoniometerAverage) {
    const auto s = setup("bricks", 32, 100);
    const EllipseMap ellipses = fit_ellipses(s->hf, s->dirs, s->vis);
    const vec3 wi = direction_from_degrees(35.f, 20.f), wo = direction_from_degrees(55.f, 200.f);
    for (bool use_ellipses : {false, true}) {
        SCOPED_TRACE(use_ellipses ? "ellipse masking" : "exact masking");
        GonioSettings g;
        g.scatter.depth = 2;
        g.scatter.ellipses = use_ellipses ? &ellipses : nullptr;
        g.phong = true;
        g.ks = vec3(0.2f, 0.3f, 0.4f);
        const Image img = goniometer_image(s->hf, s->dirs, s->vis, g, wi, wo);
        ASSERT_EQ(img.width, 32);
        ASSERT_EQ(img.height, 32);
        ASSERT_EQ(img.channels, 3);
        const std::vector<float> V = use_ellipses ? ellipse_visibility_texture(ellipses, s->hf, wo) : visibility_texture(s->hf, s->dirs, s->vis, wo);
        double sum[3] = {0, 0, 0}, wsum = 0;
        int masked = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const vec3 n = s->hf.normal(x, y);
                const double proj = std::max(0.f, glm::dot(n, wo)) / n.z;
                for (int c = 0; c < 3; ++c) sum[c] += double(img.at(x, y)[c]) * proj;
                wsum += double(V[s->hf.index(x, y)]) * proj;
                if (V[s->hf.index(x, y)] == 0.f) {
                    ++masked;
                    for (int c = 0; c < 3; ++c) EXPECT_EQ(img.at(x, y)[c], 0.f) << "masked texel " << x << "," << y;
                }
            }
        EXPECT_GT(masked, 0) << "a 55-degree view must mask some of the bricks' texels";
        const vec3 want = goniometer_average(s->hf, s->dirs, s->vis, g, wi, wo);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / wsum, double(want[c]), 1e-5 * double(want[c])) << c;
    }
}

// [SECTION] Reciprocity
// f = T / cos(theta_i). At depth 0, T(wi, wo) cos(theta_i)^-1 = sum_x rho/pi (n.wi) V_i V_o (n.wo)/n.z
// / (cos(theta_i) sum_x m(x, wo)), and sum_x m(x, wo) = N cos(theta_o) for an exact heightfield
// visibility (every line of sight meets one visible facet): symmetric up to the discrete
// visibility and the central-difference normals.
TEST(Goniometer, SimulatedBrdfIsReciprocalWithoutScattering) {
    const auto s = setup("bricks", 64, 100);
    GonioSettings g;
    g.scatter.depth = 0;
    g.resolution = 8;
    const SimulatedBrdf b = simulate_brdf(s->hf, s->dirs, s->vis, g);
    double sum = 0, worst = 0;
    int pairs = 0;
    for (int a = 0; a < b.nodes(); ++a)
        for (int v = a + 1; v < b.nodes(); ++v) {
            const vec3 wa = b.node_direction(a / b.n_phi, a % b.n_phi), wv = b.node_direction(v / b.n_phi, v % b.n_phi);
            if (wa.z <= std::cos(radians(60.f)) || wv.z <= std::cos(radians(60.f))) continue;
            const vec3 fav = b.table[size_t(a) * size_t(b.nodes()) + size_t(v)] / wa.z, fva = b.table[size_t(v) * size_t(b.nodes()) + size_t(a)] / wv.z;
            for (int c = 0; c < 3; ++c) {
                if (fav[c] + fva[c] <= 0.f) continue;
                const double asym = std::abs(double(fav[c] - fva[c])) / double(fav[c] + fva[c]);
                sum += asym;
                worst = std::max(worst, asym);
                ++pairs;
            }
        }
    ASSERT_GT(pairs, 100);
    const double mean = sum / pairs;
    std::printf("reciprocity: mean asymmetry %.5f, max %.5f over %d pairs x channels\n", mean, worst, pairs);
    EXPECT_LT(mean, 0.02);
    EXPECT_LT(worst, 0.1);
}

// [SECTION] Spherical harmonics
TEST(Goniometer, RealShIsOrthonormal) {
    // Midpoint quadrature on a (theta, phi) grid; the basis is smooth, so 1e-3 is generous.
    const int bands = 8, B = bands * bands, nt = 96, np = 192;
    std::vector<double> gram(size_t(B * B), 0.0), y(static_cast<size_t>(B));
    for (int i = 0; i < nt; ++i)
        for (int j = 0; j < np; ++j) {
            const double th = (i + 0.5) * kPi / nt, ph = (j + 0.5) * 2 * kPi / np;
            const double dw = std::sin(th) * (kPi / nt) * (2 * kPi / np);
            real_sh(bands, vec3(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th))), y.data());
            for (int a = 0; a < B; ++a)
                for (int c = 0; c < B; ++c) gram[size_t(a * B + c)] += y[size_t(a)] * y[size_t(c)] * dw;
        }
    for (int a = 0; a < B; ++a)
        for (int c = 0; c < B; ++c) ASSERT_NEAR(gram[size_t(a * B + c)], a == c ? 1.0 : 0.0, 1e-3) << a << "," << c;
    real_sh(2, vec3(0.6f, 0.f, 0.8f), y.data());
    EXPECT_NEAR(y[0], 0.2820948, 1e-6);
    EXPECT_NEAR(y[2], 0.4886025 * 0.8, 1e-6);
    EXPECT_NEAR(y[3], -0.4886025 * 0.6, 1e-6);
}

TEST(Goniometer, ShFitOfFlatFieldMatchesExactTable) {
    const vec3 rho(0.6f);
    const auto s = setup("flat", 16, 64, rho);
    GonioSettings g;
    g.scatter.depth = 1;
    g.scatter.shadows = false;  // T = rho/pi cos(theta_i) exactly (see FlatFieldIsLambert...)
    g.resolution = 8;
    const SimulatedBrdf exact = simulate_brdf(s->hf, s->dirs, s->vis, g);
    g.fit = GonioSettings::Fit::SH;
    g.samples = 300;
    for (int bands : {3, 4}) {
        g.sh_bands = bands;
        const SimulatedBrdf b = simulate_brdf(s->hf, s->dirs, s->vis, g);
        ASSERT_EQ(b.sh_bands, bands);
        ASSERT_EQ(b.sh.size(), size_t(bands * bands * bands * bands));
        EXPECT_EQ(b.images, 1 + 300);
        double err = 0, sq = 0;
        for (size_t k = 0; k < b.table.size(); ++k) {
            const double d = std::abs(double(b.table[k].x - exact.table[k].x));
            err = std::max(err, d);
            sq += d * d;
        }
        const double scale = rho.x * kInvPi, rel = err / scale, rms = std::sqrt(sq / double(b.table.size())) / scale;
        std::printf("SH bands %d: |table - exact| max %.4f, RMS %.4f of rho/pi; fit residual %.5f\n", bands, rel, rms, b.fit_residual);
        EXPECT_LT(rel, bands == 3 ? 0.03 : 0.08);
        EXPECT_LT(rms, 0.02);
        EXPECT_LT(b.fit_residual, 0.01);
        EXPECT_EQ(b.env, exact.env) << "env is simulated as for the table";
        // eval_sh agrees with the tabulated fit at a node.
        const vec3 wi = b.node_direction(2, 3), wo = b.node_direction(5, 1);
        EXPECT_LE(rel_diff(b.eval_sh(wi, wo), b.table[size_t(2 * 8 + 3) * size_t(b.nodes()) + size_t(5 * 8 + 1)]), 1e-4f);
    }
}

TEST(Goniometer, ShFitDependsOnTheSeedOnlyNotOnTheThreadCount) {
    // The random images are solved in parallel batches: one thread and many threads must draw and
    // fit the same images for a seed; another seed gives another fit.
    const auto s = setup("bumps", 16, 64);
    GonioSettings g;
    g.scatter.depth = 1;
    g.resolution = 5;
    g.fit = GonioSettings::Fit::SH;
    g.samples = 40;
    g.sh_bands = 2;
    const SimulatedBrdf a = test::with_threads(test::kManyThreads, [&] { return simulate_brdf(s->hf, s->dirs, s->vis, g); });
    const SimulatedBrdf b = test::with_threads(1, [&] { return simulate_brdf(s->hf, s->dirs, s->vis, g); });
    ASSERT_EQ(a.sh.size(), size_t(2 * 2 * 2 * 2));
    ASSERT_EQ(a.table.size(), size_t(25 * 25));
    EXPECT_EQ(a.sh, b.sh);
    EXPECT_EQ(a.table, b.table);
    EXPECT_EQ(a.fit_residual, b.fit_residual);
    g.seed = 2;
    const SimulatedBrdf c = simulate_brdf(s->hf, s->dirs, s->vis, g);
    EXPECT_NE(a.sh, c.sh);
}

TEST(Goniometer, BadShFitsStayFiniteAndNonNegative) {
    const auto s = setup("bricks", 16, 64);
    GonioSettings g;
    g.scatter.depth = 1;
    g.resolution = 4;
    g.fit = GonioSettings::Fit::SH;
    for (const auto& [samples, bands] : {std::pair{1, 8}, std::pair{5, 8}, std::pair{3, 1}}) {
        g.samples = samples;
        g.sh_bands = bands;
        const SimulatedBrdf b = simulate_brdf(s->hf, s->dirs, s->vis, g);
        ASSERT_EQ(b.table.size(), size_t(16 * 16));
        for (const vec3& x : b.table)
            for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(x[c]) && x[c] >= 0.f) << samples << " samples, " << bands << " bands";
        for (const vec3& x : b.sh)
            for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(x[c]));
        EXPECT_TRUE(std::isfinite(b.fit_residual));
        const vec3 e = b.eval_sh(direction_from_degrees(20.f, 5.f), direction_from_degrees(70.f, 300.f));
        for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(e[c]) && e[c] >= 0.f);
    }
}

// [SECTION] Settings
TEST(Goniometer, BadSettingsAreInputErrorsNamingTheKey) {
    const auto s = setup("bumps", 8, 16);
    auto expect_error = [&](const GonioSettings& g, const std::string& key, const Visibility* vis = nullptr) {
        try {
            simulate_brdf(s->hf, s->dirs, vis ? *vis : s->vis, g);
            ADD_FAILURE() << "no error for " << key;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
        }
    };
    GonioSettings g;
    for (int r : {1, 65, -3}) {
        g.resolution = r;
        expect_error(g, "microgeom.brdf_resolution");
    }
    g = GonioSettings{};
    g.fit = GonioSettings::Fit::SH;
    g.samples = 0;
    expect_error(g, "microgeom.brdf_samples");
    g = GonioSettings{};
    for (int bands : {0, 9}) {
        g.sh_bands = bands;
        expect_error(g, "microgeom.sh_bands");
    }
    const Heightfield other = field("bumps", 12);
    const Visibility wrong = compute_visibility(other, s->dirs);
    expect_error(GonioSettings{}, "microgeom.visibility", &wrong);
    EXPECT_THROW(goniometer_average(s->hf, s->dirs, wrong, GonioSettings{}, vec3(0, 0, 1), vec3(0, 0, 1)), InputError);
    EXPECT_THROW(goniometer_image(s->hf, s->dirs, wrong, GonioSettings{}, vec3(0, 0, 1), vec3(0, 0, 1)), InputError);
}
