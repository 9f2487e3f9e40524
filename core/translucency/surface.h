#pragma once
// [SECTION] The dipole over the object's own surface: R_S(y) = ∫_S R_d(|x − y|) dA_x.
// Lensch et al. 2002, Eq. 2 sums the dipole over the object's surface S, B(x) = ∫_S E(x') R_d(x, x') dA(x'),
// with R_d at the 3D distance |x − x'| (Eq. 3 and Jensen et al. 2001, Eq. 5–8; the brute-force
// reference, reference.h, does the same over the atlas's texels). Unit irradiance at a point y of
// the surface therefore leaves it, in all, as
//   R_S(y) = ∫_S R_d(|x − y|) dA_x        (dimensionless, per channel),
// which is R_total only on a plane (Jensen et al.'s Eq. 8 integrated). On a closed object it is
// not: where the surface folds within R_d's reach (an edge, a thin part) more of it lies close to
// y in 3D than along the surface, and R_S > R_total; where the object is not much larger than the
// diffusion length there is less surface than a plane's, and R_S < R_total. The blending's energy
// closure (blend.h) holds a source texel's power to R_S where it can top it up.
//
// Measured (the sphere and the fold: tests/translucency/surface_test.cpp): on a sphere of radius a every point sees the
// surface at chords s ∈ [0, 2a] with dA = 2π s ds, so R_S = ∫_0^{2a} 2π s R_d(s) ds, the dipole's
// power within the diameter (skin1: 0.49 / 0.79 / 0.95 R_total at a = 1 mm, 0.998 at 10 mm); 1 mm
// from a 90° fold, 1.11 / 1.11 / 1.07 R_total (skin1), 1.08 (marble); on a regular octahedron at 10
// mm per unit (skin1) 1.09 / 1.02 / 1.00 at a face's centre, 0.67 at a corner (its four faces
// span 240°, two thirds of a plane's angle).
//
// One triangle f, exactly (polar coordinates about the foot y' of y on f's plane, height h):
//   ∫_f R_d(|x − y|) dA = Σ_edges ± ∫ [T(|h|) − T(√(ρ(θ)² + h²))] dθ,
//   T(R) = ∫_R^∞ R_d(r) r dr = α' / 4π Σ_{z = z_r, z_v} z e^(−σ_tr D) / D,  D = √(R² + z²)
// (r dr = ρ dρ; T is closed form: 2π T(R) = R_total − Dipole::reflectance_within(R)), each edge
// (a, b) closing the sub-triangle (y', a, b), signed by its orientation. Along an edge at distance d
// from y', with τ measured from the foot of the perpendicular, ρ² = d² + τ² and dθ = d dτ / (d² +
// τ²): the T(|h|) part is T(|h|) times the angle the edge subtends (atan), exactly, so that the
// sub-triangles of a point beside f cancel without rounding; the rest, ∫ T(√(d² + τ² + h²)) d /
// (d² + τ²) dτ, by Gauss–Legendre panels (4 points) d / 2 wide at τ = 0 and as wide as τ beyond.
// Far from y, a node of a bounding-volume tree over the triangles (area A, centroid g, second
// moment M = ∫ (x − g)(x − g)ᵀ dA) is expanded to second order about g, r = y − g:
//   ∫ R_d(|x − y|) dA ≈ A R_d(r) + ½ [R_d''(r) r̂ᵀ M r̂ + R_d'(r) / r (tr M − r̂ᵀ M r̂)],
// accepted where its bounding radius a ≤ 0.4 r and σ_tr a ≤ 4 in every channel whose share
// R_d(r − a) A is above 1e-5 R_total; a triangle that fails while y lies beyond its bounding radius
// is split in four (at most three times), otherwise integrated exactly. One triangle against a
// 700² midpoint sum: within 1e-3 (the sum's own error at spectralon's peak; 2.5e-4 at 1,500²); the
// tree against every triangle integrated exactly, on 90° folds of 12,800 squares: within 2.3e-3.
// About 0.05 ms a point on the 8,000 triangles of the bunny at 4,000 vertices (one core of a
// 2-core AMD EPYC VM).
#include "core/math.h"
#include "core/translucency/dipole.h"

#include <array>
#include <memory>
#include <cstdint>
#include <vector>

namespace mesolab::translucency {

class SurfaceReflectance {
public:
    // The mesh's triangles in mm (positions × mm_per_unit); triangles without area are left out.
    SurfaceReflectance(const std::vector<vec3>& position, const std::vector<uint32_t>& index, double mm_per_unit, const Profile& profile);
    // R_S(y) per channel, y in mm (a point of the surface; anywhere within the mesh's bounds).
    dvec3 operator()(const vec3& y_mm) const;
    // ∫ R_d(|x − y|) dA over the f-th triangle kept (mm²·mm⁻²), by the polar sum above.
    dvec3 triangle(size_t f, const dvec3& y_mm) const;
    size_t triangles() const { return tri_.size(); }

private:
    struct Triangle {
        std::array<dvec3, 3> p;
        dvec3 normal{0.0}, centroid{0.0};
        double area = 0.0, radius = 0.0;
        glm::dmat3 moment{0.0};
    };
    struct Node {
        dvec3 centroid{0.0};
        glm::dmat3 moment{0.0};
        double area = 0.0, radius = 0.0;
        int left = -1, right = -1, tri = -1;  // children, or the triangle of a leaf
    };
    static Triangle make_triangle(const dvec3& a, const dvec3& b, const dvec3& c);
    int build(std::vector<int>& order, int begin, int end);
    dvec3 exact(const Triangle& t, const dvec3& y) const;
    dvec3 expansion(const dvec3& centroid, const glm::dmat3& moment, double area, const dvec3& y) const;
    bool expandable(double radius, double area, double r) const;
    dvec3 leaf(const Triangle& t, const dvec3& y, int depth) const;
    // T(R) = Q(∞) − Q(R) = α' / 4π Σ_{z = z_r, z_v} z e^(−σ_tr D) / D, D = √(R² + z²), and
    // (R_d, R_d', R_d''), tabulated like RdTable (uniform in √(r / r_max)).
    dvec3 tail(double r) const;
    dvec3 tail_exact(double r) const;
    void derivatives(double r, dvec3& f, dvec3& f1, dvec3& f2) const;

    std::vector<Triangle> tri_;
    std::vector<Node> node_;
    std::shared_ptr<const Profile> profile_;
    dvec3 sigma_tr_{0.0}, negligible_{0.0};
    double r_max_ = 1.0;
    int n_ = 0;
    std::vector<dvec3> tail_table_;
    std::vector<std::array<dvec3, 3>> d_table_;
};
}  // namespace mesolab::translucency
