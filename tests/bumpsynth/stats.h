#pragma once
// Shared by the bumpsynth tests: a fixed-seed RNG, independent reference closed forms of the NDFs
// (textbook (θ, φ) forms, not the library's code), and Pearson's χ² goodness-of-fit test with the
// regularised incomplete gamma function (no external statistics library).
#include "core/math.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace mesolab::test {

// [SECTION] Random numbers: uniform in [0, 1) from 53 random bits (portable, fixed seed).
struct Rng {
    std::mt19937_64 engine;
    explicit Rng(uint64_t seed) : engine(seed) {}
    double uniform() { return double(engine() >> 11) * 0x1.0p-53; }
};

// [SECTION] A ring NDF image: 1 where r0 <= r <= r1 (r = |(x, y)|), else 0; row 0 at y = +1.
inline std::vector<float> ring_image(int n, double r0, double r1) {
    std::vector<float> img(size_t(n) * size_t(n), 0.f);
    for (int py = 0; py < n; ++py)
        for (int px = 0; px < n; ++px) {
            const double x = -1.0 + (px + 0.5) * 2.0 / n, y = 1.0 - (py + 0.5) * 2.0 / n, r = std::hypot(x, y);
            if (r >= r0 && r <= r1) img[size_t(py) * size_t(n) + size_t(px)] = 1.f;
        }
    return img;
}

// [SECTION] Reference closed forms, in the lobe frame (φ measured from the lobe's α_x axis)
// Beckmann: exp(-tan²θ (cos²φ/αx² + sin²φ/αy²)) / (π αx αy cos⁴θ)
inline double ref_beckmann(double theta, double phi, double ax, double ay) {
    const double c = std::cos(theta), t = std::tan(theta);
    const double a = std::cos(phi) * std::cos(phi) / (ax * ax) + std::sin(phi) * std::sin(phi) / (ay * ay);
    return std::exp(-t * t * a) / (std::numbers::pi * ax * ay * c * c * c * c);
}
// GGX: 1 / (π αx αy cos⁴θ (1 + tan²θ (cos²φ/αx² + sin²φ/αy²))²)
inline double ref_ggx(double theta, double phi, double ax, double ay) {
    const double c = std::cos(theta), t = std::tan(theta);
    const double a = std::cos(phi) * std::cos(phi) / (ax * ax) + std::sin(phi) * std::sin(phi) / (ay * ay);
    const double d = 1.0 + t * t * a;
    return 1.0 / (std::numbers::pi * ax * ay * c * c * c * c * d * d);
}
// Ward's Gaussian, unnormalised: exp(-tan²θ (cos²φ/αx² + sin²φ/αy²))
inline double ref_ward_unnormalised(double theta, double phi, double ax, double ay) {
    const double t = std::tan(theta);
    const double a = std::cos(phi) * std::cos(phi) / (ax * ax) + std::sin(phi) * std::sin(phi) / (ay * ay);
    return std::exp(-t * t * a);
}
// Blinn-Phong: (e+2)/(2π) cos^e θ
inline double ref_phong(double theta, double e) { return (e + 2.0) / (2.0 * std::numbers::pi) * std::pow(std::cos(theta), e); }

// (θ, φ in the lobe frame) of the projected point (x, y) of the disk, for a lobe rotated by rot_deg.
inline void to_lobe_angles(double x, double y, double rot_deg, double& theta, double& phi) {
    const double r2 = x * x + y * y;
    theta = std::atan2(std::sqrt(r2), std::sqrt(std::max(0.0, 1.0 - r2)));
    phi = std::atan2(y, x) - rot_deg * std::numbers::pi / 180.0;
}

// ∫_H f(θ, φ) cos θ dω by a midpoint rule in (ψ, φ), θ = atan(a tan ψ) (resolves lobes of width a).
template <class F>
double hemisphere_integral(const F& f, double a, int n_psi = 4000, int n_phi = 720) {
    double sum = 0.0;
    for (int i = 0; i < n_psi; ++i) {
        const double psi = (i + 0.5) * (std::numbers::pi / 2) / n_psi, tp = std::tan(psi);
        const double theta = std::atan(a * tp);
        const double dtheta = a / (std::cos(psi) * std::cos(psi)) / (1.0 + a * a * tp * tp);
        double ring = 0.0;
        for (int k = 0; k < n_phi; ++k) ring += f(theta, (k + 0.5) * 2.0 * std::numbers::pi / n_phi);
        sum += ring * (2.0 * std::numbers::pi / n_phi) * std::cos(theta) * std::sin(theta) * dtheta;
    }
    return sum * (std::numbers::pi / 2) / n_psi;
}

// [SECTION] Regularised incomplete gamma Q(a, x) = Γ(a, x) / Γ(a)
// Series for x < a + 1, Lentz's continued fraction otherwise (both converge to ~1e-15).
inline double gamma_q(double a, double x) {
    if (x <= 0.0) return 1.0;
    const double lg = std::lgamma(a);
    if (x < a + 1.0) {
        double term = 1.0 / a, sum = term;
        for (int n = 1; n < 100000; ++n) {
            term *= x / (a + n);
            sum += term;
            if (std::fabs(term) < std::fabs(sum) * 1e-16) break;
        }
        return 1.0 - sum * std::exp(-x + a * std::log(x) - lg);
    }
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::fabs(c) < tiny) c = tiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::fabs(del - 1.0) < 1e-16) break;
    }
    return std::exp(-x + a * std::log(x) - lg) * h;
}

// P(χ²_k >= x): the p-value of a χ² statistic x with k degrees of freedom.
inline double chi2_sf(double x, double k) { return gamma_q(0.5 * k, 0.5 * x); }

// The critical value c with P(χ²_k >= c) = alpha (bisection on chi2_sf).
inline double chi2_critical(double alpha, double k) {
    double lo = 0.0, hi = k + 20.0 * std::sqrt(2.0 * k) + 100.0;
    for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        (chi2_sf(mid, k) > alpha ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// Wilson-Hilferty approximation of the same critical value (a cross-check of chi2_critical).
inline double chi2_critical_wilson_hilferty(double alpha, double k) {
    double lo = -40.0, hi = 40.0;  // z with P(Z >= z) = alpha
    for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
    }
    const double z = 0.5 * (lo + hi), v = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - v + z * std::sqrt(v), 3.0);
}

// Per-test level for a family-wise level alpha over `tests` independent tests (Šidák).
inline double sidak(double alpha, int tests) { return 1.0 - std::pow(1.0 - alpha, 1.0 / tests); }

// [SECTION] Pearson's χ² test with pooling
struct Chi2Result {
    double chi2 = 0.0, p = 0.0, critical = 0.0, critical_wh = 0.0;
    int dof = 0, bins = 0, pooled_bins = 0;
    long observed_in_empty = 0;  // samples in bins of probability exactly 0 (must be 0)
};

// prob: bin probabilities (sum 1); observed: counts of n samples. Bins with expected count < 5 are
// pooled into one bin (merged into the smallest kept bin if the pool itself stays below 5).
inline Chi2Result chi2_test(const std::vector<double>& prob, const std::vector<long>& observed, long n, double alpha) {
    Chi2Result r;
    std::vector<double> E, O;
    double pool_e = 0.0, pool_o = 0.0;
    for (size_t k = 0; k < prob.size(); ++k) {
        const double e = prob[k] * double(n);
        if (prob[k] == 0.0) r.observed_in_empty += observed[k];
        if (e >= 5.0) {
            E.push_back(e);
            O.push_back(double(observed[k]));
        } else {
            pool_e += e;
            pool_o += double(observed[k]);
            ++r.pooled_bins;
        }
    }
    if (pool_e >= 5.0) {
        E.push_back(pool_e);
        O.push_back(pool_o);
    } else if (!E.empty()) {
        const size_t s = size_t(std::min_element(E.begin(), E.end()) - E.begin());
        E[s] += pool_e;
        O[s] += pool_o;
    }
    for (size_t k = 0; k < E.size(); ++k) r.chi2 += (O[k] - E[k]) * (O[k] - E[k]) / E[k];
    if (r.observed_in_empty > 0) r.chi2 = std::numeric_limits<double>::infinity();
    r.bins = int(E.size());
    r.dof = r.bins - 1;
    r.p = std::isfinite(r.chi2) ? chi2_sf(r.chi2, r.dof) : 0.0;
    r.critical = chi2_critical(alpha, r.dof);
    r.critical_wh = chi2_critical_wilson_hilferty(alpha, r.dof);
    return r;
}
}  // namespace mesolab::test
