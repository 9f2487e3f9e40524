#pragma once
// [SECTION] The global response of Lensch et al. 2002, §5.2: vertex-to-vertex throughput factors.
// Radiosity far from where light enters is smooth, so it is represented in the hat basis φ_i of
// the mesh's vertices (φ_i = 1 at vertex i, 0 at the others, linear on each triangle):
//   irradiance   E_j = (3 / A_j) ∫ E(x) φ_j(x) dA (project_to_vertices): each texel's power split
//                over its triangle's corners by its barycentrics, A_j the area of the triangles
//                around j. This is the L2 projection with a lumped (diagonal) mass matrix: it
//                keeps the power exactly and never goes negative. The paper's dual basis
//                φ̃_j = (3 / A_j)(4 λ_j − 1) is exact for smooth irradiance but splits a sharp
//                edge (a shadow, a spot) into negative and positive lobes, which an R_d that falls
//                by 4x per vertex spacing (skin's blue) carries far: the energy of a spot on a
//                plane then drifts by up to 9% with where it falls on a triangle.
//   factors      B_i = Σ_j F_ij E_j,  F_ij = R̂_ij A_j / 3 (Eq. 7), kept where the largest
//                channel is at least `threshold` (the factor count of Table 1; see below)
//   radiosity    B(x) = Σ_i B_i φ_i(x): linear interpolation of the vertex values
// Interpolation correction (`FactorParams::interpolation_correction`). Both splits interpolate
// linearly across a triangle, which overestimates a convex R_d: over a triangle of edges e_k the
// linear interpolant of f exceeds f by x = (Σ e_k² / 48) ∇²f / f on average (relative), once on
// the source's side and once on the receiver's. For an exponential e^(−k s) sampled every h the
// exact excess of a step is ρ = (a / 2) coth(a / 2), a = k h, whose expansion 1 + a² / 12 matches x;
// so each side divides by ρ with a² / 12 = x:
//   R̂_ij = R_d(r_ij) / (ρ(q_i L) ρ(q_j L)),  L = ∇²R_d / R_d at r_ij,  1 / ρ(x) = tanh(b) / b,
//   b = sqrt(3x),  q_i = area-weighted mean of Σ e_k² / 48 over the triangles around i (mm²).
// It only ever shrinks R_d (x < 0 counts as 0). Pairs that share an edge and the diagonal keep
// R_d: the zero diagonal of blending sits inside both their stencils, so interpolation there
// pulls towards 0 rather than smoothing R_d. On a plane of skin1 at the paper's vertex spacing
// (0.94 mm), one lit texel's blue power at 2–6 mm is 1.56–2.00× R_d's with the paper's factors
// and 1.07–1.48× with R̂; the bunny's radiosity RMSE at 8,000 vertices falls from 0.079 to 0.063
// (tests/translucency/blend_test.cpp, the vertex sweep on core/translucency/README.md).
// With blending (§5.4) the diagonal F_ii is zero: the local kernels carry the short range.
//
// Hat-pair means (without blending). The diagonal and the pairs that share an edge have
// overlapping hats, and R_d(r_ij) stands for them only while R_d is flat over a triangle. In
// general the factor that keeps the power the lumped projection puts in (E_j A_j / 3) and the
// interpolation takes out (Σ_i B_i A_i / 3) is the Galerkin one,
//   F_ij = (3 / A_i) ∫∫ φ_i(x) φ_j(y) R_d(|x − y|) dA_x dA_y = R̄_ij A_j / 3,
//   R̄_ij = 9 / (A_i A_j) ∫∫ φ_i φ_j R_d   (the mean of R_d over both hats, mm⁻²; symmetric),
// whose columns hold R_total on a surface that is flat within R_d's reach:
// Σ_i F_ij A_i / 3 = (3 / A_j) ∫ φ_j(y) ∫ R_d(|x − y|) dA_x dA_y = R_total A_j / 3. Sampling
// R_d(0) A_i / 3 instead, on triangles far larger than the diffusion length, gives hundreds of
// R_total (a box of 300 mm faces in skin1: Σ radiosity / Σ irradiance 1719 for 0.43). Computed
// by splitting every triangle of the two hats into n² equal sub-triangles, n = ⌈longest edge /
// min z_v⌉ ≤ 8, sampled at their centroids (exact for the linear hats), a sub-triangle paired
// with itself as a disk of its area (Dipole::reflectance_within, as a texel in local.h). Far
// below z_v (the bunny at the paper's densities: n = 1) that is R_d between the triangles'
// centroids; far above the diffusion length the disk holds R_total and F_ii → R_total / 2
// (∫ φ_i² = A_i / 6), F_ij → R_total (3 / A_i)(A_T + A_T') / 12 (the consistent mass matrix),
// within the centroid rule's 1 / (3 n²) of ∫ φ_i². With blending the diagonal is zero and
// the edges keep R_d(r_ij): the kernels and the direct part carry what lands near the source,
// and the blending fit closes each texel's energy (blend.h). But an edge never carries more than
// twice its hat-pair mean, R_ij = min(R_d(r_ij), 2 R̄_ij), R̄ here with each triangle sampled once
// (its centroid; a triangle with itself as a disk of its area): a short edge between large
// triangles (3.8 mm against 60-110 mm on a convex hull at 50 mm per unit) sampled R_d's peak
// and spread it over both hats, a factor of several R_total that the fit cannot take back (it
// never makes c negative): ketchup's red came out 1.75 of the reference, 1.00 with the cap. Where
// R_d is nearly flat over the hats, as at the paper's densities, R̄ is close to R_d(r_ij) and
// the cap does not apply (the plane's energy in tests/translucency/blend_test.cpp moved by 1e-4;
// R̂ on the edges instead lost up to 9% of it, min(R_d, R̄) 1.4%).
//
// Units: positions in scene units, times mm_per_unit gives mm; R_d in mm⁻², areas in mm²; F
// is dimensionless (radiosity per unit irradiance).
//
// Storage: R̂_ij, like R_d(|x_i − x_j|), is symmetric, so only the upper triangle (j ≥ i) is
// kept, row by row, 8 bytes per pair: the three channels as IEEE half floats relative to a
// per-channel scale (R_d(0) / 2^15, so that every value is a normal half down to 2e-9 R_d(0);
// rounding ≤ 4.9e-4 relative, far below what the threshold drops), and the column's low 16
// bits. Meshes above 65,536 vertices add 2 bytes per pair for the high bits. The product scales
// the irradiance once per vertex, E'_j = E_j A_j / 3 × scale, and runs rows in parallel, each
// pair adding to both of its rows (per-thread sums): a quarter of the bytes of one float RGB +
// int column per factor, which is what the product's time is made of. upper() decodes a
// channel as an Eigen sparse matrix (for checks and tools; the product does not use it).
//
// count() is the number of vertex-to-vertex factors as Table 1 counts them (F_ij and F_ji
// separately); a pair is kept when R_d (A_i + A_j) / 6, the mean of F_ij and F_ji, reaches the
// threshold in its largest channel.
#include "core/math.h"
#include "core/translucency/dipole.h"

#include <Eigen/SparseCore>

#include <array>
#include <cstdint>
#include <vector>

namespace mesolab::translucency {

struct VertexFactors {
    int n = 0;                      // vertices
    std::vector<int> outer;         // n + 1 row starts into `pair`
    std::vector<uint64_t> pair;     // bits 0–47: R_d / scale as 3 halves (R, G, B); 48–63: column & 0xffff
    std::vector<uint16_t> col_hi;   // column >> 16 per pair, only when n > 65536
    vec3 scale{1.f};                // mm⁻² per unit of the stored halves, per channel
    std::vector<float> vertex_area; // A_i, mm² (sum of the adjacent triangles' areas)
    size_t diagonal = 0;            // pairs with j = i
    double threshold = 0.0;
    bool zero_diagonal = false;

    size_t pairs() const { return pair.size(); }
    size_t count() const { return 2 * pair.size() - diagonal; }
    size_t bytes() const { return outer.size() * sizeof(int) + pair.size() * sizeof(uint64_t) + col_hi.size() * sizeof(uint16_t); }
    int column(size_t k) const { return int(pair[k] >> 48) | (col_hi.empty() ? 0 : int(col_hi[k]) << 16); }
    vec3 rd(size_t k) const;              // R_d of pair k, mm⁻²
    vec3 factor(int i, int j) const;      // F_ij = R_d A_j / 3 (0 where the pair was dropped)
    vec3 weight(int j) const { return vertex_area[size_t(j)] / 3.f * scale; }  // E'_j = E_j × weight(j)
    // Channel c of R_d's upper triangle, decoded (F = upper.selfadjointView<Upper>() diag(A / 3)).
    Eigen::SparseMatrix<float, Eigen::RowMajor> upper(int c) const;
    // B = F E, rows in parallel; simd = false takes the portable path of CPUs without F16C.
    std::vector<vec3> multiply(const std::vector<vec3>& E, bool simd = true) const;
};

// Every factor as its own entry, rows complete (for a device without atomic float adds): row i
// holds F_ij's stored halves for every kept j, in the pair format above (the column replaced).
struct DirectedFactors {
    std::vector<int> outer;        // n + 1
    std::vector<uint64_t> entry;   // as VertexFactors::pair
    std::vector<uint16_t> col_hi;  // as VertexFactors::col_hi
};
DirectedFactors expand_directed(const VertexFactors& F);
// B = F E over the expanded rows (the CPU reference of the GPU's product).
std::vector<vec3> multiply_directed(const VertexFactors& F, const DirectedFactors& D, const std::vector<vec3>& E);

// IEEE 754 half-precision bits of a float, rounded to nearest even, and back.
uint16_t half_bits(float f);
float half_value(uint16_t h);

struct FactorParams {
    double mm_per_unit = 1.0;   // translucency.mm_per_unit
    float threshold = 0.f;      // translucency.threshold: smallest factor kept (largest channel)
    bool zero_diagonal = false; // blending on
    bool wide_columns = false;  // keep the columns' high 16 bits below 65,536 vertices too (tests)
    bool interpolation_correction = true;  // R̂, and without blending R̄ on overlapping hats, instead of R_d (above; off: the paper's factors, for tests)
};

// Builds the factors for a mesh (positions, 3 indices per triangle) and a dipole. Rows in
// parallel; R_d from an RdTable over the mesh's diameter. InputError naming
// translucency.mm_per_unit / translucency.threshold for values out of range.
VertexFactors build_vertex_factors(const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Profile& dipole,
                                   const FactorParams& p);

// E_j = (3 / A_j) ∫ E φ_j dA from per-texel irradiance over an atlas of the same mesh (inner
// texels: their triangle's barycentrics and surface area), with vertex areas A_j in mm² and texel
// areas scaled by mm_per_unit². Σ_j E_j A_j / 3 = Σ_t E_t A_t exactly; constant irradiance gives
// E_j = E up to the texel quadrature.
struct Atlas;
std::vector<vec3> project_to_vertices(const Atlas& atlas, const std::vector<uint32_t>& index, const std::vector<vec3>& texel_irradiance,
                                      const std::vector<float>& vertex_area, double mm_per_unit);

// A_j of every vertex in mm² (the sum of the areas of the triangles that share it).
std::vector<float> vertex_areas(const std::vector<vec3>& position, const std::vector<uint32_t>& index, double mm_per_unit);
}  // namespace mesolab::translucency
