// The diffuse dipole (see dipole.h).
#include "core/translucency/dipole.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace mesolab::translucency {

namespace {
constexpr double kPiD = 3.14159265358979323846;

std::string fmt3(dvec3 v) {
    std::ostringstream s;
    s << v.x << "," << v.y << "," << v.z;
    return s.str();
}
}  // namespace

// [SECTION] Measured materials (Jensen et al. 2001, Fig. 5 table: σ's, σa in mm^-1, R_d)
const std::vector<MeasuredMaterial>& measured_materials() {
    static const std::vector<MeasuredMaterial> m = {
        {"apple", {{2.29, 2.39, 1.97}, {0.0030, 0.0034, 0.046}, 1.3}, {0.846, 0.841, 0.528}},
        {"chicken1", {{0.15, 0.21, 0.38}, {0.015, 0.077, 0.19}, 1.3}, {0.314, 0.156, 0.126}},
        {"chicken2", {{0.19, 0.25, 0.32}, {0.018, 0.088, 0.20}, 1.3}, {0.321, 0.160, 0.108}},
        {"cream", {{7.38, 5.47, 3.15}, {0.0002, 0.0028, 0.0163}, 1.3}, {0.976, 0.900, 0.725}},
        {"ketchup", {{0.18, 0.07, 0.03}, {0.061, 0.97, 1.45}, 1.3}, {0.164, 0.006, 0.002}},
        {"marble", {{2.19, 2.62, 3.00}, {0.0021, 0.0041, 0.0071}, 1.5}, {0.830, 0.791, 0.753}},
        {"potato", {{0.68, 0.70, 0.55}, {0.0024, 0.0090, 0.12}, 1.3}, {0.764, 0.613, 0.213}},
        {"skimmilk", {{0.70, 1.22, 1.90}, {0.0014, 0.0025, 0.0142}, 1.3}, {0.815, 0.813, 0.682}},
        {"skin1", {{0.74, 0.88, 1.01}, {0.032, 0.17, 0.48}, 1.3}, {0.436, 0.227, 0.131}},
        {"skin2", {{1.09, 1.59, 1.79}, {0.013, 0.070, 0.145}, 1.3}, {0.623, 0.433, 0.344}},
        {"spectralon", {{11.6, 20.4, 14.9}, {0.0, 0.0, 0.0}, 1.3}, {1.0, 1.0, 1.0}},
        {"wholemilk", {{2.55, 3.21, 3.77}, {0.0011, 0.0024, 0.014}, 1.3}, {0.908, 0.881, 0.759}},
    };
    return m;
}

const MeasuredMaterial& measured_material(const std::string& name, const std::string& key) {
    std::vector<std::string> names;
    for (const MeasuredMaterial& m : measured_materials()) {
        if (m.name == name) return m;
        names.push_back(m.name);
    }
    std::string msg = key + ": unknown material '" + name + "'";
    if (const std::string near = nearest_key(name, names); !near.empty()) msg += " (did you mean '" + near + "'?)";
    msg += "; expected one of:";
    for (const std::string& n : names) msg += " " + n;
    throw InputError(msg);
}

void validate(const Medium& m, const std::string& group) {
    for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(m.sigma_s[c]) || m.sigma_s[c] < 0.0)
            throw InputError(group + ".sigma_s: " + fmt3(m.sigma_s) + " must be finite and >= 0 (reduced scattering, mm^-1)");
        if (!std::isfinite(m.sigma_a[c]) || m.sigma_a[c] < 0.0)
            throw InputError(group + ".sigma_a: " + fmt3(m.sigma_a) + " must be finite and >= 0 (absorption, mm^-1)");
        if (!(m.sigma_s[c] + m.sigma_a[c] > 0.0))
            throw InputError(group + ".sigma_s: " + fmt3(m.sigma_s) + " with " + group + ".sigma_a " + fmt3(m.sigma_a) +
                             ": every channel needs sigma_s + sigma_a > 0 (a medium that neither scatters nor absorbs has no dipole)");
    }
    if (!std::isfinite(m.eta) || m.eta < 1.0 || m.eta > 3.0)
        throw InputError(group + ".eta: " + std::to_string(m.eta) + " must be in [1, 3]");
}

// [SECTION] Fresnel terms
double fresnel_diffuse_reflectance(double eta) { return -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta; }

double fresnel_transmittance(double cos_theta, double eta) {
    if (eta == 1.0) return 1.0;
    const double r0 = (eta - 1.0) / (eta + 1.0) * ((eta - 1.0) / (eta + 1.0));
    const double c = std::clamp(std::abs(cos_theta), 0.0, 1.0), m = 1.0 - c;
    const double m2 = m * m;
    return std::clamp(1.0 - (r0 + (1.0 - r0) * m2 * m2 * m), 0.0, 1.0);
}

double diffuse_transmittance(double eta) {
    if (eta == 1.0) return 1.0;
    const double r0 = (eta - 1.0) / (eta + 1.0) * ((eta - 1.0) / (eta + 1.0));
    return (1.0 - r0) * 20.0 / 21.0;  // 2 ∫ (1 - r0)(1 - (1 - μ)^5) μ dμ, ∫ (1 - μ)^5 μ dμ = 1/42
}

// [SECTION] The dipole
Dipole::Dipole(const Medium& m) : m_(m) {
    validate(m);
    const double Fdr = fresnel_diffuse_reflectance(m.eta);
    A_ = (1.0 + Fdr) / (1.0 - Fdr);
    for (int c = 0; c < 3; ++c) {
        const double st = m.sigma_s[c] + m.sigma_a[c];
        alpha_[c] = m.sigma_s[c] / st;
        sigma_tr_[c] = std::sqrt(3.0 * m.sigma_a[c] * st);
        zr_[c] = 1.0 / st;
        zv_[c] = zr_[c] * (1.0 + 4.0 * A_ / 3.0);
    }
}

double Dipole::Rd(double r, int c) const {
    const double r2 = r * r, s = sigma_tr_[c], zr = zr_[c], zv = zv_[c];
    const double dr = std::sqrt(r2 + zr * zr), dv = std::sqrt(r2 + zv * zv);
    const double real = zr * (s * dr + 1.0) * std::exp(-s * dr) / (dr * dr * dr);
    const double virt = zv * (s * dv + 1.0) * std::exp(-s * dv) / (dv * dv * dv);
    return alpha_[c] / (4.0 * kPiD) * (real + virt);
}

void Dipole::derivatives(double r, int c, double& f, double& f1, double& f2) const {
    const double s = sigma_tr_[c];
    double g = 0.0, g1 = 0.0, g2 = 0.0;
    for (const double z : {zr_[c], zv_[c]}) {
        const double D2 = r * r + z * z, D = std::sqrt(D2), sD = s * D, e = std::exp(-sD);
        const double T = z * (sD + 1.0) * e / (D2 * D);
        const double T1 = -z * e * (sD * sD + 3.0 * sD + 3.0) / (D2 * D2);
        const double T2 = z * e * (sD * sD * sD + 5.0 * sD * sD + 12.0 * sD + 12.0) / (D2 * D2 * D);
        g += T, g1 += T1 * r / D, g2 += T2 * r * r / D2 + T1 * z * z / (D2 * D);
    }
    const double k = alpha_[c] / (4.0 * kPiD);
    f = k * g, f1 = k * g1, f2 = k * g2;
}

dvec3 Dipole::tail(double R) const {
    dvec3 out(0.0);
    for (int c = 0; c < 3; ++c)
        for (const double z : {zr_[c], zv_[c]}) {
            const double D = std::sqrt(R * R + z * z);
            out[c] += alpha_[c] / (4.0 * kPiD) * z * std::exp(-sigma_tr_[c] * D) / D;
        }
    return out;
}

dvec3 Dipole::laplacian_ratio(double r) const {
    r = std::abs(r);
    dvec3 out(0.0);
    for (int c = 0; c < 3; ++c) {
        // A step small against every length of the dipole (r, z_r), large against rounding.
        const double h = 1e-3 * std::max(r, zr_[c]);
        const double f0 = Rd(r, c), fp = Rd(r + h, c), fm = Rd(std::abs(r - h), c);
        if (!(f0 > 0.0) || !std::isfinite(f0)) continue;
        const double d2 = (fp - 2.0 * f0 + fm) / (h * h);
        const double d1_over_r = r > h ? (fp - fm) / (2.0 * h * r) : d2;  // R_d'(r)/r → R_d''(0)
        out[c] = (d2 + d1_over_r) / f0;
    }
    return out;
}

// ∫_0^R 2πr z (σ d + 1) e^(-σ d) / d³ dr = 2π z [e^(-σ z)/z - e^(-σ d(R))/d(R)]  (r dr = d dd).
dvec3 Dipole::reflectance_within(double R) const {
    dvec3 out(0.0);
    for (int c = 0; c < 3; ++c) {
        const double s = sigma_tr_[c];
        double sum = 0.0;
        for (const double z : {zr_[c], zv_[c]}) {
            const double d = std::sqrt(R * R + z * z);
            sum += z * (std::exp(-s * z) / z - (std::isfinite(d) ? std::exp(-s * d) / d : 0.0));
        }
        out[c] = alpha_[c] / 2.0 * sum;
    }
    return out;
}

dvec3 Profile::reflectance_within_square(double a) const {
    static constexpr double x[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274, 0.6178762444026438,
                                    0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499};
    static constexpr double w[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025, 0.1495959888165767,
                                    0.1246289712555339, 0.0951585116824928, 0.0622535239386479, 0.0271524594117541};
    const double b = 0.5 * std::abs(a);
    dvec3 sum = reflectance_within(b);
    for (int i = 0; i < 16; ++i) {
        const double phi = kPiD / 8.0 * (1.0 + (i < 8 ? -x[i] : x[i - 8])), wi = w[i % 8] * kPiD / 8.0;
        const double c = std::cos(phi);
        sum += Rd(b / c) * ((2.0 * kPiD - 8.0 * phi) * b * b * std::sin(phi) / (c * c * c) * wi);
    }
    return sum;
}

dvec3 Dipole::total_reflectance() const {
    dvec3 out(0.0);
    for (int c = 0; c < 3; ++c) {
        const double k = std::sqrt(3.0 * (1.0 - alpha_[c]));
        out[c] = alpha_[c] / 2.0 * (1.0 + std::exp(-4.0 / 3.0 * A_ * k)) * std::exp(-k);
    }
    return out;
}

double Profile::radius_holding(double f) const {
    f = std::clamp(f, 0.0, 1.0 - 1e-12);
    const dvec3 total = reflectance_within(INFINITY);
    double lo = 0.0, hi = reach_hint();
    const auto enough = [&](double R) {
        const dvec3 w = reflectance_within(R);
        for (int c = 0; c < 3; ++c)
            if (total[c] > 0.0 && w[c] < f * total[c]) return false;
        return true;
    };
    while (!enough(hi) && hi < 1e12) hi *= 2.0;
    for (int it = 0; it < 100 && hi - lo > 1e-9 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (enough(mid) ? hi : lo) = mid;
    }
    return hi;
}

// [SECTION] Tabulated R_d
RdTable::RdTable(const Profile& d, double r_max, int n) : r_max_(r_max), n_(std::max(2, n)) {
    if (!(r_max > 0.0) || !std::isfinite(r_max)) throw std::invalid_argument("RdTable: r_max must be positive and finite");
    inv_r_max_ = float(1.0 / r_max);
    r_max2_ = float(r_max * r_max);
    table_.resize(size_t(n_));
    for (int i = 0; i < n_; ++i) {
        const double q = double(i) / double(n_ - 1), r = q * q * r_max;
        table_[size_t(i)] = vec3(d.Rd(r));
    }
    // A profile infinite at r = 0 (Christensen–Burley's 1/r) keeps its mean over the disk of the
    // first sample's radius there: the power the disk holds over its area.
    const double r1 = r_max / double((n_ - 1) * (n_ - 1));
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(table_[0][c])) table_[0][c] = float(d.reflectance_within(r1)[c] / (kPiD * r1 * r1));
}
}  // namespace mesolab::translucency
