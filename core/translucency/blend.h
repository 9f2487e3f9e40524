#pragma once
// [SECTION] Blending the local and global responses, Lensch et al. 2002, §5.4 (Eq. 9, Fig. 5).
// Added as they are, the local kernels and the interpolated global response count the light
// near where it enters twice. The paper's fix, done here:
//   1. the global factors lose their diagonal (F0, VertexFactors::zero_diagonal);
//   2. each inner texel t adds a "direct" radiosity c_k(t) E(t) to the three vertices v_k of
//      its triangle, with c(t) fitted by least squares so that the global response to unit
//      irradiance at t (direct part + F0 part, interpolated) equals R_d(|x_p − x_t|) A_t on the
//      ring of texels p just outside t's K x K kernel, where the kernel no longer reaches;
//   3. every kernel weight w(t', t) loses that global response at t' (the part the kernel
//      already holds), so inside the kernel the total is the kernel's, outside it the global.
//   B(x) = B_local(x) + Σ_i φ_i(x) (B_G0,i + B_D,i),  B_G0 = F0 E_vertex,  B_D,i = Σ_t c_i(t) E(t).
// Sources in a kernel that are border texels (the surface beyond a chunk's edge) take the F0
// part only: their direct part belongs to the inner texel of another chunk that samples the
// same surface.
#include "core/math.h"
#include "core/translucency/atlas.h"
#include "core/translucency/global.h"
#include "core/translucency/local.h"

#include <array>
#include <vector>

namespace mesolab::translucency {

struct BlendWeights {
    // Per inner texel (LocalKernels::texel order): c for the three corners of its triangle, per channel.
    std::vector<std::array<vec3, 3>> c;
};

// Fits c and corrects the kernels in place (K from the kernels; the ring needs the atlas's border
// of (K-1)/2 + 1 texels, which LocalKernels already requires). `F0` must have a zero diagonal.
BlendWeights fit_blending(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Dipole& dipole,
                          double mm_per_unit, const VertexFactors& F0, LocalKernels& kernels);

// B_D per vertex from per-texel irradiance.
std::vector<vec3> direct_vertex_radiosity(const BlendWeights& b, const LocalKernels& kernels, const Atlas& atlas, const std::vector<uint32_t>& index,
                                          size_t vertex_count, const std::vector<vec3>& E);

// Σ_i φ_i(x_t) B_i at every non-empty texel (barycentric interpolation of vertex values).
std::vector<vec3> interpolate_to_texels(const Atlas& atlas, const std::vector<uint32_t>& index, const std::vector<vec3>& vertex_value);
}  // namespace mesolab::translucency
