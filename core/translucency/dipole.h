#pragma once
// [SECTION] The diffuse dipole of Jensen et al. 2001, as Lensch et al. 2002 use it (their Fig. 2, Eq. 2-3).
// Multiple scattering in a homogeneous, highly scattering medium under a planar boundary: the
// radiosity leaving the surface at distance r from where unit power entered is R_d(r) (mm^-2), and
// the fraction of the entering power that leaves at all is the total diffuse reflectance
// R_total = ∫ 2πr R_d(r) dr. Single scattering is ignored, as in both papers.
//
// Per colour channel, with the reduced scattering σ's and the absorption σa (mm^-1) and the
// relative index of refraction η:
//   σ't = σ's + σa,  α' = σ's / σ't,  σtr = sqrt(3 σa σ't)            (effective transport, mm^-1)
//   F_dr = -1.440/η² + 0.710/η + 0.668 + 0.0636 η                      (diffuse Fresnel reflectance fit)
//   A = (1 + F_dr) / (1 - F_dr)
//   z_r = 1/σ't,  z_v = z_r (1 + 4A/3)                                  (real and virtual source depths, mm)
//   d_r = sqrt(r² + z_r²),  d_v = sqrt(r² + z_v²)
//   R_d(r) = α'/(4π) [ z_r (σtr d_r + 1) e^(-σtr d_r) / d_r³ + z_v (σtr d_v + 1) e^(-σtr d_v) / d_v³ ]
//   R_total = α'/2 (1 + e^(-4/3 A sqrt(3(1-α')))) e^(-sqrt(3(1-α')))     (Jensen et al. 2001, Eq. 8 integrated)
// R_d(0) is finite (z_r > 0); σa = 0 gives σtr = 0 and R_total = 1 (spectralon).
//
// Fresnel transmittance (Schlick 1994, as the paper): T(cos θ) = 1 - R0 - (1 - R0)(1 - cos θ)^5
// with R0 = ((η - 1)/(η + 1))². At η = 1 there is no interface: T = 1 at every angle.
#include "core/math.h"
#include "core/translucency/profile.h"

#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace mesolab::translucency {

// A homogeneous medium, RGB. Lengths in millimetres.
struct Medium {
    dvec3 sigma_s{0.0};  // reduced scattering coefficient σ's, mm^-1
    dvec3 sigma_a{0.0};  // absorption coefficient σa, mm^-1
    double eta = 1.3;    // relative index of refraction
};

// One of Jensen et al. 2001's measured materials (Table in ../shared/papers/README.md), with the
// total diffuse reflectance that paper lists for it (R_d, 3 decimals).
struct MeasuredMaterial {
    std::string name;
    Medium medium;
    dvec3 listed_reflectance;
};

// apple, chicken1, chicken2, cream, ketchup, marble, potato, skimmilk, skin1, skin2, spectralon,
// wholemilk; η = 1.3, marble 1.5.
const std::vector<MeasuredMaterial>& measured_materials();
// InputError naming `key` and the known names (with a suggestion) for an unknown name.
const MeasuredMaterial& measured_material(const std::string& name, const std::string& key = "translucency.material");

// Checks a medium: σ's, σa ≥ 0 and finite, σ's + σa > 0 per channel, η in [1, 3]. InputError
// naming the key (`group`.sigma_s, .sigma_a, .eta) otherwise.
void validate(const Medium& m, const std::string& group = "translucency");

// Diffuse Fresnel reflectance F_dr(η) (Egan and Hilgeman's fit, as Jensen et al. 2001).
double fresnel_diffuse_reflectance(double eta);
// Schlick's Fresnel transmittance into (or out of) a medium of relative index η at cos θ.
double fresnel_transmittance(double cos_theta, double eta);
// Its cosine-weighted mean over the hemisphere, 2 ∫ T(μ) μ dμ = (1 − R0) 20/21 (1 at η = 1): the
// fraction of a uniform environment's irradiance that enters the medium, and of the light leaving
// it that the display's T(cos θo) / π sends out. (1 − F_dr is the same from inside the medium, where
// light meets the boundary from the denser side: 0.40 for η = 1.5 against 0.91 from outside.)
double diffuse_transmittance(double eta);

// The dipole for one medium, with the per-channel constants computed once.
class Dipole final : public Profile {
public:
    explicit Dipole(const Medium& m);
    std::unique_ptr<Profile> clone() const override { return std::make_unique<Dipole>(*this); }

    // R_d(r) per channel, mm^-2, r in mm (r < 0 is taken as |r|).
    using Profile::Rd;
    double Rd(double r, int channel) const override;
    // R_d and its first two derivatives in r: per source at depth z, T(D) = z (σ D + 1) e^(−σD) / D³
    // at D = √(r² + z²), T'(D) = −z e^(−σD) (σ²D² + 3σD + 3) / D⁴,
    // T''(D) = z e^(−σD) (σ³D³ + 5σ²D² + 12σD + 12) / D⁵, dT/dr = T'(D) r / D,
    // d²T/dr² = T''(D) r² / D² + T'(D) z² / D³; times α'/4π.
    void derivatives(double r, int channel, double& f, double& f1, double& f2) const override;
    // T(R) = α'/4π Σ_{z = z_r, z_v} z e^(−σ_tr D) / D, D = √(R² + z²).
    dvec3 tail(double R) const override;
    dvec3 decay() const override { return sigma_tr_; }
    double length_scale() const override { return std::max(1e-12, std::min({zv_.x, zv_.y, zv_.z})); }
    double reach_hint() const override { return std::max({zv_.x, zv_.y, zv_.z}); }
    // ∇²R_d / R_d at r per channel, mm⁻²: the Laplacian in the surface's plane,
    // (R_d'' + R_d' / r) / R_d, by central differences (r → 0: 2 R_d'' / R_d). Positive where
    // R_d is convex across the plane (beyond about the source depth z_r); σ_tr² far out. 0 where
    // R_d is 0.
    dvec3 laplacian_ratio(double r) const override;
    // ∫ 2πr R_d(r) dr over [0, R] per channel (closed form), and R_total (R = ∞).
    dvec3 reflectance_within(double R) const override;
    dvec3 total_reflectance() const override;
    // reflectance_within_square and radius_holding: Profile's (profile.h).

    const Medium& medium() const { return m_; }
    const dvec3& sigma_tr() const { return sigma_tr_; }
    const dvec3& alpha_prime() const { return alpha_; }
    const dvec3& z_r() const { return zr_; }
    const dvec3& z_v() const { return zv_; }
    double A() const { return A_; }

private:
    Medium m_;
    dvec3 sigma_tr_{0.0}, alpha_{0.0}, zr_{0.0}, zv_{0.0};
    double A_ = 1.0;
};
// R_d tabulated for fast look-ups over many pairs of points (the vertex-to-vertex factors, the
// texel kernels): `n` samples uniform in sqrt(r / r_max) over [0, r_max] mm, linear between them,
// 0 beyond r_max. Relative error against Dipole::Rd below 1e-4 for n = 8192 and r_max up to
// 50 mean free paths of every channel (tests/translucency/dipole_test.cpp).
class RdTable {
public:
    RdTable(const Profile& d, double r_max, int n = 8192);
    // R_d at squared distance r2 (mm²).
    vec3 at_r2(float r2) const {
        const float q = std::sqrt(std::sqrt(r2) * inv_r_max_) * float(n_ - 1);
        if (!(q < float(n_ - 1))) return q == q && r2 <= r_max2_ ? table_[size_t(n_ - 1)] : vec3(0.f);
        const int i = int(q);
        const float t = q - float(i);
        return table_[size_t(i)] * (1.f - t) + table_[size_t(i) + 1] * t;
    }
    double r_max() const { return r_max_; }
    // The samples (for the GPU's copy of the table): sample i at r = r_max (i / (n - 1))².
    const std::vector<vec3>& samples() const { return table_; }

private:
    std::vector<vec3> table_;
    double r_max_ = 0.0;
    float inv_r_max_ = 0.f, r_max2_ = 0.f;
    int n_ = 0;
};
}  // namespace mesolab::translucency
