#pragma once
// [SECTION] A diffusion profile: R_d(r), the radiosity leaving a planar surface at distance r from
// where unit power entered (mm⁻²), per colour channel. The paper's method uses the dipole (Jensen
// et al. 2001, dipole.h); lensch-burley Christensen and Burley's normalised profile (burley.h).
// Everything the atlas and vertex pipeline reads of a profile goes through this interface.
#include "core/math.h"

#include <memory>

namespace mesolab::translucency {

using dvec3 = glm::dvec3;

class Profile {
public:
    virtual ~Profile() = default;
    virtual std::unique_ptr<Profile> clone() const = 0;
    // R_d(r) per channel, mm⁻², r in mm (|r|).
    virtual double Rd(double r, int channel) const = 0;
    dvec3 Rd(double r) const { return {Rd(r, 0), Rd(r, 1), Rd(r, 2)}; }
    // R_d, R_d' and R_d'' at r (closed form).
    virtual void derivatives(double r, int channel, double& f, double& f1, double& f2) const = 0;
    // T(R) = ∫_R^∞ R_d(r) r dr per channel (closed form).
    virtual dvec3 tail(double R) const = 0;
    // ∫_0^R 2πr R_d dr per channel, and its limit R_total.
    virtual dvec3 reflectance_within(double R) const = 0;
    virtual dvec3 total_reflectance() const = 0;
    // (R_d'' + R_d'/r) / R_d per channel (0 where R_d is 0).
    virtual dvec3 laplacian_ratio(double r) const = 0;
    // The fastest exponential fall-off of R_d, per channel (mm⁻¹): the dipole's σ_tr, Burley's s/ℓ.
    // A cluster of the surface is expanded about its centroid only where it spans a few of these.
    virtual dvec3 decay() const = 0;
    // The shortest length of the profile (mm): below it a surface element is split (global.h).
    virtual double length_scale() const = 0;
    // A radius to start the search for radius_holding from (mm).
    virtual double reach_hint() const = 0;

    // ∫ R_d over a square of side a centred where the light enters (mm): the disk of radius a/2
    // in closed form plus the four corners by 16-point Gauss–Legendre (dipole.h).
    dvec3 reflectance_within_square(double a) const;
    // The radius within which R_d holds a fraction f of R_total in every channel (mm).
    double radius_holding(double f) const;
};
}  // namespace mesolab::translucency
