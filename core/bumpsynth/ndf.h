#pragma once
// Normal density functions (NDFs) for bump-map synthesis (Kautz, Heidrich, Seidel 2001, §3.1, §4).
//
// [SECTION] Model
// Microfacet normals m are unit vectors in the macro tangent frame: n = +z (macro normal), +x the
// macro tangent, +y the bitangent. The NDF D(m) (sr^-1) is the paper's p(n_m) (§3.1, Fig. 2): the
// density of microfacet orientations, normalised by projected area,
//     ∫_H D(m) (m·n) dω = 1                                          (H: upper hemisphere)
// so that it can shade directly, D(h) at the half vector (§3.1, §5), and be sampled (§4).
// The paper stores the NDF "in a 2D hemispherical map directly using the x- and y-component of the
// normals" (§4, Fig. 2 right). With (x, y) = (m_x, m_y) in the unit disk and m_z = sqrt(1-x²-y²),
// dω = dx dy / m_z, so ∫_H D(m) m_z dω = ∫_disk D dx dy = 1: in this parametrisation D itself is the
// probability density of (x, y), the f(x, y) of §4 (dimensionless per unit projected area).
//
// [SECTION] Analytic lobes (closed forms, Lobe::D)
// In the lobe frame, rotated by `rotation` degrees from +x towards +y (x' = cos ρ x + sin ρ y,
// y' = -sin ρ x + cos ρ y) and q = x'²/α_x² + y'²/α_y², so that q / m_z² is the slope metric
// tan²θ_m (cos²φ'/α_x² + sin²φ'/α_y²) (θ_m from n, φ' the azimuth in the lobe frame):
//   Blinn-Phong (Blinn 1977) D = (e+2)/(2π) m_z^e                    (e >= 0, isotropic)
//   Beckmann (anisotropic)   D = exp(-q / m_z²) / (π α_x α_y m_z⁴)   D(n) = 1/(π α_x α_y)
//   GGX / Trowbridge-Reitz   D = 1 / (π α_x α_y (q + m_z²)²)          D(n) = 1/(π α_x α_y)
//   Ward (1992, eq. 5a)      D = K exp(-q / m_z²)
// Ward's specular lobe is ρ_s exp(-tan²θ_h(...)) / (4π α_x α_y sqrt(cos θ_i cos θ_o)); its only
// half-vector dependence is the Gaussian, the 1/sqrt(cos cos) factor being a shadowing-like term
// that the paper leaves out (§3.1: no masking or Fresnel term). So the Ward NDF is that Gaussian,
// with K making it integrate to 1 (K -> 1/(π α_x α_y), Ward's constant, for small α). K is exact:
//   K⁻¹ = ½ ∫_0^{2π} J(A(φ)) dφ,  A(φ) = cos²φ/α_x² + sin²φ/α_y²,  J(A) = ∫_0^∞ e^{-Au}/(1+u)² du
//       = 1 - A e^A E₁(A)   (u = tan²θ), evaluated by the continued fraction of E₁ and a
// 4096-point periodic trapezoid rule in the elliptic angle ψ (tan φ = (α_y/α_x) tan ψ).
// Ranges: α_x, α_y in [1e-4, 1] (Beckmann, GGX, Ward), e in [0, 2e8] (e = 2/α² - 2 spans the same
// widths), rotation any finite angle, weight finite and >= 0. All closed forms integrate to 1.
// A weighted sum of lobes is D = Σ w_i D_i / Σ w_i (normalised; Σ w_i > 0).
//
// [SECTION] Table (class Ndf)
// R x R cells over [-1, 1]² (R in [64, 512], default 128), cell (i, j) covering
// x in [-1 + i h, -1 + (i+1) h], y in [-1 + j h, -1 + (j+1) h], h = 2/R (j = 0 at y = -1; stored
// row-major, index j R + i). Per cell:
//   mass(i, j)  = ∫_{cell ∩ disk} D dx dy, normalised numerically so that Σ mass = 1 exactly;
//   area(i, j)  = |cell ∩ disk| (exact, closed form);
//   value(i, j) = mass / area: the mean of D over the cell's part of the disk (sr^-1); 0 outside.
// raw_integral() is Σ mass before the normalisation: 1 for an exact tabulation of an analytic source.
// Tabulation of analytic sources: per cell an adaptive cubature (4x4 Gauss-Legendre on the cell's
// part of the disk, splitting x where the circle crosses the cell's edges so the chord limits are
// smooth; a cell is split into four while the four children's sum differs from the parent's rule by
// more than 1e-7 relative, up to 6 levels). Sharp lobes are never missed: every (sub)cell that is
// wider than half a lobe width (in the lobe's own α-scaled frame) and not well separated from the
// lobe's centre is split further (up to 40 levels), so α = 1e-4 in a 1/32-wide cell is resolved and
// integrates to 1 (raw integral within 1e-10 for every lobe tested, α from 1e-4 to 1). In parallel
// over rows (TBB), deterministic. Cost on 2 cores (Release): R = 128 in 7-30 ms, R = 512 in
// 0.13-0.35 s; an extreme aspect ratio (α_y/α_x = 1e4) takes ~1.2 s, the thin strip being refined
// along its whole length.
// Images: piecewise constant (one value per pixel), box-filtered exactly: mass = Σ_p v_p |p ∩ cell ∩ disk|.
// Normals (§7, "an NDF for an existing bump map"): a histogram, mass = count / N.
// An NDF with no positive mass, or a non-finite one, is an InputError.
//
// [SECTION] Evaluation
// eval(xy): bilinear interpolation of value() between cell centres, over the cells that intersect
// the disk only (weights renormalised), so it follows D up to the rim; 0 outside the disk (beyond
// float rounding: |xy|² <= 1 + 1e-6 counts as on the rim). Its relative error is second order,
// up to (h |∇ ln D|)² / 6: about 1% in a lobe's core, a few % far out in a Gaussian tail at R = 128.
// eval(m): eval at (m_x, m_y) of m normalised; 0 for m_z < 0 (and for a zero or NaN m).
#include "core/math.h"
#include <string>
#include <string_view>
#include <vector>

namespace mesolab::bumpsynth {

enum class LobeKind { blinn_phong, beckmann, ggx, ward };

// One analytic NDF lobe. Built by the factories, which validate the parameters (InputError naming
// bumpsynth.exponent / alpha_x / alpha_y / rotation / weight).
class Lobe {
public:
    static Lobe blinn_phong(float exponent, float weight = 1.f);
    static Lobe beckmann(float alpha_x, float alpha_y, float rotation_deg = 0.f, float weight = 1.f);
    static Lobe ggx(float alpha_x, float alpha_y, float rotation_deg = 0.f, float weight = 1.f);
    static Lobe ward(float alpha_x, float alpha_y, float rotation_deg = 0.f, float weight = 1.f);
    // Beckmann, GGX or Ward by kind (blinn_phong: std::logic_error; it takes an exponent).
    static Lobe anisotropic(LobeKind kind, float alpha_x, float alpha_y, float rotation_deg = 0.f, float weight = 1.f);

    LobeKind kind() const { return kind_; }
    float exponent() const { return exponent_; }      // Blinn-Phong only
    float alpha_x() const { return alpha_x_; }        // Beckmann, GGX, Ward (Phong: the equivalent width)
    float alpha_y() const { return alpha_y_; }
    float rotation_deg() const { return rotation_deg_; }
    float weight() const { return weight_; }
    double ward_constant() const { return ward_k_; }  // K (sr^-1), Ward only

    // Closed form D(m) (sr^-1) for a direction m (normalised here); 0 for m_z < 0.
    double D(vec3 m) const;
    // The same at the projected point (x, y) of the unit disk (m_z = sqrt(1 - x² - y²)); 0 outside.
    double D_xy(double x, double y) const;

private:
    LobeKind kind_ = LobeKind::beckmann;
    float exponent_ = 0.f, alpha_x_ = 1.f, alpha_y_ = 1.f, rotation_deg_ = 0.f, weight_ = 1.f;
    double cos_ = 1.0, sin_ = 0.0, ward_k_ = 0.0;
};

// The names of the kinds in parameters and lobe lists: phong, beckmann, ggx, ward.
const char* lobe_name(LobeKind kind);
bool lobe_kind(std::string_view name, LobeKind& kind);  // false for an unknown name

// Closed form of a weighted sum, Σ w_i D_i(m) / Σ w_i (InputError if empty or Σ w_i = 0).
double D(const std::vector<Lobe>& lobes, vec3 m);

// [SECTION] Lists of lobes as text (bumpsynth.lobes)
//   sum  := term ('+' term)*          term := [w '*'] lobe | lobe ['*' w]
//   lobe := phong(e) | K(α) | K(α_x, α_y) | K(α_x, α_y, rotation°)     K = beckmann | ggx | ward
// e.g. "beckmann(0.3) + 0.5 * ggx(0.05, 0.5, 45)"; any number of lobes, weights default to 1 and are
// normalised by their sum. InputError naming the character position and the lobe for bad syntax or
// values ("lobe 2 (ggx): alpha_y ... must be in [1e-4, 1]").
std::vector<Lobe> parse_lobes(std::string_view text);
// "" when `text` parses, else what parse_lobes would say (the parameter's syntax check).
std::string lobes_syntax_error(const std::string& text);
// The canonical text of a list (round trip: parse_lobes(format_lobes(l)) equals l within 6 digits).
std::string format_lobes(const std::vector<Lobe>& lobes);
std::string format_lobe(const Lobe& lobe);  // one term, with its weight when it is not 1

// The exact Ward constant K(α_x, α_y) above (any α_x, α_y > 0).
double ward_constant(double alpha_x, double alpha_y);

class Ndf {
public:
    static constexpr int kDefaultResolution = 128;
    static constexpr int kMinResolution = 64, kMaxResolution = 512;

    // Analytic sources (InputError for a bad resolution, bumpsynth.resolution, or bad lobes).
    static Ndf from_lobe(const Lobe& lobe, int resolution = kDefaultResolution);
    static Ndf from_lobes(const std::vector<Lobe>& lobes, int resolution = kDefaultResolution);
    // An image of width x height floats (row-major, row 0 at the top = y +1, column 0 at x = -1)
    // over [-1, 1]², proportional to D (any positive scale), piecewise constant per pixel; pixels
    // outside the disk are ignored. InputError (bumpsynth.ndf_image) for a size mismatch, negative or
    // non-finite pixels, or no positive mass inside the disk.
    static Ndf from_image(const std::vector<float>& pixels, int width, int height,
                          int resolution = kDefaultResolution);
    // Histogram of microfacet normals (§7). Each is normalised; InputError (bumpsynth.normals) for
    // an empty list, a non-finite or zero vector, or one pointing below the surface (m_z < -1e-6).
    static Ndf from_normals(const std::vector<vec3>& normals, int resolution = kDefaultResolution);

    int resolution() const { return R_; }
    float cell_size() const { return 2.f / float(R_); }
    vec2 cell_centre(int i, int j) const;
    float value(int i, int j) const { return value_[idx(i, j)]; }
    double mass(int i, int j) const { return mass_[idx(i, j)]; }
    double cell_area(int i, int j) const { return area_[idx(i, j)]; }
    const std::vector<float>& values() const { return value_; }
    const std::vector<double>& masses() const { return mass_; }
    double integral() const;                           // Σ value · area (= 1 up to rounding)
    double raw_integral() const { return raw_integral_; }

    float eval(vec2 xy) const;
    float eval(vec3 m) const;

private:
    friend struct NdfBuilder;
    size_t idx(int i, int j) const { return size_t(j) * size_t(R_) + size_t(i); }
    int R_ = 0;
    double raw_integral_ = 0.0;
    std::vector<double> mass_, area_;
    std::vector<float> value_;
};

// Area of the intersection of the rectangle [x0, x1] x [y0, y1] with the unit disk (exact).
double disk_rect_area(double x0, double x1, double y0, double y1);
}  // namespace mesolab::bumpsynth
