#pragma once
// [SECTION] The reference radiosity: the dipole summed over the whole surface.
// B(t) = Σ_s w(t, s) E(s) over every inner texel s of the atlas, with w as the local kernels'
// (R_d(|x_t − x_s|) A_s, the texel's own disk for s = t) but no kernel truncation, no
// threshold and no vertex interpolation: what the local + global split approximates. Cost:
// (inner texels) x (lit inner texels) R_d look-ups, rows in parallel.
#include "core/math.h"
#include "core/translucency/atlas.h"
#include "core/translucency/dipole.h"

#include <vector>

namespace mesolab::translucency {

// Per atlas texel (0 outside inner texels); x_mm from texel_positions_mm.
std::vector<vec3> reference_radiosity(const Atlas& atlas, const std::vector<vec3>& x_mm, const Dipole& dipole, double mm_per_unit,
                                      const std::vector<vec3>& E);
}  // namespace mesolab::translucency
