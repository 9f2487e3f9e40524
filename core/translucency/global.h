#pragma once
// [SECTION] The global response of Lensch et al. 2002, §5.2: vertex-to-vertex throughput factors.
// Radiosity far from where light enters is smooth, so it is represented in the hat basis φ_i of
// the mesh's vertices (φ_i = 1 at vertex i, 0 at the others, linear on each triangle):
//   irradiance   E(x) ≈ Σ_j E_j φ_j(x),  E_j = ∫ E(x) φ̃_j(x) dA  with the dual basis
//                φ̃_j(x) = (3 / A_j) (4 λ_j(x) − 1) on the triangles around j (λ_j: x's
//                barycentric coordinate of j, A_j: the area of those triangles), which
//                reproduces constant irradiance exactly (project_to_vertices)
//   factors      B_i = Σ_j F_ij E_j,  F_ij = R_d(|x_i − x_j|) ∫ φ_j dA = R_d(|x_i − x_j|) A_j / 3
//                (Eq. 7 with R_d evaluated once per pair of vertices), kept where the largest
//                channel is at least `threshold` (the factor count of Table 1)
//   radiosity    B(x) = Σ_i B_i φ_i(x): linear interpolation of the vertex values
// With blending (§5.4) the diagonal F_ii is zero: the local kernels carry the short range.
//
// Units: positions in scene units, times mm_per_unit gives mm; R_d in mm⁻², areas in mm²; F
// is dimensionless (radiosity per unit irradiance).
//
// Storage: one compressed-row structure (row starts, column indices) shared by the three colour
// channels, and one float array of values per channel: 4 + 3 × 4 bytes per factor. Each channel
// is an Eigen::SparseMatrix<float, RowMajor> through Eigen::Map (channel()); the product runs
// rows in parallel (TBB).
#include "core/math.h"
#include "core/translucency/dipole.h"

#include <Eigen/SparseCore>

#include <array>
#include <cstdint>
#include <vector>

namespace mesolab::translucency {

struct VertexFactors {
    int n = 0;                               // vertices
    std::vector<int> outer;                  // n + 1 row starts
    std::vector<int> inner;                  // column of each factor
    std::array<std::vector<float>, 3> value; // per channel, parallel to `inner`
    std::vector<float> vertex_area;          // A_i, mm² (sum of the adjacent triangles' areas)
    double threshold = 0.0;
    bool zero_diagonal = false;

    size_t count() const { return inner.size(); }
    size_t bytes() const { return outer.size() * sizeof(int) + inner.size() * (sizeof(int) + 3 * sizeof(float)); }
    // Channel c as an Eigen sparse matrix (a view: the factors must outlive it).
    Eigen::Map<const Eigen::SparseMatrix<float, Eigen::RowMajor>> channel(int c) const;
    // B = F E, rows in parallel.
    std::vector<vec3> multiply(const std::vector<vec3>& E) const;
};

struct FactorParams {
    double mm_per_unit = 1.0;   // translucency.mm_per_unit
    float threshold = 0.f;      // translucency.threshold: smallest factor kept (largest channel)
    bool zero_diagonal = false; // blending on
};

// Builds the factors for a mesh (positions, 3 indices per triangle) and a dipole. Rows in
// parallel; R_d from an RdTable over the mesh's diameter. InputError naming
// translucency.mm_per_unit / translucency.threshold for values out of range.
VertexFactors build_vertex_factors(const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Dipole& dipole,
                                   const FactorParams& p);

// E_j = ∫ E φ̃_j dA from per-texel irradiance over an atlas of the same mesh (inner texels:
// their triangle's barycentrics and surface area), with vertex areas A_j in mm² and texel areas
// scaled by mm_per_unit². Constant irradiance gives E_j = E up to the texel quadrature.
struct Atlas;
std::vector<vec3> project_to_vertices(const Atlas& atlas, const std::vector<uint32_t>& index, const std::vector<vec3>& texel_irradiance,
                                      const std::vector<float>& vertex_area, double mm_per_unit);

// A_j of every vertex in mm² (the sum of the areas of the triangles that share it).
std::vector<float> vertex_areas(const std::vector<vec3>& position, const std::vector<uint32_t>& index, double mm_per_unit);
}  // namespace mesolab::translucency
