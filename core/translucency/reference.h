#pragma once
// [SECTION] The reference radiosity: the dipole summed over the whole surface.
// B(t) = Σ_s w(t, s) E(s) over every inner texel s of the atlas, with w as the local kernels'
// (R_d(max(|x_t − x_s|, ρ_s)) A_s, the texel's own disk for s = t; local.h) but no kernel
// truncation, no threshold and no vertex interpolation: what the local + global split
// approximates. Cost: (inner texels) x (lit inner texels) R_d look-ups, rows in parallel.
// The GPU's reference step (gpu/translucency/reference.comp) sums the same terms.
#include "core/math.h"
#include "core/translucency/atlas.h"
#include "core/translucency/dipole.h"
#include "core/translucency/local.h"

#include <vector>

namespace mesolab::translucency {

// What the loop's pair of a texel with itself (R_d at ρ, times A) must add to make it the disk
// ∫_{r < ρ} R_d 2πr dr, for a texel of area A (mm²).
vec3 reference_self_weight(const Profile& dipole, const RdTable& Rd, float area_mm2);

// Per atlas texel (0 outside inner texels); x_mm from texel_positions_mm.
std::vector<vec3> reference_radiosity(const Atlas& atlas, const std::vector<vec3>& x_mm, const Profile& dipole, double mm_per_unit,
                                      const std::vector<vec3>& E);
}  // namespace mesolab::translucency
