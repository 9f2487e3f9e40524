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

dvec3 BurleyProfile::Rd(double r) const { return {Rd(r, 0), Rd(r, 1), Rd(r, 2)}; }

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

double BurleyProfile::radius_holding(double f) const {
    f = std::clamp(f, 0.0, 1.0 - 1e-12);
    // Per channel the fraction within R is 1 - (e^(-R/d) + 3 e^(-R/3d)) / 4: monotonic, solved by bisection.
    double R = 0.0;
    for (int c = 0; c < 3; ++c) {
        if (!(A_[c] > 0.0)) continue;
        double lo = 0.0, hi = 3.0 * d_[c];
        const auto within = [&](double x) { return 1.0 - (std::exp(-x / d_[c]) + 3.0 * std::exp(-x / (3.0 * d_[c]))) / 4.0; };
        while (within(hi) < f) hi *= 2.0;
        for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
            const double mid = 0.5 * (lo + hi);
            (within(mid) < f ? lo : hi) = mid;
        }
        R = std::max(R, hi);
    }
    return R;
}
}  // namespace mesolab::translucency
