// The cloth model and its fit (core/cloth/lafortune.h, fit.h): analytic values, recovery of known
// lobes from noiseless samples, the closed-form table, and the hard cases.
#include "core/cloth/fit.h"
#include "core/cloth/acquire.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
std::vector<dvec3> hemisphere(int n, double z_min = 0.02) { return hemisphere_directions(n, z_min); }

PointSamples samples_of(const ClothBrdf& truth, const std::vector<dvec3>& lights, const std::vector<dvec3>& views) {
    std::vector<BrdfSample> s;
    for (const dvec3& v : views)
        for (const dvec3& l : lights) s.push_back({l, v, truth.f(l, v), 0, l.z});
    return group_by_view(std::move(s));
}

// Three lobes per channel, each channel its own: forward, retro-reflective and grazing.
Lafortune three_lobes() {
    Lafortune L;
    L.kd = dvec3(0.12, 0.08, 0.05);
    LafortuneLobe fwd, retro, graze;
    fwd.Cx = dvec3(-0.95, -0.9, -0.97), fwd.Cy = dvec3(-0.85, -0.9, -0.8), fwd.Cz = dvec3(0.95, 0.9, 1.0), fwd.n = dvec3(12.0, 15.0, 10.0);
    retro.Cx = dvec3(0.6, 0.7, 0.65), retro.Cy = dvec3(0.65, 0.7, 0.6), retro.Cz = dvec3(0.8, 0.75, 0.7), retro.n = dvec3(3.0, 4.0, 2.5);
    graze.Cx = dvec3(-0.8, -0.75, -0.85), graze.Cy = dvec3(-0.8, -0.8, -0.75), graze.Cz = dvec3(0.3, 0.25, 0.35), graze.n = dvec3(6.0, 5.0, 8.0);
    L.lobes = {fwd, retro, graze};
    return L;
}

double worst_relative(const ClothBrdf& fit, const ClothBrdf& truth, const std::vector<dvec3>& lights, const std::vector<dvec3>& views) {
    double worst = 0.0;
    for (const dvec3& v : views)
        for (const dvec3& l : lights) {
            const dvec3 a = fit.f(l, v), b = truth.f(l, v);
            for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(a[c] - b[c]) / std::max(std::abs(b[c]), 1e-12));
        }
    return worst;
}

bool finite(const ClothBrdf& b) {
    auto ok = [](dvec3 x) { return std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z); };
    if (!ok(b.L.kd)) return false;
    for (const auto& l : b.L.lobes)
        if (!ok(l.Cx) || !ok(l.Cy) || !ok(l.Cz) || !ok(l.n)) return false;
    for (const dvec4& T : b.table.T)
        if (!ok(dvec3(T)) || !std::isfinite(T.w)) return false;
    return true;
}
}  // namespace

TEST(Lafortune, ValueIsTheDiffuseTermPlusEachLobesPositiveBaseToItsExponent) {
    Lafortune L;
    L.kd = dvec3(0.1, 0.2, 0.3);
    LafortuneLobe a;
    a.Cx = dvec3(-1.0), a.Cy = dvec3(-1.0), a.Cz = dvec3(1.0), a.n = dvec3(2.0, 3.0, 4.0);
    L.lobes = {a};
    const dvec3 l = glm::normalize(dvec3(0.3, 0.1, 0.9)), v = glm::normalize(dvec3(-0.3, -0.1, 0.9));
    const double base = -l.x * v.x - l.y * v.y + l.z * v.z;
    const dvec3 f = L.f(l, v);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[c], L.kd[c] + std::pow(base, a.n[c]), 1e-14);
    // A negative base contributes nothing (the paper's footnote), whatever the exponent.
    LafortuneLobe neg = a;
    neg.Cz = dvec3(-1.0);
    L.lobes = {neg};
    EXPECT_EQ(L.f(dvec3(0, 0, 1), dvec3(0, 0, 1)), L.kd);
}

TEST(ViewTable, ReturnsEntriesAtTheirDirectionsAndBlendsBetween) {
    ViewTable t;
    t.v = {dvec3(0, 0, 1), glm::normalize(dvec3(1, 0, 1)), glm::normalize(dvec3(0, 1, 1))};
    t.T = {dvec4(1, 0, 0, 1), dvec4(0, 1, 0, 0.5), dvec4(0, 0, 1, 0)};
    for (size_t i = 0; i < 3; ++i) EXPECT_EQ(t.at(t.v[i]), t.T[i]);
    const dvec4 mid = t.at(glm::normalize(t.v[0] + t.v[1]));
    EXPECT_GT(mid.x, 0.2);
    EXPECT_GT(mid.y, 0.2);
    EXPECT_NEAR(mid.x + mid.y + mid.z, 1.0, 1e-12);  // a convex blend of the three
    EXPECT_EQ(ViewTable{}.at(dvec3(0, 0, 1)), dvec4(1.0));
}

// T(v) is continuous: a direction's weight falls to 0 where it stops being one of the three
// nearest, so a view crossing such a border moves T by as little as any other step. Plain
// inverse-angle weights jumped there by about a quarter of the difference between two entries
// (up to 0.29 on this circle, against 7e-5 now), so that the CPU and the GPU, whose interpolated view
// directions differ by about 1e-5, read different values in a band along each border.
TEST(ViewTable, IsContinuousWhereTheThreeNearestChange) {
    ViewTable t;
    t.v = hemisphere_directions(12);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (size_t i = 0; i < t.v.size(); ++i) t.T.push_back(dvec4(u(rng), u(rng), u(rng), u(rng) < 0.5 ? 0.0 : 1.0));
    // A circle at 40 degrees from the normal, in steps of 2e-5 rad, which passes no direction
    // closer than 0.05 rad: a step moves the weights' share by about 2 steps / 0.05 rad, so T by at
    // most 1e-3 (entries differ by at most 1).
    const int steps = int(2.0 * M_PI / 2e-5);
    const double theta = 40.0 * M_PI / 180.0;
    double nearest = 1.0, worst = 0.0;
    int changes = 0;
    auto three = [&](dvec3 w) {
        std::vector<std::pair<double, int>> c;
        for (size_t i = 0; i < t.v.size(); ++i) c.push_back({-glm::dot(t.v[i], w), int(i)});
        std::sort(c.begin(), c.end());
        return std::array<int, 3>{c[0].second, c[1].second, c[2].second};
    };
    dvec3 prev_w(std::sin(theta), 0.0, std::cos(theta));
    dvec4 prev = t.at(prev_w);
    std::array<int, 3> prev_set = three(prev_w);
    std::sort(prev_set.begin(), prev_set.end());
    for (int i = 1; i <= steps; ++i) {
        const double phi = 2.0 * M_PI * double(i) / double(steps);
        const dvec3 w(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        for (const dvec3& d : t.v) nearest = std::min(nearest, std::acos(std::min(1.0, glm::dot(d, w))));
        const dvec4 T = t.at(w);
        for (int c = 0; c < 4; ++c) worst = std::max(worst, std::fabs(T[c] - prev[c]));
        std::array<int, 3> set = three(w);
        std::sort(set.begin(), set.end());
        changes += set != prev_set;
        prev = T, prev_set = set;
    }
    ASSERT_GT(nearest, 0.05);
    EXPECT_GE(changes, 6);  // the circle does cross borders
    std::printf("worst %g changes %d nearest %g\n", worst, changes, nearest);
    EXPECT_LT(worst, 1e-3) << changes << " changes of the three nearest";
}

// Noiseless samples of three lobes per channel: the fit reproduces the BRDF's values to three
// significant digits (relative error < 5e-4 on every sample, and on directions it never saw)
// from each of several starting points on its own: the paper's grey start (slightly anisotropic
// lobes) and a retro-reflective-first one. A start whose lobes are all wrong (backwards, n = 400,
// values 10^120 too large) is rescaled to the data and ends finite, of the data's magnitude, on
// its own; with the built-in starts beside it, the fit recovers the values.
TEST(ClothFit, RecoversThreeLobesPerChannelFromSeveralStarts) {
    ClothBrdf truth;
    truth.L = three_lobes();
    const std::vector<dvec3> lights = hemisphere(32), views = hemisphere(32, 0.05);
    const PointSamples ps = samples_of(truth, lights, views);
    ASSERT_EQ(ps.views.size(), 32u);
    const std::vector<dvec3> unseen_l = hemisphere(23, 0.1), unseen_v = hemisphere(19, 0.1);
    FitOptions o;
    o.lobes = 3;
    o.lookup_table = false;
    o.builtin_starts = false;
    const std::vector<Lafortune> builtin = default_starts(ps, 3);
    for (size_t k : {0u, 3u}) {
        o.starts = {builtin[k]};
        FitReport rep;
        const ClothBrdf fit = fit_brdf(ps, o, &rep);
        EXPECT_EQ(rep.starts_tried, 1);
        EXPECT_LT(worst_relative(fit, truth, lights, views), 5e-4) << "start " << k << ", rel rms " << rep.rel_rms;
        EXPECT_LT(worst_relative(fit, truth, unseen_l, unseen_v), 5e-4) << "start " << k;
    }
    Lafortune bad;
    bad.kd = dvec3(5.0);
    for (int i = 0; i < 3; ++i) {
        LafortuneLobe l;
        l.Cx = dvec3(2.0), l.Cy = dvec3(-2.0), l.Cz = dvec3(-0.5), l.n = dvec3(400.0);
        bad.lobes.push_back(l);
    }
    o.starts = {bad};
    FitReport alone;
    const ClothBrdf rescued = fit_brdf(ps, o, &alone);
    EXPECT_TRUE(finite(rescued));
    // Of the data's magnitude: the mean value over the sampled directions within a factor of two
    // of the truth's, channel by channel (the start's was 10^120 times too large).
    dvec3 mean_fit(0.0), mean_truth(0.0);
    for (const dvec3& l : lights)
        for (const dvec3& v : views) mean_fit += rescued.f(l, v), mean_truth += truth.f(l, v);
    for (int c = 0; c < 3; ++c) {
        EXPECT_GT(mean_fit[c], 0.5 * mean_truth[c]) << "channel " << c;
        EXPECT_LT(mean_fit[c], 2.0 * mean_truth[c]) << "channel " << c;
    }
    o.builtin_starts = true;
    FitReport rep;
    const ClothBrdf fit = fit_brdf(ps, o, &rep);
    EXPECT_EQ(rep.starts_tried, 1 + int(builtin.size()));
    EXPECT_LT(worst_relative(fit, truth, lights, views), 5e-4) << "rel rms " << rep.rel_rms;
    EXPECT_LT(worst_relative(fit, truth, unseen_l, unseen_v), 5e-4);
}

// With the right lobes, Eq. 4 gives the table exactly, whatever it holds.
TEST(ClothFit, TableIsExactWhenTheLobesAreRight) {
    ClothBrdf truth;
    truth.L = three_lobes();
    truth.table.v = hemisphere(16, 0.05);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.2, 1.5);
    for (size_t i = 0; i < truth.table.v.size(); ++i) truth.table.T.push_back(dvec4(u(rng), u(rng), u(rng), 1.0));
    const PointSamples ps = samples_of(truth, hemisphere(32), truth.table.v);
    const ViewTable t = fit_table(ps, truth.L);
    ASSERT_EQ(t.T.size(), truth.table.T.size());
    for (size_t i = 0; i < t.T.size(); ++i)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(t.T[i][c], truth.table.T[i][c], 1e-12 * std::abs(truth.table.T[i][c]));
}

// Lobes times a table that darkens and reddens grazing views (the paper's Fig. 5). At the
// paper's tolerance (0.1) the alternation stops within a few rounds and fits better than lobes
// alone; tightened, it converges to the exact product (alternating least squares: linearly).
TEST(ClothFit, AlternationFitsLobesTimesAViewTable) {
    ClothBrdf truth;
    truth.L = three_lobes();
    truth.L.lobes.resize(2);
    truth.table.v = hemisphere(32, 0.05);
    for (const dvec3& v : truth.table.v) truth.table.T.push_back(dvec4(1.0, 0.4 + 0.6 * v.z, 0.3 + 0.7 * v.z, 1.0));
    const PointSamples ps = samples_of(truth, hemisphere(32), truth.table.v);
    FitOptions o;
    o.lobes = 2;
    o.lookup_table = false;
    FitReport plain;
    fit_brdf(ps, o, &plain);
    o.lookup_table = true;
    FitReport paper;
    fit_brdf(ps, o, &paper);
    EXPECT_TRUE(paper.converged);
    EXPECT_LE(paper.rounds, 3);
    EXPECT_LT(paper.rel_rms, plain.rel_rms);
    o.tolerance = 1e-4;
    o.max_rounds = 60;
    FitReport tight;
    const ClothBrdf fit = fit_brdf(ps, o, &tight);
    EXPECT_TRUE(tight.converged);
    EXPECT_LT(tight.rel_rms, 1e-3);
    EXPECT_LT(tight.rel_rms, plain.rel_rms / 100.0);
    // The table's colour follows the truth's shift: red over blue grows towards grazing views.
    const dvec4 top = fit.table.at(dvec3(0, 0, 1)), side = fit.table.at(glm::normalize(dvec3(1, 0, 0.1)));
    EXPECT_GT(side.x / side.z, 1.5 * top.x / top.z);
}

// [SECTION] Hard cases: no NaN, no crash.
TEST(ClothFitHardCases, AllBlackSamplesGiveAZeroModel) {
    std::vector<BrdfSample> s;
    for (const dvec3& v : hemisphere(8))
        for (const dvec3& l : hemisphere(8)) s.push_back({l, v, dvec3(0.0), 0});
    const PointSamples ps = group_by_view(s);
    for (int lobes = 1; lobes <= 3; ++lobes) {
        FitOptions o;
        o.lobes = lobes;
        FitReport rep;
        const ClothBrdf b = fit_brdf(ps, o, &rep);
        ASSERT_TRUE(finite(b));
        for (const BrdfSample& x : ps.s) EXPECT_LT(glm::length(b.f(x.l, x.v)), 1e-9);
        EXPECT_EQ(rep.rel_rms, 0.0);
    }
}

TEST(ClothFitHardCases, GrazingDirectionsHugeExponentsAndNegativeBases) {
    // Grazing: light and view in the tangent plane (z = 0) and a lobe with a huge exponent.
    ClothBrdf truth;
    truth.L.kd = dvec3(0.05);
    LafortuneLobe sharp;
    sharp.Cx = sharp.Cy = dvec3(-1.0005), sharp.Cz = dvec3(1.0005), sharp.n = dvec3(5000.0);
    LafortuneLobe backwards;  // a base that is negative for most directions
    backwards.Cx = backwards.Cy = dvec3(3.0), backwards.Cz = dvec3(-2.0), backwards.n = dvec3(2.0);
    truth.L.lobes = {sharp, backwards};
    std::vector<dvec3> dirs = hemisphere(24, 0.0);
    dirs.push_back(dvec3(1, 0, 0)), dirs.push_back(dvec3(0, 1, 0)), dirs.push_back(dvec3(0, 0, 1));
    const PointSamples ps = samples_of(truth, dirs, dirs);
    for (bool table : {false, true}) {
        FitOptions o;
        o.lobes = 2;
        o.lookup_table = table;
        FitReport rep;
        const ClothBrdf b = fit_brdf(ps, o, &rep);
        ASSERT_TRUE(finite(b)) << table;
        EXPECT_TRUE(std::isfinite(rep.rms));
        for (const dvec3& v : dirs)
            for (const dvec3& l : dirs) {
                const dvec3 f = b.f(l, v);
                ASSERT_TRUE(std::isfinite(f.x) && std::isfinite(f.y) && std::isfinite(f.z));
            }
        for (const auto& l : b.L.lobes) EXPECT_GT(l.n.x, 0.0);
    }
}

TEST(ClothFitHardCases, ABadStartIsClampedIntoTheBoundsAndStillFits) {
    ClothBrdf truth;
    truth.L = three_lobes();
    truth.L.lobes.resize(1);
    const PointSamples ps = samples_of(truth, hemisphere(24), hemisphere(24, 0.05));
    Lafortune bad;
    bad.kd = dvec3(-3.0);  // below its bound
    LafortuneLobe l;
    l.Cx = dvec3(1e9), l.Cy = dvec3(-1e9), l.Cz = dvec3(1e9), l.n = dvec3(1e9);  // overflows at once
    bad.lobes = {l};
    FitOptions o;
    o.lobes = 1;
    o.lookup_table = false;
    o.starts = {bad};
    o.builtin_starts = false;
    FitReport rep;
    const ClothBrdf b = fit_brdf(ps, o, &rep);
    ASSERT_TRUE(finite(b));
    // On its own the bad start may end anywhere finite; with the built-in starts it recovers.
    o.builtin_starts = true;
    const ClothBrdf good = fit_brdf(ps, o, &rep);
    EXPECT_LT(rep.rel_rms, 1e-4);
    EXPECT_TRUE(finite(good));
}

TEST(ClothFitHardCases, BadOptionsNameTheirKey) {
    const PointSamples ps = samples_of(ClothBrdf{}, hemisphere(4), hemisphere(4));
    FitOptions o;
    o.lobes = 4;
    try {
        fit_brdf(ps, o);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.lobes"), std::string::npos) << e.what();
    }
    o.lobes = 0;
    EXPECT_THROW(fit_brdf(ps, o), InputError);
    o.lobes = 2;
    o.tolerance = 0.0;
    try {
        fit_brdf(ps, o);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.tolerance"), std::string::npos) << e.what();
    }
}
