// Christensen and Burley's normalised diffusion profile (see burley.h).
#include "core/translucency/burley.h"

#include <algorithm>
#include <cmath>

namespace mesolab::translucency {
namespace {
constexpr double kPiD = 3.14159265358979323846;
}

double BurleyProfile::scaling(double A) { return 1.85 - A + 7.0 * std::pow(std::abs(A - 0.8), 3.0); }

BurleyProfile::BurleyProfile(const Medium& m) {
    const Dipole dipole(m);
    A_ = dipole.total_reflectance();
    for (int c = 0; c < 3; ++c) {
        const double l = 1.0 / (m.sigma_s[c] + m.sigma_a[c]);
        s_[c] = scaling(A_[c]);
        d_[c] = l / s_[c];
    }
}

double BurleyProfile::Rd(double r, int c) const {
    r = std::abs(r);
    const double d = d_[c];
    return A_[c] * (std::exp(-r / d) + std::exp(-r / (3.0 * d))) / (8.0 * kPiD * d * r);
}

void BurleyProfile::derivatives(double r, int c, double& f, double& f1, double& f2) const {
    // R = K (e^(-r/d) + e^(-r/3d)) / r, K = A / (8π d): each term g = e^(-a r) / r has
    // g' = -g (a + 1/r), g'' = g ((a + 1/r)² + 1/r²).
    const double K = A_[c] / (8.0 * kPiD * d_[c]);
    f = f1 = f2 = 0.0;
    for (const double a : {1.0 / d_[c], 1.0 / (3.0 * d_[c])}) {
        const double g = std::exp(-a * r) / r, b = a + 1.0 / r;
        f += K * g, f1 -= K * g * b, f2 += K * g * (b * b + 1.0 / (r * r));
    }
}

dvec3 BurleyProfile::laplacian_ratio(double r) const {
    r = std::max(std::abs(r), 1e-12);
    dvec3 out(0.0);
    for (int c = 0; c < 3; ++c) {
        double f, f1, f2;
        derivatives(r, c, f, f1, f2);
        if (f > 0.0 && std::isfinite(f)) out[c] = (f2 + f1 / r) / f;
    }
    return out;
}

dvec3 BurleyProfile::tail(double R) const {
    dvec3 out(0.0);
    for (int c = 0; c < 3; ++c) {
        const double d = d_[c];
        out[c] = std::isfinite(R) ? A_[c] * (std::exp(-R / d) + 3.0 * std::exp(-R / (3.0 * d))) / (8.0 * kPiD) : 0.0;
    }
    return out;
}

dvec3 BurleyProfile::reflectance_within(double R) const { return A_ - 2.0 * kPiD * tail(std::abs(R)); }

}  // namespace mesolab::translucency
