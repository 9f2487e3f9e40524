// Environment lighting: lat-long lookup, order-2 spherical-harmonic projection and irradiance.
#include "core/env.h"
#include "core/parallel.h"
#include "core/sampling.h"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace mesolab {

namespace {
constexpr double kPiD = 3.14159265358979323846;

// Real SH basis normalisation constants, bands 0..2.
const double kY00 = 0.5 * std::sqrt(1.0 / kPiD);         // 0.282095
const double kY1 = std::sqrt(3.0 / (4.0 * kPiD));        // 0.488603
const double kY2 = 0.5 * std::sqrt(15.0 / kPiD);         // 1.092548 (xy, yz, xz)
const double kY20 = 0.25 * std::sqrt(5.0 / kPiD);        // 0.315392 (3z^2 - 1)
const double kY22 = 0.25 * std::sqrt(15.0 / kPiD);       // 0.546274 (x^2 - y^2)

// Cosine-lobe convolution per band (Ramamoorthi & Hanrahan 2001).
constexpr double kA0 = kPiD, kA1 = 2.0 * kPiD / 3.0, kA2 = kPiD / 4.0;

// Texel value as RGB (a 1- or 2-channel map is read as grey).
vec3 texel(const Image& m, int x, int y) {
    const float* p = m.at(x, y);
    return m.channels >= 3 ? vec3(p[0], p[1], p[2]) : vec3(p[0]);
}
}  // namespace

// Radiance lookup
vec3 Environment::radiance(vec3 dir) const {
    const float len2 = dir.x * dir.x + dir.y * dir.y + dir.z * dir.z;
    if (constant() || !(len2 > 0.f) || !std::isfinite(len2)) return color * intensity;
    const Image& map = *this->map;
    const vec3 d = dir / std::sqrt(len2);
    const float theta = std::acos(std::clamp(d.z, -1.f, 1.f));
    float phi = std::atan2(d.y, d.x);
    if (phi < 0.f) phi += 2.f * kPi;
    // Around in phi, clamped at the poles (as GL_REPEAT x GL_CLAMP_TO_EDGE).
    const BilinearTaps t = BilinearTaps::at_uv({phi * (0.5f * kInvPi), theta * kInvPi}, map.width, map.height, Edge::Wrap, Edge::Clamp);
    return t.blend([&](int x, int y) { return texel(map, x, y); }) * intensity;
}

// Spherical-harmonic projection
// Each texel is treated as constant radiance over its (theta, phi) rectangle and the nine basis
// functions, which factor into a theta part and a phi part, are integrated over it exactly
// (d omega = sin theta d theta d phi). The texel weights therefore sum to exactly 4 pi and a
// constant map projects onto the constant term only, up to rounding.
SH9 project_sh9(const Environment& env) {
    SH9 sh;
    static const Image kNone;
    const Image& m = env.map ? *env.map : kNone;
    if (m.empty() || m.width <= 0 || m.height <= 0 || m.channels <= 0) {
        sh.c[0] = env.color * env.intensity * float(2.0 * std::sqrt(kPiD));  // L * 4 pi * Y00
        return sh;
    }
    const int w = m.width, h = m.height;

    // Per-column phi integrals over [phi0, phi1]: 1, cos, sin, cos 2phi, sin 2phi.
    struct PhiW { double one, c1, s1, c2, s2; };
    std::vector<PhiW> pw(static_cast<size_t>(w));
    for (int i = 0; i < w; ++i) {
        const double p0 = 2.0 * kPiD * i / w, p1 = 2.0 * kPiD * (i + 1) / w;
        pw[size_t(i)] = {p1 - p0, std::sin(p1) - std::sin(p0), std::cos(p0) - std::cos(p1),
                         0.5 * (std::sin(2 * p1) - std::sin(2 * p0)), 0.5 * (std::cos(2 * p0) - std::cos(2 * p1))};
    }

    // Per-row results: the 9 coefficients of that row, summed afterwards in row order so the
    // result does not depend on how TBB splits the work.
    std::vector<std::array<double, 27>> rows(static_cast<size_t>(h));
    mesolab::parallel_for(tbb::blocked_range<int>(0, h, 8), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j != r.end(); ++j) {
            // Theta integrals over [t0, t1] with c = cos theta: int sin = c0 - c1, int cos sin,
            // int sin^2, int sin^3, int sin^2 cos, int (3cos^2 - 1) sin.
            const double t0 = kPiD * j / h, t1 = kPiD * (j + 1) / h;
            const double c0 = std::cos(t0), c1 = std::cos(t1), s0 = std::sin(t0), s1 = std::sin(t1);
            const double i_sin = c0 - c1;
            const double i_cos_sin = 0.5 * (s1 * s1 - s0 * s0);
            const double i_sin2 = 0.5 * (t1 - t0) - 0.25 * (std::sin(2 * t1) - std::sin(2 * t0));
            const double i_sin3 = (c0 - c1) - (c0 * c0 * c0 - c1 * c1 * c1) / 3.0;
            const double i_sin2_cos = (s1 * s1 * s1 - s0 * s0 * s0) / 3.0;
            const double i_p20 = (c0 * c0 * c0 - c1 * c1 * c1) - (c0 - c1);  // int (3c^2-1) sin

            // Radiance times each phi weight, summed over the row.
            double a[5][3] = {};
            for (int i = 0; i < w; ++i) {
                const vec3 L = texel(m, i, j);
                const PhiW& p = pw[size_t(i)];
                for (int k = 0; k < 3; ++k) {
                    const double v = L[k];
                    a[0][k] += v * p.one;
                    a[1][k] += v * p.c1;
                    a[2][k] += v * p.s1;
                    a[3][k] += v * p.c2;
                    a[4][k] += v * p.s2;
                }
            }
            auto& out = rows[size_t(j)];
            for (int k = 0; k < 3; ++k) {
                out[0 * 3 + k] = kY00 * i_sin * a[0][k];
                out[1 * 3 + k] = kY1 * i_sin2 * a[2][k];          // y  = sin t sin p
                out[2 * 3 + k] = kY1 * i_cos_sin * a[0][k];       // z  = cos t
                out[3 * 3 + k] = kY1 * i_sin2 * a[1][k];          // x  = sin t cos p
                out[4 * 3 + k] = kY2 * i_sin3 * 0.5 * a[4][k];    // xy = sin^2 t sin 2p / 2
                out[5 * 3 + k] = kY2 * i_sin2_cos * a[2][k];      // yz = sin t cos t sin p
                out[6 * 3 + k] = kY20 * i_p20 * a[0][k];          // 3z^2 - 1
                out[7 * 3 + k] = kY2 * i_sin2_cos * a[1][k];      // xz = sin t cos t cos p
                out[8 * 3 + k] = kY22 * i_sin3 * a[3][k];         // x^2 - y^2 = sin^2 t cos 2p
            }
        }
    });

    double total[27] = {};
    for (const auto& r : rows)
        for (int k = 0; k < 27; ++k) total[k] += r[size_t(k)];
    for (int b = 0; b < 9; ++b)
        sh.c[size_t(b)] = vec3(float(total[b * 3 + 0]), float(total[b * 3 + 1]), float(total[b * 3 + 2])) *
                          env.intensity;
    return sh;
}

// Irradiance from SH
vec3 sh9_irradiance(const SH9& sh, vec3 n) {
    const float len2 = n.x * n.x + n.y * n.y + n.z * n.z;
    if (!(len2 > 0.f) || !std::isfinite(len2)) return sh.c[0] * float(kA0 * kY00);  // no direction: mean
    const vec3 d = n / std::sqrt(len2);
    const double x = d.x, y = d.y, z = d.z;
    const double wgt[9] = {kA0 * kY00,
                           kA1 * kY1 * y,
                           kA1 * kY1 * z,
                           kA1 * kY1 * x,
                           kA2 * kY2 * x * y,
                           kA2 * kY2 * y * z,
                           kA2 * kY20 * (3.0 * z * z - 1.0),
                           kA2 * kY2 * x * z,
                           kA2 * kY22 * (x * x - y * y)};
    double e[3] = {};
    for (int b = 0; b < 9; ++b)
        for (int k = 0; k < 3; ++k) e[k] += wgt[b] * double(sh.c[size_t(b)][k]);
    return vec3(float(e[0]), float(e[1]), float(e[2]));
}
}  // namespace mesolab
