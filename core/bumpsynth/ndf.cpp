#include "core/bumpsynth/ndf.h"
#include "core/parallel.h"

#include "core/error.h"

#include <tbb/blocked_range.h>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace mesolab::bumpsynth {

namespace {

constexpr double kPiD = 3.14159265358979323846;

std::string to_text(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// [SECTION] Parameter validation
void check_alpha(const char* key, float a) {
    if (!(a >= 1e-4f && a <= 1.f)) throw InputError(std::string(key) + ": value " + to_text(a) + " must be in [1e-4, 1]");
}

void check_rotation(float deg) {
    if (!std::isfinite(deg)) throw InputError("bumpsynth.rotation: value " + to_text(deg) + " must be finite (degrees)");
}

void check_weight(float w) {
    if (!(w >= 0.f && std::isfinite(w))) throw InputError("bumpsynth.weight: value " + to_text(w) + " must be finite and >= 0");
}

void check_resolution(int R) {
    if (R < Ndf::kMinResolution || R > Ndf::kMaxResolution)
        throw InputError("bumpsynth.resolution: value " + std::to_string(R) + " must be in [" + std::to_string(Ndf::kMinResolution) +
                         ", " + std::to_string(Ndf::kMaxResolution) + "]");
}

// [SECTION] Ward's normalisation: J(A) = ∫_0^∞ e^{-Au} / (1+u)² du = 1 - A e^A E1(A)
// e^A E1(A) = 1/(A+1 - 1²/(A+3 - 2²/(A+5 - ...))) = 1/(A+1-c); J = (1-c)/(A+1-c), no cancellation.
double ward_J(double A) {
    const int terms = A >= 1.0 ? 120 : 4000;
    double t = 0.0;
    for (int k = terms; k >= 1; --k) t = double(k) * double(k) / (A + 2.0 * k + 1.0 - t);
    return (1.0 - t) / (A + 1.0 - t);
}

// [SECTION] Area of a rectangle inside the unit disk
// F(x) = ∫_0^x sqrt(1 - t²) dt.
double F(double x) {
    x = std::clamp(x, -1.0, 1.0);
    return 0.5 * (x * std::sqrt(std::max(0.0, 1.0 - x * x)) + std::asin(x));
}

// |{x <= a, y <= b} ∩ disk|.
double quadrant_area(double a, double b) {
    a = std::clamp(a, -1.0, 1.0);
    if (b <= -1.0) return 0.0;
    const double full = 2.0 * (F(a) - F(-1.0));
    if (b >= 1.0) return full;
    const double c = std::sqrt(1.0 - b * b);
    if (a <= -c) return b >= 0.0 ? full : 0.0;
    const double q = std::min(c, a);
    const double cap = F(q) - F(-c);  // ∫_{-c}^{q} Y dx
    return b >= 0.0 ? full - (cap - b * (q + c)) : cap + b * (q + c);
}

// Squared distance from the origin to the nearest / farthest point of a rectangle.
double near2(double x0, double x1, double y0, double y1) {
    const double dx = x0 > 0.0 ? x0 : (x1 < 0.0 ? -x1 : 0.0);
    const double dy = y0 > 0.0 ? y0 : (y1 < 0.0 ? -y1 : 0.0);
    return dx * dx + dy * dy;
}
double far2(double x0, double x1, double y0, double y1) {
    const double dx = std::max(std::fabs(x0), std::fabs(x1)), dy = std::max(std::fabs(y0), std::fabs(y1));
    return dx * dx + dy * dy;
}

// [SECTION] Cubature over a rectangle's part of the disk
constexpr double kNode[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
constexpr double kWeight[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};

struct Rect {
    double x0, x1, y0, y1;
};

// 4x4 Gauss-Legendre over rect ∩ disk: x split where the circle crosses y = y0 or y = y1, so the
// chord limits max(y0, -Y(x)), min(y1, Y(x)) are smooth within each piece.
template <class Fn>
double cubature(const Fn& f, const Rect& r) {
    double bp[6];
    int n = 0;
    bp[n++] = r.x0;
    for (double yy : {r.y0, r.y1})
        if (std::fabs(yy) < 1.0) {
            const double c = std::sqrt(1.0 - yy * yy);
            if (-c > r.x0 && -c < r.x1) bp[n++] = -c;
            if (c > r.x0 && c < r.x1) bp[n++] = c;
        }
    bp[n++] = r.x1;
    for (int a = 1; a < n; ++a)  // insertion sort of at most 6 values
        for (int b = a; b > 0 && bp[b] < bp[b - 1]; --b) std::swap(bp[b], bp[b - 1]);
    double sum = 0.0;
    for (int k = 0; k + 1 < n; ++k) {
        const double a = bp[k], b = bp[k + 1];
        if (!(b > a)) continue;
        const double xm = 0.5 * (a + b), xr = 0.5 * (b - a);
        for (int p = 0; p < 4; ++p) {
            const double x = xm + xr * kNode[p];
            const double Y = std::sqrt(std::max(0.0, 1.0 - x * x));
            const double lo = std::max(r.y0, -Y), hi = std::min(r.y1, Y);
            if (!(hi > lo)) continue;
            const double ym = 0.5 * (lo + hi), yr = 0.5 * (hi - lo);
            double s = 0.0;
            for (int q = 0; q < 4; ++q) s += kWeight[q] * f(x, ym + yr * kNode[q]);
            sum += kWeight[p] * xr * yr * s;
        }
    }
    return sum;
}

// A lobe's centre and widths, for the forced refinement of sharp lobes.
struct Core {
    double c, s, ax, ay;
};

// Whether a rectangle is wider than half the lobe width (in the lobe's α-scaled frame) and not well
// separated from the lobe's centre (scaled distance < max(8, 4 x its scaled half size)).
bool must_split(const Core& k, const Rect& r) {
    const double cx = 0.5 * (r.x0 + r.x1), cy = 0.5 * (r.y0 + r.y1), hx = 0.5 * (r.x1 - r.x0), hy = 0.5 * (r.y1 - r.y0);
    const double u = (k.c * cx + k.s * cy) / k.ax, v = (-k.s * cx + k.c * cy) / k.ay;
    const double eu = (std::fabs(k.c) * hx + std::fabs(k.s) * hy) / k.ax, ev = (std::fabs(k.s) * hx + std::fabs(k.c) * hy) / k.ay;
    const double size = std::max(eu, ev);
    if (size <= 0.5) return false;
    const double du = std::max(0.0, std::fabs(u) - eu), dv = std::max(0.0, std::fabs(v) - ev);
    return std::sqrt(du * du + dv * dv) < std::max(8.0, 4.0 * size);
}

constexpr int kMaxErrorDepth = 6;    // error-driven splits
constexpr int kMaxForcedDepth = 40;  // splits towards a sharp lobe
constexpr double kRelTol = 1e-7, kAbsTol = 1e-16;

template <class Fn>
double adaptive(const Fn& f, const std::vector<Core>& cores, const Rect& r, double coarse, int depth) {
    if (near2(r.x0, r.x1, r.y0, r.y1) >= 1.0) return 0.0;
    const double xm = 0.5 * (r.x0 + r.x1), ym = 0.5 * (r.y0 + r.y1);
    const Rect child[4] = {{r.x0, xm, r.y0, ym}, {xm, r.x1, r.y0, ym}, {r.x0, xm, ym, r.y1}, {xm, r.x1, ym, r.y1}};
    double fine[4], sum = 0.0;
    for (int k = 0; k < 4; ++k) sum += fine[k] = cubature(f, child[k]);
    bool split = depth < kMaxErrorDepth && std::fabs(sum - coarse) > std::max(kRelTol * std::fabs(sum), kAbsTol);
    if (!split && depth < kMaxForcedDepth)
        for (const Core& k : cores)
            if (must_split(k, r)) {
                split = true;
                break;
            }
    if (!split) return sum;
    double s = 0.0;
    for (int k = 0; k < 4; ++k) s += adaptive(f, cores, child[k], fine[k], depth + 1);
    return s;
}

// Cell masses of an analytic density f(x, y) over the R x R grid, in parallel over rows.
template <class Fn>
std::vector<double> tabulate(int R, const Fn& f, const std::vector<Core>& cores) {
    std::vector<double> mass(size_t(R) * size_t(R), 0.0);
    const double h = 2.0 / R;
    mesolab::parallel_for(tbb::blocked_range<int>(0, R), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < R; ++i) {
                const Rect cell{-1.0 + i * h, -1.0 + (i + 1) * h, -1.0 + j * h, -1.0 + (j + 1) * h};
                if (near2(cell.x0, cell.x1, cell.y0, cell.y1) >= 1.0) continue;
                mass[size_t(j) * size_t(R) + size_t(i)] = adaptive(f, cores, cell, cubature(f, cell), 0);
            }
    });
    return mass;
}

Core core_of(const Lobe& l) {
    return {std::cos(double(radians(l.rotation_deg()))), std::sin(double(radians(l.rotation_deg()))), double(l.alpha_x()),
            double(l.alpha_y())};
}

void check_lobes(const std::vector<Lobe>& lobes, double& total_weight) {
    if (lobes.empty()) throw InputError("bumpsynth.lobes: the list is empty; an NDF needs at least one lobe");
    total_weight = 0.0;
    for (const Lobe& l : lobes) total_weight += double(l.weight());
    if (!(total_weight > 0.0))
        throw InputError("bumpsynth.weight: the lobe weights sum to 0; at least one lobe needs a positive weight");
}
}  // namespace

// [SECTION] Lobes: factories and closed forms
Lobe Lobe::blinn_phong(float exponent, float weight) {
    if (!(exponent >= 0.f && exponent <= 2e8f))
        throw InputError("bumpsynth.exponent: value " + to_text(exponent) + " must be in [0, 2e8]");
    check_weight(weight);
    Lobe l;
    l.kind_ = LobeKind::blinn_phong;
    l.exponent_ = exponent;
    l.alpha_x_ = l.alpha_y_ = float(std::sqrt(2.0 / (double(exponent) + 2.0)));  // Beckmann-equivalent width
    l.weight_ = weight;
    return l;
}

Lobe Lobe::beckmann(float ax, float ay, float rot, float w) { return anisotropic(LobeKind::beckmann, ax, ay, rot, w); }
Lobe Lobe::ggx(float ax, float ay, float rot, float w) { return anisotropic(LobeKind::ggx, ax, ay, rot, w); }
Lobe Lobe::ward(float ax, float ay, float rot, float w) { return anisotropic(LobeKind::ward, ax, ay, rot, w); }

Lobe Lobe::anisotropic(LobeKind kind, float ax, float ay, float rot, float w) {
    if (kind == LobeKind::blinn_phong) throw std::logic_error("Lobe::anisotropic: Blinn-Phong takes an exponent (Lobe::blinn_phong)");
    check_alpha("bumpsynth.alpha_x", ax);
    check_alpha("bumpsynth.alpha_y", ay);
    check_rotation(rot);
    check_weight(w);
    Lobe l;
    l.kind_ = kind;
    l.alpha_x_ = ax;
    l.alpha_y_ = ay;
    l.rotation_deg_ = rot;
    l.weight_ = w;
    const double rad = double(rot) * (kPiD / 180.0);
    l.cos_ = std::cos(rad);
    l.sin_ = std::sin(rad);
    if (kind == LobeKind::ward) l.ward_k_ = bumpsynth::ward_constant(ax, ay);
    return l;
}

double ward_constant(double ax, double ay) {
    // K⁻¹ = ½ ∫ J(A(φ)) dφ; with tan φ = (α_y/α_x) tan ψ: A = 1/(α_x² cos²ψ + α_y² sin²ψ), dφ = α_x α_y A dψ.
    constexpr int n = 4096;
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
        const double psi = 2.0 * kPiD * (k + 0.5) / n, c = std::cos(psi), s = std::sin(psi);
        const double A = 1.0 / (ax * ax * c * c + ay * ay * s * s);
        sum += A * ward_J(A);
    }
    const double k_inv = 0.5 * ax * ay * (2.0 * kPiD / n) * sum;
    return 1.0 / k_inv;
}

double Lobe::D_xy(double x, double y) const {
    const double r2 = x * x + y * y;
    if (!(r2 <= 1.0)) return 0.0;
    const double z2 = 1.0 - r2;
    if (kind_ == LobeKind::blinn_phong) {
        const double e = exponent_;
        if (z2 <= 0.0) return e == 0.0 ? 1.0 / kPiD : 0.0;
        return (e + 2.0) / (2.0 * kPiD) * std::exp(0.5 * e * std::log1p(-r2));
    }
    const double ax = alpha_x_, ay = alpha_y_;
    const double u = (cos_ * x + sin_ * y) / ax, v = (-sin_ * x + cos_ * y) / ay;
    const double q = u * u + v * v;
    switch (kind_) {
    case LobeKind::beckmann:
        if (z2 <= 0.0) return 0.0;
        return std::exp(-q / z2) / (kPiD * ax * ay * z2 * z2);
    case LobeKind::ggx: {
        const double d = q + z2;
        return d > 0.0 ? 1.0 / (kPiD * ax * ay * d * d) : 0.0;
    }
    case LobeKind::ward:
        if (z2 <= 0.0) return 0.0;
        return ward_k_ * std::exp(-q / z2);
    default:
        return 0.0;
    }
}

double Lobe::D(vec3 m) const {
    const double x = m.x, y = m.y, z = m.z, len = std::sqrt(x * x + y * y + z * z);
    if (!(len > 0.0) || z < 0.0) return 0.0;
    return D_xy(x / len, y / len);
}

double D(const std::vector<Lobe>& lobes, vec3 m) {
    double W = 0.0;
    check_lobes(lobes, W);
    double s = 0.0;
    for (const Lobe& l : lobes)
        if (l.weight() > 0.f) s += double(l.weight()) * l.D(m);
    return s / W;
}

// [SECTION] Geometry
double disk_rect_area(double x0, double x1, double y0, double y1) {
    if (!(x1 > x0 && y1 > y0)) return 0.0;
    if (near2(x0, x1, y0, y1) >= 1.0) return 0.0;
    if (far2(x0, x1, y0, y1) <= 1.0) return (x1 - x0) * (y1 - y0);
    const double a = quadrant_area(x1, y1) - quadrant_area(x0, y1) - quadrant_area(x1, y0) + quadrant_area(x0, y0);
    return std::clamp(a, 0.0, (x1 - x0) * (y1 - y0));
}

vec2 Ndf::cell_centre(int i, int j) const {
    const double h = 2.0 / R_;
    return vec2(float(-1.0 + (i + 0.5) * h), float(-1.0 + (j + 0.5) * h));
}

// [SECTION] Table construction
struct NdfBuilder {
    // Validates and normalises raw cell masses; `key` names the source in errors.
    static Ndf finish(int R, std::vector<double> mass, const std::string& key) {
        double total = 0.0;
        bool finite = true;
        for (double m : mass) {
            finite = finite && std::isfinite(m);
            total += m;
        }
        if (!finite || !std::isfinite(total))
            throw InputError(key + ": the NDF is not finite (NaN or infinite density); it must be finite everywhere");
        if (!(total > 0.0))
            throw InputError(key + ": the NDF is zero everywhere inside the unit disk (all-zero NDF); it needs positive density somewhere");
        Ndf ndf;
        ndf.R_ = R;
        ndf.raw_integral_ = total;
        ndf.mass_ = std::move(mass);
        ndf.area_.assign(ndf.mass_.size(), 0.0);
        ndf.value_.assign(ndf.mass_.size(), 0.f);
        const double h = 2.0 / R;
        const double min_area = 1e-15 * h * h;  // slivers below this count as outside the disk for eval
        mesolab::parallel_for(tbb::blocked_range<int>(0, R), [&](const tbb::blocked_range<int>& rows) {
            for (int j = rows.begin(); j != rows.end(); ++j)
                for (int i = 0; i < R; ++i) {
                    const size_t c = ndf.idx(i, j);
                    ndf.mass_[c] /= total;
                    const double a = disk_rect_area(-1.0 + i * h, -1.0 + (i + 1) * h, -1.0 + j * h, -1.0 + (j + 1) * h);
                    ndf.area_[c] = a > min_area ? a : 0.0;
                    ndf.value_[c] = ndf.area_[c] > 0.0 ? float(ndf.mass_[c] / ndf.area_[c]) : 0.f;
                }
        });
        return ndf;
    }
};

Ndf Ndf::from_lobe(const Lobe& lobe, int resolution) { return from_lobes({lobe}, resolution); }

Ndf Ndf::from_lobes(const std::vector<Lobe>& lobes, int resolution) {
    check_resolution(resolution);
    double W = 0.0;
    check_lobes(lobes, W);
    std::vector<Lobe> used;
    std::vector<Core> cores;
    for (const Lobe& l : lobes)
        if (l.weight() > 0.f) {
            used.push_back(l);
            cores.push_back(core_of(l));
        }
    const auto f = [&](double x, double y) {
        double s = 0.0;
        for (const Lobe& l : used) s += double(l.weight()) * l.D_xy(x, y);
        return s / W;
    };
    return NdfBuilder::finish(resolution, tabulate(resolution, f, cores), "bumpsynth.lobes");
}

Ndf Ndf::from_image(const std::vector<float>& pixels, int width, int height, int resolution) {
    check_resolution(resolution);
    const std::string key = "bumpsynth.ndf_image";
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError(key + ": size " + std::to_string(width) + "x" + std::to_string(height) + " must be within 1x1 to 16384x16384");
    if (pixels.size() != size_t(width) * size_t(height))
        throw InputError(key + ": " + std::to_string(pixels.size()) + " values for a " + std::to_string(width) + "x" + std::to_string(height) +
                         " image (expected " + std::to_string(size_t(width) * size_t(height)) + ")");
    for (size_t p = 0; p < pixels.size(); ++p)
        if (!(pixels[p] >= 0.f) || !std::isfinite(pixels[p]))
            throw InputError(key + ": pixel (" + std::to_string(p % size_t(width)) + ", " + std::to_string(p / size_t(width)) + ") has value " +
                             to_text(pixels[p]) + "; NDF values must be finite and >= 0");
    const int R = resolution;
    const double h = 2.0 / R, pw = 2.0 / width, ph = 2.0 / height;
    std::vector<double> mass(size_t(R) * size_t(R), 0.0);
    mesolab::parallel_for(tbb::blocked_range<int>(0, R), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < R; ++i) {
                const double cx0 = -1.0 + i * h, cx1 = -1.0 + (i + 1) * h, cy0 = -1.0 + j * h, cy1 = -1.0 + (j + 1) * h;
                if (near2(cx0, cx1, cy0, cy1) >= 1.0) continue;
                // Pixel column px covers x in [-1 + px pw, -1 + (px+1) pw]; row py covers y in [1 - (py+1) ph, 1 - py ph].
                const int px0 = std::max(0, int(std::floor((cx0 + 1.0) / pw))), px1 = std::min(width - 1, int(std::ceil((cx1 + 1.0) / pw)) - 1);
                const int py0 = std::max(0, int(std::floor((1.0 - cy1) / ph))), py1 = std::min(height - 1, int(std::ceil((1.0 - cy0) / ph)) - 1);
                double m = 0.0;
                for (int py = py0; py <= py1; ++py) {
                    const double y0 = std::max(cy0, 1.0 - (py + 1) * ph), y1 = std::min(cy1, 1.0 - py * ph);
                    if (!(y1 > y0)) continue;
                    for (int px = px0; px <= px1; ++px) {
                        const float v = pixels[size_t(py) * size_t(width) + size_t(px)];
                        if (v == 0.f) continue;
                        const double x0 = std::max(cx0, -1.0 + px * pw), x1 = std::min(cx1, -1.0 + (px + 1) * pw);
                        m += double(v) * disk_rect_area(x0, x1, y0, y1);
                    }
                }
                mass[size_t(j) * size_t(R) + size_t(i)] = m;
            }
    });
    return NdfBuilder::finish(R, std::move(mass), key);
}

Ndf Ndf::from_normals(const std::vector<vec3>& normals, int resolution) {
    check_resolution(resolution);
    const std::string key = "bumpsynth.normals";
    if (normals.empty()) throw InputError(key + ": the list is empty; an NDF from normals needs at least one normal");
    const int R = resolution;
    const double h = 2.0 / R;
    std::vector<double> count(size_t(R) * size_t(R), 0.0);
    for (size_t k = 0; k < normals.size(); ++k) {
        const vec3 n = normals[k];
        double x = n.x, y = n.y, z = n.z;
        const double len = std::sqrt(x * x + y * y + z * z);
        if (!std::isfinite(len) || !(len > 0.0))
            throw InputError(key + ": normal " + std::to_string(k) + " (" + to_text(n.x) + ", " + to_text(n.y) + ", " + to_text(n.z) +
                             ") is not a finite non-zero vector");
        x /= len;
        y /= len;
        z /= len;
        if (z < -1e-6)
            throw InputError(key + ": normal " + std::to_string(k) + " has z = " + to_text(z) +
                             " < 0; microfacet normals must point into the upper hemisphere");
        const double r = std::sqrt(x * x + y * y), r_max = 1.0 - 1e-9;
        if (r > r_max) {
            x *= r_max / r;
            y *= r_max / r;
        }
        const int i = std::clamp(int(std::floor((x + 1.0) / h)), 0, R - 1), j = std::clamp(int(std::floor((y + 1.0) / h)), 0, R - 1);
        count[size_t(j) * size_t(R) + size_t(i)] += 1.0;
    }
    const double N = double(normals.size());
    for (double& c : count) c /= N;
    return NdfBuilder::finish(R, std::move(count), key);
}

// [SECTION] Evaluation
double Ndf::integral() const {
    double s = 0.0;
    for (size_t c = 0; c < mass_.size(); ++c) s += double(value_[c]) * area_[c];
    return s;
}

float Ndf::eval(vec2 xy) const {
    double x = xy.x, y = xy.y;
    const double r2 = x * x + y * y;
    if (R_ == 0 || !(r2 <= 1.0 + 1e-6)) return 0.f;  // float rounding of unit vectors: on the rim
    if (r2 > 1.0) {
        x /= std::sqrt(r2);
        y /= std::sqrt(r2);
    }
    const double h = 2.0 / R_;
    const double fx = (x + 1.0) / h - 0.5, fy = (y + 1.0) / h - 0.5;
    const int i0 = int(std::floor(fx)), j0 = int(std::floor(fy));
    const double tx = fx - i0, ty = fy - j0;
    double sum = 0.0, sum_w = 0.0;
    for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di) {
            const int i = i0 + di, j = j0 + dj;
            if (i < 0 || j < 0 || i >= R_ || j >= R_ || area_[idx(i, j)] <= 0.0) continue;
            const double w = (di ? tx : 1.0 - tx) * (dj ? ty : 1.0 - ty);
            sum += w * double(value_[idx(i, j)]);
            sum_w += w;
        }
    if (sum_w > 0.0) return float(sum / sum_w);
    // Only cells outside the disk carry weight: the cell containing (x, y).
    const int i = std::clamp(int(std::floor((x + 1.0) / h)), 0, R_ - 1), j = std::clamp(int(std::floor((y + 1.0) / h)), 0, R_ - 1);
    return value_[idx(i, j)];
}

float Ndf::eval(vec3 m) const {
    const double len = std::sqrt(double(m.x) * m.x + double(m.y) * m.y + double(m.z) * m.z);
    if (!(len > 0.0) || m.z < 0.f) return 0.f;
    return eval(vec2(float(m.x / len), float(m.y / len)));
}
// [SECTION] Lists of lobes as text
namespace {

class LobeParser {
public:
    explicit LobeParser(std::string_view t) : t_(t) {}

    std::vector<Lobe> parse() {
        std::vector<Lobe> out;
        skip();
        if (pos_ == t_.size()) fail("the list is empty; write e.g. beckmann(0.3) + 0.5 * ggx(0.05, 0.5, 45)");
        do out.push_back(term(int(out.size()) + 1));
        while (accept('+'));
        if (pos_ != t_.size()) fail("expected '+' or the end, found '" + std::string(1, t_[pos_]) + "'");
        return out;
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError("at character " + std::to_string(pos_ + 1) + ": " + what);
    }
    void skip() {
        while (pos_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[pos_]))) ++pos_;
    }
    bool accept(char c) {
        skip();
        if (pos_ < t_.size() && t_[pos_] == c) {
            ++pos_;
            skip();
            return true;
        }
        return false;
    }
    void expect(char c, const char* after) {
        if (!accept(c)) fail(std::string("expected '") + c + "' " + after);
    }
    bool at_number() const {
        return pos_ < t_.size() && (std::isdigit(static_cast<unsigned char>(t_[pos_])) || t_[pos_] == '.' || t_[pos_] == '-' || t_[pos_] == '+');
    }
    double number(const char* what) {
        skip();
        const char* b = t_.data() + pos_;
        char* e = nullptr;
        const std::string s(b, t_.size() - pos_);
        const double v = std::strtod(s.c_str(), &e);
        const size_t n = size_t(e - s.c_str());
        if (n == 0) fail(std::string("expected a number (") + what + ")");
        pos_ += n;
        skip();
        return v;
    }
    Lobe term(int index) {
        double w = 1.0;
        if (at_number()) {
            w = number("a weight");
            expect('*', "after the weight");
        }
        size_t b = pos_;
        while (pos_ < t_.size() && std::isalpha(static_cast<unsigned char>(t_[pos_]))) ++pos_;
        const std::string kind(t_.substr(b, pos_ - b));
        if (kind.empty()) fail("expected a lobe: phong, beckmann, ggx or ward");
        LobeKind k = LobeKind::beckmann;
        if (!lobe_kind(kind, k)) {
            pos_ = b;
            fail("unknown lobe '" + kind + "' (expected phong, beckmann, ggx or ward)");
        }
        expect('(', ("after '" + kind + "'").c_str());
        std::vector<double> a{number("a lobe parameter")};
        while (accept(',')) a.push_back(number("a lobe parameter"));
        expect(')', "after the lobe's parameters");
        if (accept('*')) w *= number("a weight");
        const size_t most = kind == "phong" ? 1 : 3;
        if (a.size() > most) fail(kind + " takes " + (kind == "phong" ? std::string("1 parameter (the exponent)") : "1 to 3 parameters (alpha_x, alpha_y, rotation)") +
                                  ", got " + std::to_string(a.size()));
        try {
            if (k == LobeKind::blinn_phong) return Lobe::blinn_phong(float(a[0]), float(w));
            return Lobe::anisotropic(k, float(a[0]), float(a.size() > 1 ? a[1] : a[0]), float(a.size() > 2 ? a[2] : 0.0), float(w));
        } catch (const InputError& e) {
            std::string msg = e.what();
            if (msg.rfind("bumpsynth.", 0) == 0) msg = msg.substr(10);  // the lobe's own field, not a key
            throw InputError("lobe " + std::to_string(index) + " (" + kind + "): " + msg);
        }
    }

    std::string_view t_;
    size_t pos_ = 0;
};

std::string short_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}
}  // namespace

const char* lobe_name(LobeKind kind) {
    switch (kind) {
        case LobeKind::blinn_phong: return "phong";
        case LobeKind::beckmann: return "beckmann";
        case LobeKind::ggx: return "ggx";
        case LobeKind::ward: return "ward";
    }
    return "beckmann";
}

bool lobe_kind(std::string_view name, LobeKind& kind) {
    for (LobeKind k : {LobeKind::blinn_phong, LobeKind::beckmann, LobeKind::ggx, LobeKind::ward})
        if (name == lobe_name(k)) {
            kind = k;
            return true;
        }
    return false;
}

std::vector<Lobe> parse_lobes(std::string_view text) {
    std::vector<Lobe> lobes = LobeParser(text).parse();
    double sum = 0.0;
    for (const Lobe& l : lobes) sum += l.weight();
    if (!(sum > 0.0)) throw InputError("the lobe weights sum to 0; at least one lobe needs a positive weight");
    return lobes;
}

std::string lobes_syntax_error(const std::string& text) {
    try {
        parse_lobes(text);
        return {};
    } catch (const InputError& e) {
        return e.what();
    }
}

std::string format_lobe(const Lobe& l) {
    std::string s = l.weight() == 1.f ? "" : short_number(l.weight()) + " * ";
    if (l.kind() == LobeKind::blinn_phong) return s + "phong(" + short_number(l.exponent()) + ")";
    s += std::string(lobe_name(l.kind())) + "(";
    s += short_number(l.alpha_x());
    if (l.alpha_y() != l.alpha_x() || l.rotation_deg() != 0.f) s += ", " + short_number(l.alpha_y());
    if (l.rotation_deg() != 0.f) s += ", " + short_number(l.rotation_deg());
    return s + ")";
}

std::string format_lobes(const std::vector<Lobe>& lobes) {
    std::string s;
    for (const Lobe& l : lobes) s += (s.empty() ? "" : " + ") + format_lobe(l);
    return s;
}
}  // namespace mesolab::bumpsynth
