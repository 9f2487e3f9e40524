#include "core/bumpsynth/lut.h"
#include "core/parallel.h"

#include "core/error.h"

#include <tbb/blocked_range.h>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace mesolab::bumpsynth {

namespace {

constexpr double kMaxR2 = 1.0 - 1e-8;  // |(x, y)|² of a sampled normal, so m_z >= 1e-4

std::string to_text(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// r clamped to [0, 1]; NaN counts as 0.
double clamp01(double r) { return r > 0.0 ? (r < 1.0 ? r : 1.0) : 0.0; }

// [SECTION] Inversion of a piecewise-linear CDF
// cdf has n + 1 values at the interval edges (cdf[0] = 0, cdf[n] = 1, non-decreasing). Finds the
// interval k with cdf[k] <= u < cdf[k+1], which always has mass (zero-mass intervals are skipped),
// and the position t in [0, 1) inside it; u >= 1 takes the end of the last interval with mass.
void invert_cdf(const double* cdf, int n, int last, double u, int& k, double& t) {
    u = clamp01(u);
    const int e = int(std::upper_bound(cdf, cdf + n + 1, u) - cdf);  // first edge > u, >= 1
    if (e > n) {
        k = last;
        t = 1.0;
        return;
    }
    k = e - 1;
    t = (u - cdf[k]) / (cdf[k + 1] - cdf[k]);
}

// Last interval with mass (-1 if none).
int last_with_mass(const double* cdf, int n) {
    for (int k = n - 1; k >= 0; --k)
        if (cdf[k + 1] > cdf[k]) return k;
    return -1;
}

void check_knots(const std::vector<double>& r, std::vector<double>& g, const std::string& key) {
    if (r.size() < 2 || r.size() != g.size())
        throw InputError(key + ": " + std::to_string(r.size()) + " abscissae and " + std::to_string(g.size()) +
                         " values; G needs the same number of both, at least 2");
    for (size_t k = 0; k < r.size(); ++k)
        if (!std::isfinite(r[k]) || !std::isfinite(g[k]))
            throw InputError(key + ": knot " + std::to_string(k) + " (" + to_text(r[k]) + ", " + to_text(g[k]) + ") is not finite");
    for (size_t k = 0; k < g.size(); ++k) {
        if (g[k] < -1e-6 || g[k] > 1.0 + 1e-6)
            throw InputError(key + ": value " + to_text(g[k]) + " at knot " + std::to_string(k) + " must be in [0, 1]");
        g[k] = std::clamp(g[k], 0.0, 1.0);
        if (k > 0 && g[k] < g[k - 1])
            throw InputError(key + ": value " + to_text(g[k]) + " at knot " + std::to_string(k) + " is below the previous " +
                             to_text(g[k - 1]) + "; a CDF must be non-decreasing");
        if (k > 0 && !(r[k] > r[k - 1]))
            throw InputError(key + ": abscissa " + to_text(r[k]) + " at knot " + std::to_string(k) + " must be above the previous " +
                             to_text(r[k - 1]));
    }
    if (std::fabs(r.front()) > 1e-6 || std::fabs(r.back() - 1.0) > 1e-6)
        throw InputError(key + ": the knots span [" + to_text(r.front()) + ", " + to_text(r.back()) + "]; they must span [0, 1]");
    if (std::fabs(g.back() - 1.0) > 1e-6)
        throw InputError(key + ": G(1) = " + to_text(g.back()) + "; a CDF must end at 1");
    g.back() = 1.0;
}
}  // namespace

// [SECTION] Input CDF G
InputCdf::InputCdf() : r_{0.0, 1.0}, g_{0.0, 1.0} {}

InputCdf InputCdf::tabulated(const std::vector<float>& g) {
    std::vector<double> r(g.size()), gd(g.begin(), g.end());
    for (size_t k = 0; k < g.size(); ++k) r[k] = g.size() > 1 ? double(k) / double(g.size() - 1) : 0.0;
    return from_knots(r, gd);
}

InputCdf InputCdf::from_knots(const std::vector<double>& r, const std::vector<double>& g) {
    std::vector<double> gg = g;
    check_knots(r, gg, "bumpsynth.input_cdf");
    InputCdf c;
    c.r_ = r;
    c.r_.front() = 0.0;
    c.r_.back() = 1.0;
    c.g_ = std::move(gg);
    return c;
}

double InputCdf::operator()(double r) const {
    r = clamp01(r);
    if (is_identity()) return r;
    const int n = int(r_.size());
    const int k = std::clamp(int(std::upper_bound(r_.begin(), r_.end(), r) - r_.begin()) - 1, 0, n - 2);
    const double t = (r - r_[size_t(k)]) / (r_[size_t(k) + 1] - r_[size_t(k)]);
    return g_[size_t(k)] + t * (g_[size_t(k) + 1] - g_[size_t(k)]);
}

double InputCdf::inverse(double u) const {
    u = clamp01(u);
    if (is_identity()) return u;
    if (u < g_.front()) return 0.0;  // inside an atom at r = 0
    const size_t k1 = size_t(std::lower_bound(g_.begin(), g_.end(), u) - g_.begin());  // first g >= u (exists: g_back = 1)
    if (g_[k1] > u) {  // strictly inside segment (k1-1, k1); k1 >= 1 since g_0 <= u
        const double t = (u - g_[k1 - 1]) / (g_[k1] - g_[k1 - 1]);
        return r_[k1 - 1] + t * (r_[k1] - r_[k1 - 1]);
    }
    const size_t k2 = size_t(std::upper_bound(g_.begin(), g_.end(), u) - g_.begin()) - 1;  // last g == u
    return 0.5 * (r_[k1] + r_[k2]);
}

InputCdf measure_input_cdf(const std::vector<float>& samples, int bins, CdfBinning binning) {
    if (samples.empty()) throw InputError("bumpsynth.input_samples: no samples; measuring G needs at least one");
    if (bins < 1 || bins > (1 << 20))
        throw InputError("bumpsynth.input_cdf_bins: value " + std::to_string(bins) + " must be in [1, 1048576]");
    std::vector<double> s(samples.size());
    for (size_t k = 0; k < samples.size(); ++k) {
        if (!std::isfinite(samples[k]))
            throw InputError("bumpsynth.input_samples: sample " + std::to_string(k) + " is " + to_text(samples[k]) + "; samples must be finite");
        s[k] = clamp01(samples[k]);
    }
    std::sort(s.begin(), s.end());
    // Knot abscissae: r = k/B and/or the midpoints between the order statistics around ranks kN/B.
    std::vector<double> knots;
    if (binning != CdfBinning::equal_count)
        for (int k = 0; k <= bins; ++k) knots.push_back(double(k) / bins);
    if (binning != CdfBinning::equal_width)
        for (int k = 1; k < bins; ++k) {
            const size_t idx = size_t(std::llround(double(k) * double(s.size()) / bins));
            if (idx > 0 && idx < s.size()) knots.push_back(0.5 * (s[idx - 1] + s[idx]));
        }
    knots.push_back(0.0);
    knots.push_back(1.0);
    std::sort(knots.begin(), knots.end());
    knots.erase(std::unique(knots.begin(), knots.end()), knots.end());
    // G at the knots: the empirical CDF, fraction of samples <= r (G(1) = 1).
    const double N = double(s.size());
    std::vector<double> g(knots.size());
    for (size_t k = 0; k < knots.size(); ++k) g[k] = double(std::upper_bound(s.begin(), s.end(), knots[k]) - s.begin()) / N;
    g.back() = 1.0;
    return InputCdf::from_knots(knots, g);
}

// [SECTION] Microfacet frame
LutEntry microfacet_frame(vec3 mf) {
    const double x = mf.x, y = mf.y, z = mf.z, k = 1.0 / (1.0 + z);
    LutEntry e;
    e.m = mf;
    e.t = vec3(float(1.0 - x * x * k), float(-x * y * k), float(-x));
    e.b = vec3(float(-x * y * k), float(1.0 - y * y * k), float(-y));
    return e;
}

// [SECTION] Sampling
void Lut::invert_marginal(double u, int& i, double& tx) const { invert_cdf(M_.data(), R_, last_column_[0], u, i, tx); }

vec3 Lut::normal_in_column(int i, double x, double u2) const {
    const double* C = C_.data() + size_t(i) * size_t(R_ + 1);
    int j = 0;
    double ty = 0.0;
    invert_cdf(C, R_, std::max(0, last_cell_[size_t(i)]), u2, j, ty);
    const double y0 = -1.0 + j * h(), y1 = y0 + h();
    double Y = std::sqrt(std::max(0.0, 1.0 - x * x));
    double lo = std::max(y0, -Y), hi = std::min(y1, Y);
    if (hi < lo) {
        // The chord at x misses the cell: the nearest x of the column whose chord reaches it.
        const double e = y0 > 0.0 ? y0 : -y1;  // the cell's y-edge nearest to the x axis (> Y)
        const double xl = std::sqrt(std::max(0.0, 1.0 - e * e));
        const double cx0 = -1.0 + i * h(), cx1 = cx0 + h();
        const double xa = std::max(cx0, -xl), xb = std::max(xa, std::min(cx1, xl));
        x = std::clamp(x, xa, xb);
        Y = std::sqrt(std::max(0.0, 1.0 - x * x));
        lo = std::max(y0, -Y);
        hi = std::max(lo, std::min(y1, Y));
    }
    double y = lo + ty * (hi - lo);
    const double r2 = x * x + y * y;
    if (r2 > kMaxR2) {
        const double s = std::sqrt(kMaxR2 / r2);
        x *= s;
        y *= s;
    }
    const double z = std::sqrt(1.0 - x * x - y * y);
    return vec3(float(x), float(y), float(z));
}

vec3 Lut::sample_uniform(double u1, double u2) const {
    int i = 0;
    double tx = 0.0;
    invert_marginal(u1, i, tx);
    return normal_in_column(i, -1.0 + (i + tx) * h(), u2);
}

LutEntry Lut::sample(vec2 r) const { return microfacet_frame(sample_uniform(G_(r.x), G_(r.y))); }

// In float, as the GLSL (gpu/bumpsynth/synthesis.glsl lut_entry): r S rounds in float where S is
// not a power of two, and the double product truncates to the entry below where the float one
// reaches the next integer.
ivec2 Lut::entry(vec2 r) const {
    const auto index = [&](float v) { return std::min(S_ - 1, int((v > 0.f ? (v < 1.f ? v : 1.f) : 0.f) * float(S_))); };
    return {index(r.x), index(r.y)};
}

// [SECTION] CDFs and the inverse map (§7)
double Lut::marginal_cdf(double x) const {
    x = std::clamp(x, -1.0, 1.0);
    const int i = std::clamp(int(std::floor((x + 1.0) / h())), 0, R_ - 1);
    const double tx = std::clamp((x - (-1.0 + i * h())) / h(), 0.0, 1.0);
    return M_[size_t(i)] + tx * (M_[size_t(i) + 1] - M_[size_t(i)]);
}

double Lut::conditional_in_column(int i, double x, double y) const {
    const double* C = C_.data() + size_t(i) * size_t(R_ + 1);
    y = std::clamp(y, -1.0, 1.0);
    const int j = std::clamp(int(std::floor((y + 1.0) / h())), 0, R_ - 1);
    const double y0 = -1.0 + j * h(), y1 = y0 + h();
    const double Y = std::sqrt(std::max(0.0, 1.0 - x * x));
    const double lo = std::max(y0, -Y), hi = std::min(y1, Y);
    const double ty = hi > lo ? std::clamp((y - lo) / (hi - lo), 0.0, 1.0) : 0.5;
    return C[j] + ty * (C[j + 1] - C[j]);
}

double Lut::conditional_cdf(double y, double x) const {
    x = std::clamp(x, -1.0, 1.0);
    return conditional_in_column(std::clamp(int(std::floor((x + 1.0) / h())), 0, R_ - 1), x, y);
}

vec2 Lut::index(vec3 m) const {
    double x = m.x, y = m.y, z = m.z;
    const double len = std::sqrt(x * x + y * y + z * z);
    if (!std::isfinite(len) || !(len > 0.0)) {
        x = y = 0.0;
    } else {
        x /= len;
        y /= len;
        z /= len;
        const double rr = std::sqrt(x * x + y * y);
        if (z < 0.0 && rr > 0.0) {  // below the horizon: the rim point of its azimuth
            x /= rr;
            y /= rr;
        }
    }
    const float r1 = float(G_.inverse(marginal_cdf(x)));
    // C in the column that the forward map selects for this (float) r1.
    int i = 0;
    double tx = 0.0;
    invert_marginal(G_(r1), i, tx);
    const double x2 = -1.0 + (i + tx) * h();
    const float r2 = float(G_.inverse(conditional_in_column(i, x2, y)));
    return vec2(r1, r2);
}

// [SECTION] Construction
Lut build_lut(const Ndf& ndf, int size, const InputCdf& g) {
    if (size < Lut::kMinSize || size > Lut::kMaxSize)
        throw InputError("bumpsynth.lut_size: value " + std::to_string(size) + " must be in [" + std::to_string(Lut::kMinSize) + ", " +
                         std::to_string(Lut::kMaxSize) + "]");
    const int R = ndf.resolution();
    if (R <= 0) throw std::invalid_argument("build_lut: empty NDF");
    Lut L;
    L.R_ = R;
    L.S_ = size;
    L.G_ = g;
    // Marginal M over the columns (cell masses already include the cell areas).
    std::vector<double> column(size_t(R), 0.0);
    for (int i = 0; i < R; ++i)
        for (int j = 0; j < R; ++j) column[size_t(i)] += ndf.mass(i, j);
    L.M_.assign(size_t(R) + 1, 0.0);
    for (int i = 0; i < R; ++i) L.M_[size_t(i) + 1] = L.M_[size_t(i)] + column[size_t(i)];
    const double total = L.M_[size_t(R)];
    if (!(total > 0.0) || !std::isfinite(total)) throw std::invalid_argument("build_lut: NDF without mass");
    for (double& v : L.M_) v = std::min(1.0, v / total);
    L.M_[size_t(R)] = 1.0;
    L.last_column_ = {last_with_mass(L.M_.data(), R)};
    // Conditional C(y | x) per column; a column without mass gets a uniform CDF (never sampled).
    L.C_.assign(size_t(R) * size_t(R + 1), 0.0);
    L.last_cell_.assign(size_t(R), -1);
    mesolab::parallel_for(tbb::blocked_range<int>(0, R), [&](const tbb::blocked_range<int>& cols) {
        for (int i = cols.begin(); i != cols.end(); ++i) {
            double* C = L.C_.data() + size_t(i) * size_t(R + 1);
            for (int j = 0; j < R; ++j) C[j + 1] = C[j] + ndf.mass(i, j);
            const double col = C[R];
            if (col > 0.0) {
                for (int j = 0; j <= R; ++j) C[j] = std::min(1.0, C[j] / col);
                C[R] = 1.0;
                L.last_cell_[size_t(i)] = last_with_mass(C, R);
            } else {
                for (int j = 0; j <= R; ++j) C[j] = double(j) / R;
            }
        }
    });
    // Entries at the texel centres: the column and x depend on r1 only.
    const int S = size;
    std::vector<int> col_of(static_cast<size_t>(S));
    std::vector<double> x_of(static_cast<size_t>(S));
    for (int a = 0; a < S; ++a) {
        int i = 0;
        double tx = 0.0;
        L.invert_marginal(L.G_((a + 0.5) / S), i, tx);
        col_of[size_t(a)] = i;
        x_of[size_t(a)] = -1.0 + (i + tx) * L.h();
    }
    L.entries_.resize(size_t(S) * size_t(S));
    mesolab::parallel_for(tbb::blocked_range<int>(0, S), [&](const tbb::blocked_range<int>& rows) {
        for (int b = rows.begin(); b != rows.end(); ++b) {
            const double u2 = L.G_((b + 0.5) / S);
            for (int a = 0; a < S; ++a)
                L.entries_[size_t(b) * size_t(S) + size_t(a)] = microfacet_frame(L.normal_in_column(col_of[size_t(a)], x_of[size_t(a)], u2));
        }
    });
    return L;
}
}  // namespace mesolab::bumpsynth
