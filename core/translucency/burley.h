#pragma once
// [SECTION] Christensen and Burley's normalised diffusion profile (2015), for translucency.method =
// lensch-burley: the paper's atlas and vertex pipeline with this profile in place of the dipole.
// Per Christensen and Burley, "Approximate Reflectance Profiles for Efficient Subsurface
// Scattering", Pixar Technical Memo 15-04, 2015, eq. 2-3 and §4.1 (the search-light configuration):
//   R(r) = A s (e^(-s r / ℓ) + e^(-s r / (3ℓ))) / (8π ℓ r)                        (mm⁻²)
//   s = 1.85 - A + 7 |A - 0.8|³                                                     (their eq. 5)
// with A the total diffuse reflectance (the surface albedo) and ℓ the mean free path. mesolab
// takes A = the dipole's R_total of the same medium (Jensen et al. 2001, Eq. 8 integrated: the
// same albedo as the paper's method, so the two differ in shape only) and ℓ = 1/σ't, the reduced
// mean free path, per colour channel. With d = ℓ/s:
//   ∫_0^∞ 2πr R dr = A                                                               (normalised)
//   T(R) = ∫_R^∞ R(r) r dr = A (e^(-R/d) + 3 e^(-R/(3d))) / (8π)
//   ∫_0^R 2πr R dr = A - 2π T(R)
// R is infinite at r = 0, integrably (r R → A / (4π d)); a table or a point look-up at r = 0 must
// use the mean over a small disk instead ((A - 2π T(ε)) / (π ε²)).
#include "core/translucency/dipole.h"

#include <algorithm>

namespace mesolab::translucency {

class BurleyProfile final : public Profile {
public:
    explicit BurleyProfile(const Medium& m);
    std::unique_ptr<Profile> clone() const override { return std::make_unique<BurleyProfile>(*this); }
    // R(r) per channel, mm⁻², r in mm (|r|; r = 0 gives +inf).
    using Profile::Rd;
    double Rd(double r, int channel) const override;
    // R, R' and R'' at r > 0 (closed form).
    void derivatives(double r, int channel, double& f, double& f1, double& f2) const override;
    // (R'' + R'/r) / R at r > 0: the Laplacian in the plane over R.
    dvec3 laplacian_ratio(double r) const override;
    // ∫_R^∞ R(r) r dr, ∫_0^R 2πr R dr and the total (A) per channel.
    dvec3 tail(double R) const override;
    dvec3 reflectance_within(double R) const override;
    dvec3 total_reflectance() const override { return A_; }
    dvec3 decay() const override { return 1.0 / d_; }
    double length_scale() const override { return std::max(1e-12, std::min({d_.x, d_.y, d_.z})); }
    double reach_hint() const override { return 3.0 * std::max({d_.x, d_.y, d_.z}); }

    const dvec3& albedo() const { return A_; }
    const dvec3& s() const { return s_; }
    const dvec3& d() const { return d_; }  // ℓ / s, mm
    // Christensen and Burley's search-light scaling factor for albedo A (their eq. 5).
    static double scaling(double A);

private:
    dvec3 A_{0.0}, s_{0.0}, d_{0.0};
};
}  // namespace mesolab::translucency
