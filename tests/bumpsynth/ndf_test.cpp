// bumpsynth NDFs (Kautz et al. 2001, §3.1, §4, §7): the closed forms against independent textbook
// forms and their normalisation ∫ D (m·n) dω = 1, the tabulation of every source (sharp lobes
// included), evaluation, and the InputErrors.
#include "core/bumpsynth/bumpsynth.h"
#include "core/bumpsynth/ndf.h"
#include "core/scene.h"
#include "core/error.h"
#include "stats.h"

#include "support/errors.h"
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

using namespace mesolab;
using mesolab::test::expect_input_error;
using mesolab::test::ring_image;
using namespace mesolab::bumpsynth;

namespace {

constexpr double kPiD = std::numbers::pi;

struct NamedLobes {
    const char* name;
    std::vector<Lobe> lobes;
};

std::vector<NamedLobes> analytic_sources() {
    return {
        {"phong e=0", {Lobe::blinn_phong(0.f)}},
        {"phong e=10", {Lobe::blinn_phong(10.f)}},
        {"phong e=2e8", {Lobe::blinn_phong(2e8f)}},
        {"beckmann 0.3", {Lobe::beckmann(0.3f, 0.3f)}},
        {"beckmann 0.15x0.5 @30", {Lobe::beckmann(0.15f, 0.5f, 30.f)}},
        {"beckmann 1e-4", {Lobe::beckmann(1e-4f, 1e-4f)}},
        {"beckmann 1", {Lobe::beckmann(1.f, 1.f)}},
        {"ggx 0.15x0.5 @30", {Lobe::ggx(0.15f, 0.5f, 30.f)}},
        {"ggx 1e-4", {Lobe::ggx(1e-4f, 1e-4f)}},
        {"ggx 1", {Lobe::ggx(1.f, 1.f)}},
        {"ggx 1e-4x1e-3 @-20", {Lobe::ggx(1e-4f, 1e-3f, -20.f)}},
        {"ward 0.2x0.4 @-45", {Lobe::ward(0.2f, 0.4f, -45.f)}},
        {"ward 1e-4", {Lobe::ward(1e-4f, 1e-4f)}},
        {"ward 1", {Lobe::ward(1.f, 1.f)}},
        {"sum phong+ggx+beckmann 1e-4",
         {Lobe::blinn_phong(50.f, 0.3f), Lobe::ggx(0.4f, 0.7f, 60.f, 0.5f), Lobe::beckmann(1e-4f, 1e-4f, 0.f, 0.2f)}},
    };
}
}  // namespace

// [SECTION] Closed forms
TEST(BumpsynthClosedForm, BeckmannAndGgxAtNormalEqualOneOverPiAlphaXAlphaY) {
    const vec3 n(0.f, 0.f, 1.f);
    for (auto [ax, ay, rot] : std::vector<std::tuple<float, float, float>>{
             {0.3f, 0.3f, 0.f}, {0.15f, 0.5f, 30.f}, {1e-4f, 1e-4f, 0.f}, {1.f, 0.2f, 110.f}, {1e-4f, 1.f, -45.f}}) {
        const double expected = 1.0 / (kPiD * double(ax) * double(ay));
        EXPECT_NEAR(Lobe::beckmann(ax, ay, rot).D(n) / expected, 1.0, 1e-12) << ax << "x" << ay;
        EXPECT_NEAR(Lobe::ggx(ax, ay, rot).D(n) / expected, 1.0, 1e-12) << ax << "x" << ay;
    }
}

TEST(BumpsynthClosedForm, MatchTextbookFormsAtRandomNormals) {
    test::Rng rng(7);
    const Lobe b = Lobe::beckmann(0.15f, 0.5f, 30.f), g = Lobe::ggx(0.15f, 0.5f, 30.f), w = Lobe::ward(0.2f, 0.4f, -45.f),
               p = Lobe::blinn_phong(37.f);
    for (int k = 0; k < 2000; ++k) {
        const double theta = std::acos(1.0 - 0.999 * rng.uniform()), phi = 2.0 * kPiD * rng.uniform();
        const vec3 m = direction_from_degrees(float(theta * 180.0 / kPiD), float(phi * 180.0 / kPiD));
        const double th = std::atan2(std::hypot(double(m.x), double(m.y)), double(m.z)), az = std::atan2(double(m.y), double(m.x));
        const double ph = az - 30.0 * kPiD / 180.0;  // azimuth in the lobe frame
        const double rb = test::ref_beckmann(th, ph, 0.15, 0.5), rg = test::ref_ggx(th, ph, 0.15, 0.5);
        EXPECT_NEAR(b.D(m), rb, 1e-4 * rb + 1e-12);
        EXPECT_NEAR(g.D(m), rg, 1e-4 * rg + 1e-12);
        const double rw = w.ward_constant() * test::ref_ward_unnormalised(th, az + 45.0 * kPiD / 180.0, 0.2, 0.4);
        EXPECT_NEAR(w.D(m), rw, 1e-4 * rw + 1e-12);
        const double rp = test::ref_phong(th, 37.0);
        EXPECT_NEAR(p.D(m), rp, 1e-4 * rp + 1e-12);
    }
    EXPECT_EQ(b.D(vec3(0.f, 0.6f, -0.8f)), 0.0);  // below the surface
}

TEST(BumpsynthClosedForm, PhongIsNormalised) {
    for (double e : {0.0, 1.0, 10.0, 100.0, 1e4}) {
        const Lobe l = Lobe::blinn_phong(float(e));
        EXPECT_NEAR(l.D(vec3(0.f, 0.f, 1.f)), (e + 2.0) / (2.0 * kPiD), 1e-9 * (e + 2.0)) << e;
        // ∫ (e+2)/(2π) cos^e θ cos θ dω = 1, by quadrature of the library's D.
        const double a = std::sqrt(2.0 / (e + 2.0));
        const double I = test::hemisphere_integral(
            [&](double th, double ph) { return l.D(vec3(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)))); },
            a, 2000, 8);
        EXPECT_NEAR(I, 1.0, 1e-4) << "e = " << e;
    }
}

TEST(BumpsynthClosedForm, EveryLobeIntegratesToOneOverTheHemisphere) {
    // Independent quadrature in (θ, φ) of the closed forms, for widths 1e-3 .. 1.
    for (auto [ax, ay, rot] : std::vector<std::tuple<float, float, float>>{
             {0.3f, 0.3f, 0.f}, {0.15f, 0.5f, 30.f}, {1e-3f, 1e-3f, 0.f}, {1.f, 1.f, 0.f}, {0.05f, 0.2f, 75.f}}) {
        const double a = std::sqrt(double(ax) * double(ay));
        for (const Lobe& l : {Lobe::beckmann(ax, ay, rot), Lobe::ggx(ax, ay, rot), Lobe::ward(ax, ay, rot)}) {
            const double I = test::hemisphere_integral(
                [&](double th, double ph) {
                    return l.D_xy(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph));
                },
                a, 2000, 360);
            EXPECT_NEAR(I, 1.0, 2e-4) << "kind " << int(l.kind()) << " " << ax << "x" << ay << " @" << rot;
        }
    }
}

TEST(BumpsynthClosedForm, WardConstantTendsToWardsOneOverPiAlphaXAlphaY) {
    EXPECT_NEAR(ward_constant(0.01, 0.02) * kPiD * 0.01 * 0.02, 1.0, 1e-3);
    EXPECT_NEAR(ward_constant(1e-4, 1e-4) * kPiD * 1e-8, 1.0, 1e-6);
    // Isotropic: K⁻¹ = π J(1/α²) with J(A) = 1 - A e^A E1(A); at α = 1, e E1(1) = 0.596347362323194.
    EXPECT_NEAR(1.0 / ward_constant(1.0, 1.0), kPiD * (1.0 - 0.596347362323194), 1e-10);
}

TEST(BumpsynthClosedForm, SumIsTheWeightedMeanOfItsLobes) {
    // Against the textbook forms (stats.h), not the lobes' own D: (1 phong(20) + 3 ggx(0.2)) / 4.
    const std::vector<Lobe> lobes{Lobe::blinn_phong(20.f, 1.f), Lobe::ggx(0.2f, 0.2f, 0.f, 3.f)};
    for (const vec3 m : {glm::normalize(vec3(0.2f, -0.1f, 1.f)), vec3(0.f, 0.f, 1.f), direction_from_degrees(35.f, 200.f)}) {
        const double th = std::atan2(std::hypot(double(m.x), double(m.y)), double(m.z)), ph = std::atan2(double(m.y), double(m.x));
        const double want = (test::ref_phong(th, 20.0) + 3.0 * test::ref_ggx(th, ph, 0.2, 0.2)) / 4.0;
        EXPECT_NEAR(D(lobes, m), want, 1e-4 * want) << m.x << "," << m.y << "," << m.z;
    }
}

// [SECTION] Tabulation
TEST(BumpsynthNdf, TabulatedNdfIntegratesToOneForEverySource) {
    for (int R : {64, 128}) {
        for (const NamedLobes& s : analytic_sources()) {
            const Ndf ndf = Ndf::from_lobes(s.lobes, R);
            // The raw integral (before the numerical normalisation) shows the tabulation caught the whole lobe.
            EXPECT_NEAR(ndf.raw_integral(), 1.0, 1e-6) << s.name << " R=" << R;
            EXPECT_NEAR(ndf.integral(), 1.0, 1e-6) << s.name << " R=" << R;
            double sum = 0.0;
            for (double m : ndf.masses()) sum += m;
            EXPECT_NEAR(sum, 1.0, 1e-12) << s.name;
            std::printf("  tabulate %-30s R=%3d  raw integral - 1 = %+.2e\n", s.name, R, ndf.raw_integral() - 1.0);
        }
    }
    const Ndf ring = Ndf::from_image(ring_image(200, 0.5, 0.7), 200, 200);
    EXPECT_NEAR(ring.integral(), 1.0, 1e-6);
    const Ndf hist = Ndf::from_normals({glm::normalize(vec3(0.1f, 0.2f, 1.f)), vec3(0.f, 0.f, 1.f), vec3(0.6f, 0.f, 0.8f)});
    EXPECT_NEAR(hist.integral(), 1.0, 1e-6);
}

TEST(BumpsynthNdf, LargestResolutionIntegratesToOne) {
    const Ndf ndf = Ndf::from_lobe(Lobe::ggx(0.15f, 0.5f, 30.f), Ndf::kMaxResolution);
    EXPECT_NEAR(ndf.raw_integral(), 1.0, 1e-6);
    EXPECT_NEAR(ndf.integral(), 1.0, 1e-6);
}

TEST(BumpsynthNdf, SharpLobeCellMassesMatchTheGaussianLimit) {
    // For α = 0.01 the Beckmann lobe in (x, y) is, to O(α²), a Gaussian of standard deviation α/√2 per
    // axis, so the four cells around n (h = 1/64) hold ¼ erf(h/α)² each.
    const float a = 0.01f;
    const Ndf ndf = Ndf::from_lobe(Lobe::beckmann(a, a), 128);
    const double h = 2.0 / 128, q = 0.25 * std::pow(std::erf(h / a), 2.0);
    for (int j : {63, 64})
        for (int i : {63, 64}) EXPECT_NEAR(ndf.mass(i, j), q, 1e-3) << i << "," << j;
    // α = 1e-4 is 150x narrower than a cell: all its mass in the four centre cells, 1/4 each.
    const Ndf sharp = Ndf::from_lobe(Lobe::ggx(1e-4f, 1e-4f), 128);
    double centre = 0.0;
    for (int j : {63, 64})
        for (int i : {63, 64}) {
            EXPECT_NEAR(sharp.mass(i, j), 0.25, 1e-3);
            centre += sharp.mass(i, j);
        }
    EXPECT_GT(centre, 0.999);
    // An odd resolution puts n at a cell centre: the mass is in that one cell.
    const Ndf odd = Ndf::from_lobe(Lobe::beckmann(1e-4f, 1e-4f, 30.f), 129);
    EXPECT_NEAR(odd.mass(64, 64), 1.0, 1e-9);
}

TEST(BumpsynthNdf, EvalFollowsTheClosedFormInTheLobeCore) {
    // Interpolating cell means of a locally exponential D with log-slope g = |∇ ln D| errs by up to
    // (gh)²/8 (interpolation) + (gh)²/24 (mean vs. point value) = (gh)²/6 relative. In the core,
    // D >= D(n)/20 (r <= 0.5 here), g = 2r/(α²(1-r²)²) - 4r/(1-r²) <= 17, h = 1/64: at most 1.2%.
    // (Far out in a Gaussian tail the same formula gives a few %.)
    const Lobe l = Lobe::beckmann(0.3f, 0.3f);
    const Ndf ndf = Ndf::from_lobe(l, 128);
    const double d_n = l.D(vec3(0.f, 0.f, 1.f));
    test::Rng rng(3);
    double worst = 0.0;
    for (int k = 0; k < 4000; ++k) {
        const vec2 xy(float(1.2 * rng.uniform() - 0.6), float(1.2 * rng.uniform() - 0.6));
        const vec3 m(xy.x, xy.y, std::sqrt(1.f - glm::dot(xy, xy)));
        const double d = l.D(m);
        if (d < d_n / 20.0) continue;
        worst = std::max(worst, std::fabs(ndf.eval(xy) - d) / d);
        EXPECT_NEAR(ndf.eval(m * 3.f), ndf.eval(xy), 1e-6 * d);  // eval(vec3) normalises
    }
    std::printf("  eval vs closed form, Beckmann 0.3, R = 128, lobe core: worst relative error %.2e\n", worst);
    EXPECT_LT(worst, 1.2e-2);
    EXPECT_EQ(ndf.eval(vec2(0.9f, 0.9f)), 0.f);           // outside the disk
    EXPECT_EQ(ndf.eval(vec3(0.f, 0.f, -1.f)), 0.f);       // below the surface
    EXPECT_EQ(ndf.eval(vec2(std::nanf(""), 0.f)), 0.f);  // NaN
}

TEST(BumpsynthNdf, EvalIsConstantUpToTheRimForAConstantNdf) {
    // GGX with α = 1 is D = 1/π: the renormalised bilinear filter keeps it so up to the rim.
    const Ndf ndf = Ndf::from_lobe(Lobe::ggx(1.f, 1.f), 64);
    for (int k = 0; k < 360; ++k)
        for (float r : {0.f, 0.5f, 0.97f, 0.999f, 1.f}) {
            const float phi = radians(float(k));
            EXPECT_NEAR(ndf.eval(vec2(r * std::cos(phi), r * std::sin(phi))), 1.0 / kPiD, 1e-5) << r << " " << k;
        }
}

TEST(BumpsynthNdf, ImageIsBoxFilteredExactly) {
    // A 2x2 image: the upper-left quadrant (x < 0, y > 0; row 0 is the top) holds 3/6 of the mass.
    const Ndf ndf = Ndf::from_image({3.f, 1.f, 1.f, 1.f}, 2, 2, 64);
    double ul = 0.0, lr = 0.0;
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) {
            if (i < 32 && j >= 32) ul += ndf.mass(i, j);
            if (i >= 32 && j < 32) lr += ndf.mass(i, j);
        }
    EXPECT_NEAR(ul, 0.5, 1e-12);
    EXPECT_NEAR(lr, 1.0 / 6.0, 1e-12);
    EXPECT_NEAR(ndf.eval(vec2(-0.5f, 0.5f)), 3.0 / (6.0 * kPiD / 4.0), 1e-5);  // D = value / ∫ over the disk
    // disk_rect_area is exact: the whole disk, a quadrant, a thin rim strip.
    EXPECT_NEAR(disk_rect_area(-1, 1, -1, 1), kPiD, 1e-14);
    EXPECT_NEAR(disk_rect_area(0, 1, 0, 1), kPiD / 4, 1e-13);
    EXPECT_NEAR(disk_rect_area(0.99, 1, -1, 1), std::acos(0.99) - 0.99 * std::sqrt(1 - 0.99 * 0.99), 1e-13);
}

TEST(BumpsynthNdf, NormalsHistogramCountsEveryNormalOnce) {
    std::vector<vec3> n;
    for (int k = 0; k < 1000; ++k) n.push_back(vec3(0.f, 0.f, 1.f));
    for (int k = 0; k < 3000; ++k) n.push_back(vec3(0.f, 6.f, 8.f));  // not unit: normalised, (0, 0.6, 0.8)
    n.push_back(vec3(1.f, 0.f, 0.f));                                     // at the rim
    const Ndf ndf = Ndf::from_normals(n, 128);
    const double h = 2.0 / 128;
    EXPECT_NEAR(ndf.mass(64, 64), 1000.0 / 4001.0, 1e-12);
    EXPECT_NEAR(ndf.mass(64, int(std::floor(1.6 / h))), 3000.0 / 4001.0, 1e-12);
    EXPECT_NEAR(ndf.mass(127, 64), 1.0 / 4001.0, 1e-12);
    EXPECT_NEAR(ndf.integral(), 1.0, 1e-6);
}

// [SECTION] Bad input
TEST(BumpsynthNdf, AllZeroNdfIsAnInputError) {
    expect_input_error([] { Ndf::from_image(std::vector<float>(16 * 16, 0.f), 16, 16); }, {"bumpsynth.ndf_image", "zero everywhere"});
    // Mass only outside the unit disk counts as zero too.
    std::vector<float> corners(4 * 4, 0.f);
    corners[0] = corners[3] = corners[12] = corners[15] = 1.f;
    Ndf::from_image(corners, 4, 4);  // the corner pixels do reach into the disk
    std::vector<float> outside(64 * 64, 0.f);
    outside[0] = 1.f;  // pixel (0, 0): x, y in [-1, -0.97] x [0.97, 1], entirely outside
    expect_input_error([&] { Ndf::from_image(outside, 64, 64); }, {"zero everywhere"});
}

TEST(BumpsynthNdf, NonFiniteOrNegativeNdfIsAnInputError) {
    std::vector<float> img(8 * 8, 1.f);
    img[9] = std::nanf("");
    expect_input_error([&] { Ndf::from_image(img, 8, 8); }, {"bumpsynth.ndf_image", "pixel (1, 1)", "finite"});
    img[9] = -1.f;
    expect_input_error([&] { Ndf::from_image(img, 8, 8); }, {"bumpsynth.ndf_image", "-1", ">= 0"});
    img[9] = std::numeric_limits<float>::infinity();
    expect_input_error([&] { Ndf::from_image(img, 8, 8); }, {"finite"});
    expect_input_error([] { Ndf::from_image(std::vector<float>(10, 1.f), 4, 4); }, {"bumpsynth.ndf_image", "10 values", "expected 16"});
}

TEST(BumpsynthNdf, BadParametersNameTheirKeys) {
    expect_input_error([] { Lobe::beckmann(0.f, 0.3f); }, {"bumpsynth.alpha_x: value 0 must be in [1e-4, 1]"});
    expect_input_error([] { Lobe::ggx(0.3f, 1.5f); }, {"bumpsynth.alpha_y: value 1.5 must be in [1e-4, 1]"});
    expect_input_error([] { Lobe::ward(0.3f, std::nanf("")); }, {"bumpsynth.alpha_y", "nan"});
    expect_input_error([] { Lobe::beckmann(0.3f, 0.3f, std::numeric_limits<float>::infinity()); }, {"bumpsynth.rotation", "finite"});
    expect_input_error([] { Lobe::blinn_phong(-1.f); }, {"bumpsynth.exponent: value -1 must be in [0, 2e8]"});
    expect_input_error([] { Lobe::blinn_phong(10.f, -0.5f); }, {"bumpsynth.weight", "-0.5"});
    expect_input_error([] { Ndf::from_lobe(Lobe::ggx(0.3f, 0.3f), 32); }, {"bumpsynth.resolution: value 32 must be in [64, 512]"});
    expect_input_error([] { Ndf::from_lobe(Lobe::ggx(0.3f, 0.3f), 1024); }, {"bumpsynth.resolution"});
    expect_input_error([] { Ndf::from_lobes({}); }, {"bumpsynth.lobes", "empty"});
    expect_input_error([] { Ndf::from_lobes({Lobe::ggx(0.3f, 0.3f, 0.f, 0.f)}); }, {"bumpsynth.weight", "sum to 0"});
    expect_input_error([] { Ndf::from_normals({}); }, {"bumpsynth.normals", "empty"});
    expect_input_error([] { Ndf::from_normals({vec3(0.f, 0.f, 0.f)}); }, {"bumpsynth.normals", "normal 0"});
    expect_input_error([] { Ndf::from_normals({vec3(0.f, 0.f, 1.f), vec3(0.f, 0.6f, -0.8f)}); }, {"bumpsynth.normals", "normal 1", "upper hemisphere"});
}

// [SECTION] Lists of lobes (bumpsynth.lobes)
// Any number of lobes as text: the parsed list tabulates exactly like the same Lobe objects, the
// canonical text round-trips, and bad text is refused where it is set, naming the key, the position
// and the lobe.
TEST(NdfLobeList, ParsesAnyNumberOfLobesAndRoundTrips) {
    const std::vector<Lobe> l = parse_lobes(" beckmann(0.08, 0.3) + 0.5*ggx(0.3,0.05, 45) + ward(0.2) * 2 + 0.25 * phong(80) ");
    ASSERT_EQ(l.size(), 4u);
    EXPECT_EQ(l[1].kind(), LobeKind::ggx);
    EXPECT_FLOAT_EQ(l[1].weight(), 0.5f);
    EXPECT_FLOAT_EQ(l[1].rotation_deg(), 45.f);
    EXPECT_FLOAT_EQ(l[2].alpha_y(), 0.2f) << "one alpha: isotropic";
    EXPECT_FLOAT_EQ(l[2].weight(), 2.f);
    EXPECT_FLOAT_EQ(l[3].exponent(), 80.f);
    const std::string text = format_lobes(l);
    EXPECT_EQ(text, "beckmann(0.08, 0.3) + 0.5 * ggx(0.3, 0.05, 45) + 2 * ward(0.2) + 0.25 * phong(80)");
    EXPECT_EQ(format_lobes(parse_lobes(text)), text);
    const std::vector<Lobe> direct{Lobe::beckmann(0.08f, 0.3f), Lobe::ggx(0.3f, 0.05f, 45.f, 0.5f), Lobe::ward(0.2f, 0.2f, 0.f, 2.f),
                                   Lobe::blinn_phong(80.f, 0.25f)};
    const Ndf a = Ndf::from_lobes(l, 64), b = Ndf::from_lobes(direct, 64);
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) ASSERT_EQ(a.mass(i, j), b.mass(i, j));
}

TEST(NdfLobeList, BadTextIsAClearErrorWhereItIsSet) {
    test::expect_input_error([] { parse_lobes(""); }, {"empty"});
    test::expect_input_error([] { parse_lobes("beckmann(0.3) + gxx(0.1)"); }, {"character 17", "unknown lobe 'gxx'"});
    test::expect_input_error([] { parse_lobes("beckmann(0.3"); }, {"expected ')'"});
    test::expect_input_error([] { parse_lobes("beckmann(0.3) ggx(0.1)"); }, {"expected '+'"});
    test::expect_input_error([] { parse_lobes("ggx(0.1, 0.2, 3, 4)"); }, {"1 to 3 parameters", "got 4"});
    test::expect_input_error([] { parse_lobes("beckmann(0.3) + ggx(0.1, 0)"); }, {"lobe 2 (ggx)", "[1e-4, 1]"});
    test::expect_input_error([] { parse_lobes("0 * beckmann(0.3)"); }, {"sum to 0"});
    Scene s = default_scene("bumpsynth");
    apply_set(s, "bumpsynth.ndf", "lobes");
    test::expect_input_error([&] { apply_set(s, "bumpsynth.lobes", "beckmann(0.3) + 0.5 * ggx(2)"); }, {"bumpsynth.lobes", "lobe 2 (ggx)"});
    apply_set(s, "bumpsynth.lobes", "ggx(0.2) + ggx(0.2, 0.05, 90) + ggx(0.2, 0.05, 0)");
    EXPECT_EQ(ndf_from_material(s, s.objects[0].material).resolution(), 128);
}
