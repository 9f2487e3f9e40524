// Christensen and Burley's normalised diffusion profile (core/translucency/burley.h): it integrates
// to its albedo (closed form, and numerically), its tail and derivatives are its integral's and
// slopes', and its albedo is the dipole's for the same medium (the two differ in shape only).
#include "core/translucency/burley.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
Medium skin1() {
    Medium m;
    m.sigma_s = {0.74, 0.88, 1.01};
    m.sigma_a = {0.032, 0.17, 0.48};
    m.eta = 1.3;
    return m;
}
}  // namespace

TEST(TranslucencyBurley, ItIntegratesToItsAlbedo) {
    for (const Medium& m : {skin1(), measured_material("marble").medium, measured_material("skimmilk").medium, measured_material("ketchup").medium}) {
        const BurleyProfile p(m);
        const Dipole dipole(m);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(p.albedo()[c], dipole.total_reflectance()[c], 1e-12);
            // ∫ 2πr R dr by the substitution r = u², dr = 2u du (the 1/r singularity cancels), to 60 d.
            const double d = p.d()[c], U = std::sqrt(60.0 * d);
            const int n = 200000;
            double sum = 0.0;
            for (int i = 0; i < n; ++i) {
                const double u = (i + 0.5) * U / n, r = u * u;
                sum += 2.0 * 3.14159265358979323846 * r * p.Rd(r, c) * 2.0 * u * (U / n);
            }
            EXPECT_NEAR(sum, p.albedo()[c], 1e-4 * p.albedo()[c]) << "channel " << c;
            EXPECT_NEAR(p.reflectance_within(INFINITY)[c], p.albedo()[c], 1e-12);
            EXPECT_NEAR(p.reflectance_within(0.0)[c], 0.0, 1e-12);
            // Within R: the numerical integral to R.
            const double R = 2.0 * d, V = std::sqrt(R);
            double part = 0.0;
            for (int i = 0; i < n; ++i) {
                const double u = (i + 0.5) * V / n, r = u * u;
                part += 2.0 * 3.14159265358979323846 * r * p.Rd(r, c) * 2.0 * u * (V / n);
            }
            EXPECT_NEAR(p.reflectance_within(R)[c], part, 1e-6);
        }
    }
}

TEST(TranslucencyBurley, DerivativesAndTheRadiusHoldingAFraction) {
    const BurleyProfile p(skin1());
    for (int c = 0; c < 3; ++c)
        for (double r : {0.05, 0.5, 2.0, 10.0}) {
            double f, f1, f2;
            p.derivatives(r, c, f, f1, f2);
            const double h = 1e-4 * r;
            EXPECT_NEAR(f, p.Rd(r, c), 1e-12 * f);
            EXPECT_NEAR(f1, (p.Rd(r + h, c) - p.Rd(r - h, c)) / (2 * h), 1e-5 * std::abs(f1));
            EXPECT_NEAR(f2, (p.Rd(r + h, c) - 2 * f + p.Rd(r - h, c)) / (h * h), 1e-3 * std::abs(f2));
        }
    const double R = p.radius_holding(0.9);
    const dvec3 w = p.reflectance_within(R);
    double least = 1.0;
    for (int c = 0; c < 3; ++c) least = std::min(least, w[c] / p.albedo()[c]);
    EXPECT_NEAR(least, 0.9, 1e-9);
    EXPECT_NEAR(BurleyProfile::scaling(0.8), 1.05, 1e-12);
}
