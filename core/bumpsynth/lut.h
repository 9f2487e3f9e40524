#pragma once
// The normal look-up table L(r1, r2) of bump-map synthesis (Kautz, Heidrich, Seidel 2001, §4, §5.1, §7).
//
// [SECTION] Sampling by inversion (§4)
// The tabulated NDF (ndf.h) is a piecewise-constant density f(x, y) over the unit disk with cell
// masses P_ij (x = m_x, y = m_y; cell area already included: P_ij = ∫_cell f dx dy, Σ P_ij = 1).
//   marginal     m(x) = ∫ f(x, y) dy,   M(x) = ∫_{-1}^{x} m           (piecewise linear in x)
//   conditional  c(y | x) = f(x, y) / m(x),  C(y | x) = ∫_{-1}^{y} c    (per column of cells)
// Both CDFs are stored at the R + 1 cell edges and inverted numerically with linear interpolation
// inside a cell (i.e. uniform within the cell), so a uniform u lands in cell (i, j) with probability
// exactly P_ij. The inversion finds the interval with M_k <= u < M_{k+1}, which skips zero-mass
// intervals: no sample ever falls in a cell of zero mass (u = 1 takes the last interval with mass).
// Inside a cell that the unit circle cuts, y is interpolated over the cell's part of the chord at x,
// [y_j, y_j+1] ∩ [-sqrt(1-x²), sqrt(1-x²)]; where that part is empty, x moves to the nearest x of the
// column whose chord reaches the cell. Finally sqrt(x² + y²) <= sqrt(1 - 1e-8), so m_z >= 1e-4:
// every normal is unit, in the upper hemisphere, and inside (within 1e-8 of) the cell it was drawn in.
// The table's resolution is the NDF's cell size h = 2/R: a lobe narrower than a cell is sampled
// uniformly over the cells that hold its mass.
//
// [SECTION] Non-uniform inputs (§4)
// The inputs r1, r2 (e.g. fractal Perlin noise, §3.3, §5.2.2) need not be uniform. With G the CDF
// of their (common) distribution, u = G(r) is uniform, so
//   x = M⁻¹(G(r1)),  y = C⁻¹(G(r2) | x),   m = (x, y, sqrt(1 - x² - y²)).
// G is tabulated (InputCdf): piecewise linear through knots (r_k, G_k), identity by default.
// measure_input_cdf builds it from samples of the inputs (the paper computes it numerically).
// Within a knot interval G maps the inputs uniformly, so the knots must be dense wherever the
// input density changes quickly relative to itself (its fading tails, singularities).
//
// [SECTION] The table
// S x S entries (default 256, the paper's size), entry (a, b) at the texel centre
// r1 = (a + 0.5)/S, r2 = (b + 0.5)/S (as a texture: a along u, b along v; row-major b S + a).
// Each holds the microfacet normal m and a tangent frame (t, b) (§4: needed for anisotropic NDFs,
// §5.1: the half vector is projected into {t, b, m}). The frame is the macro frame (x, y, z) turned by
// the smallest rotation taking n = +z to m (deterministic, continuous over the whole hemisphere):
//   t = (1 - m_x²/(1+m_z), -m_x m_y/(1+m_z), -m_x),  b = (-m_x m_y/(1+m_z), 1 - m_y²/(1+m_z), -m_y),
// so t × b = m, and at m = n the frame is the macro frame.
// Nearest-entry lookup quantises the inputs to 1/S: on 16² bins the entries' distribution is within
// a total variation of ~1% of the NDF at S = 256 (~0.3% at S = 1024), which a 200k-sample χ² does
// see; sample() is the exact map (a software renderer, §5.1, can call it directly).
// Build: ~1.3 ms for 256² from a 128² NDF on 2 cores (Release; ~7 ms under ASan+UBSan): the CDFs in
// O(R²), then one binary search per entry (the column depends on r1 only), TBB over rows.
//
// [SECTION] Inverse map (§7)
// index(m) = (G⁻¹(M(x)), G⁻¹(C(y | x))): the inputs that look up the normal m, to turn an existing
// bump map into an index texture (noise can then be added to it when zooming in). G⁻¹ takes the
// middle of a flat part of G. C is taken in the column that M⁻¹(G(r1)) will select (so a normal at a
// column edge comes back exactly); sample(index(m)) = m within float precision of r wherever the
// NDF is positive: (x, y) within ~1e-5 where the CDFs' densities are >= 1e-3 per unit; in m the
// error grows like 1/m_z towards the horizon (< 2e-4 for m_z >= 0.01 in the tests). Where the NDF
// is zero the index is still finite, and maps to a normal with mass.
#include "core/bumpsynth/ndf.h"
#include "core/math.h"
#include <vector>

namespace mesolab::bumpsynth {

// The CDF G of the input values r in [0, 1] (§4), piecewise linear through knots (r_k, g_k):
// r_0 = 0 < r_1 < ... < r_{n-1} = 1, 0 <= g_0 <= ... <= g_{n-1} = 1.
class InputCdf {
public:
    InputCdf();  // identity: G(r) = r
    static InputCdf identity() { return InputCdf(); }
    // g_k = G(k / (n-1)) on a uniform grid, n >= 2. InputError (bumpsynth.input_cdf) unless
    // finite, non-decreasing, in [0, 1] and ending at 1 (within 1e-6; then snapped).
    static InputCdf tabulated(const std::vector<float>& g);
    // Arbitrary knots (same rules; r strictly increasing from 0 to 1).
    static InputCdf from_knots(const std::vector<double>& r, const std::vector<double>& g);

    double operator()(double r) const;  // G(r); r clamped to [0, 1], NaN counts as 0
    double inverse(double u) const;     // G⁻¹(u) in [0, 1]; the middle of a flat part of G
    bool is_identity() const { return r_.size() == 2 && g_[0] == 0.0; }
    const std::vector<double>& knots_r() const { return r_; }
    const std::vector<double>& knots_g() const { return g_; }

private:
    std::vector<double> r_, g_;
};

enum class CdfBinning {
    combined,     // both knot sets below (default): dense where the density is high and across [0, 1]
    equal_count,  // knots at the sample quantiles k/B: follows singular densities (e.g. r = u², G = sqrt r)
                  // but is sparse where a density fades out (bell-shaped noise), biasing G's tails
    equal_width,  // knots at r = k/B (the classic histogram CDF): coarse where a density is singular
};

// G measured from samples of the inputs (§4: "the actual distribution g(x) of the Perlin turbulence
// is also computed numerically"): the empirical CDF (fraction of samples <= r) at the knots of
// `binning` with `bins` bins (combined: up to 2 bins + 1 knots), linear in between. Samples are
// clamped to [0, 1] (as a texture lookup clamps). InputError (bumpsynth.input_samples) for no samples
// or a non-finite one, and (bumpsynth.input_cdf_bins) for bins outside [1, 1 << 20].
// G is linear between knots: a 200k-sample χ² sees no bias with the default 4096 bins, for smooth
// input densities and even for a singular one (r = u²: 1024 knots are visibly too few there).
InputCdf measure_input_cdf(const std::vector<float>& samples, int bins = 4096, CdfBinning binning = CdfBinning::combined);

struct LutEntry {
    vec3 m{0.f, 0.f, 1.f};  // microfacet normal (unit, m_z > 0)
    vec3 t{1.f, 0.f, 0.f};  // tangent
    vec3 b{0.f, 1.f, 0.f};  // bitangent, t × b = m
};

// The microfacet frame for a unit normal m (m_z > -1), as above.
LutEntry microfacet_frame(vec3 m);

class Lut {
public:
    static constexpr int kDefaultSize = 256;
    static constexpr int kMinSize = 2, kMaxSize = 4096;

    int size() const { return S_; }
    int ndf_resolution() const { return R_; }
    const InputCdf& input_cdf() const { return G_; }
    const std::vector<LutEntry>& entries() const { return entries_; }
    const LutEntry& at(int a, int b) const { return entries_[size_t(b) * size_t(S_) + size_t(a)]; }

    // Nearest entry for inputs r (a texture lookup with nearest filtering; r clamped to [0, 1]).
    const LutEntry& lookup(vec2 r) const { const ivec2 e = entry(r); return at(e.x, e.y); }
    // Its indices (a, b).
    ivec2 entry(vec2 r) const;
    // The exact map for inputs r (what the entries hold at their texel centres; §5.1 software path).
    LutEntry sample(vec2 r) const;
    // The same for already uniform u = (G(r1), G(r2)), without G.
    vec3 sample_uniform(double u1, double u2) const;
    // §7: inputs (r1, r2) whose sample is m (m normalised; below the horizon: taken at the rim).
    vec2 index(vec3 m) const;

    // The CDFs: M(x) and C(y | x) (x, y in [-1, 1]; C in x's column).
    double marginal_cdf(double x) const;
    double conditional_cdf(double y, double x) const;

private:
    friend Lut build_lut(const Ndf& ndf, int size, const InputCdf& g);
    double h() const { return 2.0 / R_; }
    void invert_marginal(double u, int& i, double& tx) const;
    vec3 normal_in_column(int i, double x, double u2) const;
    double conditional_in_column(int i, double x, double y) const;
    int R_ = 0, S_ = 0;
    InputCdf G_;
    std::vector<double> M_;          // R + 1 edges
    std::vector<double> C_;          // R columns x (R + 1) edges
    std::vector<int> last_column_;   // [0]: last column with mass
    std::vector<int> last_cell_;     // per column: last cell with mass (-1: none)
    std::vector<LutEntry> entries_;
};

// Builds L for an NDF (§4). InputError (bumpsynth.lut_size) for a size outside [2, 4096];
// std::invalid_argument for an empty (default-constructed) Ndf.
Lut build_lut(const Ndf& ndf, int size = Lut::kDefaultSize, const InputCdf& g = InputCdf());
}  // namespace mesolab::bumpsynth
