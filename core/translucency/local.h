#pragma once
// [SECTION] The local response of Lensch et al. 2002, §5.3: a K x K texel-to-texel kernel per texel.
// Near where light enters, R_d is large and sharp, so it is resolved on the atlas's texels
// (piecewise constant basis, dual basis 1/area): the radiosity at an inner texel t is
//   B_local(t) = Σ_{t' in the K x K block around t} w(t, t') E(t'),
//   w(t, t')   = R_d(max(|x_t − x_t'|, ρ_t')) A_t'          for t' ≠ t (A_t': the texel's area, mm²)
//   w(t, t)    = ∫_{|r| < ρ_t} R_d 2πr dr, ρ_t = sqrt(A_t / π) (the texel as a disk of its own area,
//                closed form: Dipole::reflectance_within), since R_d(0) A_t would misjudge the
//                peak when a texel is wider than the source depth z_r.
// For the same reason no pair samples R_d nearer than the source's disk radius ρ_t': texels of one
// grid are at least a texel apart, but where two chunks' grids meet at an edge (the reference,
// reference.h, pairs every two inner texels) their centres can lie a fraction of a texel apart in
// 3D, and on texels wider than the diffusion length R_d there is its peak times a whole texel's
// area (a regular octahedron at 1,000 mm per unit in a 192² atlas, texels of 22 mm, skin1: the
// reference's Σ B A / Σ E A 1.18–1.78 times the dipole's sum over the surface, surface.h; with
// the radius, 0.99–1.00).
// The atlas's borders make every t' of the block a texel of t's chunk that samples the surface
// (unfolded beyond the chunk's edge), so kernels reach across chunk borders.
// Kernels are stored for inner texels only: K² weights per channel per inner texel (rows padded
// for SIMD, see LocalKernels::w).
#include "core/math.h"
#include "core/translucency/atlas.h"
#include "core/translucency/dipole.h"

#include <array>
#include <cstdint>
#include <vector>

namespace mesolab::translucency {

struct LocalKernels {
    int K = 0;
    int size = 0;                            // the atlas side
    int row = 0;                             // floats per kernel row: its K taps' (r, g, b), zero-padded to a multiple of 12
    std::vector<int32_t> texel;              // inner texels, in atlas order
    std::vector<int32_t> slot;               // per atlas texel: its index in `texel`, or -1
    // Per inner texel, K rows (dy) of `row` floats: the weights of the taps dx = −h..h, RGB
    // interleaved as the irradiance map's texels are, so that a kernel row and the K texels it
    // reads line up for four-wide SIMD (12 floats = 4 texels = three SIMD registers).
    std::vector<float> w;

    size_t bytes() const { return texel.size() * 4 + slot.size() * 4 + w.size() * 4; }
    static int row_floats(int K) { return (3 * K + 11) / 12 * 12; }
    // Index in `w` of the red weight of the neighbour at (dx, dy) (in [-(K-1)/2, (K-1)/2]) for kernel `k`.
    size_t at(size_t k, int dx, int dy) const {
        const int h = (K - 1) / 2;
        return (k * size_t(K) + size_t(dy + h)) * size_t(row) + 3 * size_t(dx + h);
    }
    float weight(size_t k, int dx, int dy, int c) const { return w[at(k, dx, dy) + size_t(c)]; }
};

// ρ² = A / π (mm²) of a texel of area A (mm²): the nearest distance at which a pair samples R_d.
inline float texel_disk_r2(float area_mm2) { return area_mm2 / 3.14159265358979323846f; }

// Surface positions of every non-empty atlas texel, in mm (0 for empty texels).
std::vector<vec3> texel_positions_mm(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index,
                                     double mm_per_unit);

// InputError naming translucency.kernel for an even K, K < 3 or K > 15, or a K wider than the
// atlas's border allows (border >= (K - 1)/2 + 1).
LocalKernels build_local_kernels(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Profile& dipole,
                                 double mm_per_unit, int K);

// B_local per atlas texel (0 outside inner texels) from per-texel irradiance E (every texel,
// border texels included). Rows in parallel.
std::vector<vec3> convolve_local(const LocalKernels& k, const std::vector<vec3>& E);
}  // namespace mesolab::translucency
