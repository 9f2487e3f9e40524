#pragma once
// [SECTION] Blending the local and global responses, Lensch et al. 2002, §5.4 (Eq. 9, Fig. 5).
// Added as they are, the local kernels and the interpolated global response count the light
// near where it enters twice. The paper's fix, done here:
//   1. the global factors lose their diagonal (F0, VertexFactors::zero_diagonal);
//   2. each inner texel t adds a "direct" radiosity c_k(t) E(t) to the three vertices v_k of
//      its triangle, with c(t) fitted by least squares so that the global response to unit
//      irradiance at t (direct part + F0 part, interpolated) equals R_d(|x_p − x_t|) A_t on the
//      ring of texels p just outside t's K x K kernel, where the kernel no longer reaches;
//   3. (beyond the paper) c(t) is held to the power the dipole puts beyond t's kernel: by one
//      more equation in the fit where the texels out to two mean edges hold t's hats, else by
//      the energy closure below, so that local + global keeps every source texel's power;
//   4. every kernel weight w(t', t) loses that global response at t' (the part the kernel
//      already holds), so inside the kernel the total is the kernel's, outside it the global.
//   B(x) = B_local(x) + Σ_i φ_i(x) (B_G0,i + B_D,i),  B_G0 = F0 E_vertex,  B_D,i = Σ_t c_i(t) E(t).
// Sources in a kernel that are border texels (the surface beyond a chunk's edge) take the F0
// part only: their direct part belongs to the inner texel of another chunk that samples the
// same surface.
//
// The energy equation (in the fit): the power beyond the kernel out to two mean edges (region
// P, t's chunk and border) must be R_d's there, summed over P's texels like the reference's,
// weighted 10x the ring. It applies only where P sees at least 80% of every corner's hat (and
// 20% of each beyond the kernel): elsewhere the hats reach surface that P does not see.
//
// Energy closure, where the equation does not apply: triangles larger than P (coarse meshes)
// and hats that cross a chunk's edge. Per unit irradiance at inner texel t (area A_t, mm²;
// barycentrics λ_m at the corners v_m of its triangle; projection weights e_m = 3 A_t λ_m / A_m,
// global.h), step 4 leaves the kernel's power inside t's K x K window, so the power that lands
// beyond it is the global part's there:
//   P = Σ_m c_m H_m,  H_m = A_m / 3 − Σ_{inner p in the window} φ_m(p) A_p   (mm², corner m's hat
//                                                                           beyond the kernel)
// plus F0's power beyond the window, A_t Σ_m λ_m s_m − Σ_{p in the window} F0 response(p) A_p,
// s_j = Σ_i R̂_ij A_i / 3 (F0's column sums, dimensionless). The dipole puts A_t (R_S(x_t) − P_W −
// D) there: R_S the power on the object's own surface (Eq. 2 integrated over the receivers,
// surface.h), P_W the integral of R_d over the window on a plane (a square of side K √A_t: the disk
// of half that side in closed form, Dipole::reflectance_within, plus its corners by quadrature),
// and D what the kernel's border taps hold beyond that because the surface folds at the chunk's
// edge: Σ_{border p in the window} [R_d(|x_p − x_t|) − R_d(atlas distance)] A_p (both at least the
// tap's disk radius, local.h). R_d being smooth beyond the kernel, that is also what the
// brute-force reference's texel sums give. The target for c is then
//   G = A_t (R_S − P_W − D − Σ_m λ_m s_m) + Σ_{p in the window} F0 response(p) A_p,
// and c is moved to it without making it negative: above max(G, 0) it is scaled down (where F0
// alone already puts more than the dipole beyond the kernel, c is 0); below G, and where every
// corner's hat reaches at least 20% of its integral beyond the kernel, c += (G − P) e / (H · e),
// the missing power spread like the source's own irradiance. (Where a hat barely leaves the
// kernel, the missing power would land as a bright ring just outside it; the mesh is then fine
// against the kernel and F0 carries the far field.) Where c cannot be topped up, the target keeps
// the plane's R_total in place of R_S − D: c only ever shrinks there (the hats lie mostly within
// the kernel), and R_S costs a tree query (0.05-0.1 ms) per texel, which all of the bunny's
// 43,000 texels would pay. R_S against R_total: on a regular octahedron at 10 mm per unit in skin1
// (faces 87 mm², a few diffusion lengths) the surface holds 1.03-1.09 R_total, at 1 mm 0.39 /
// 0.71 / 0.97; with R_total the blended Σ B A / Σ E A was 0.93-0.98 and 2.6 of the reference
// there, with R_S 1.00-1.02 and 1.00 (tests/translucency/energy_at_every_scale_test.cpp).
// Without D (R_S alone), the 70° folds of a tetrahedron at 50-200 mm per unit, where the kernel's
// border taps already hold the fold's share, came out 1.3-4.2% high; with D, within 0.9%.
// Why: on a mesh whose triangles are far larger than the diffusion length (a box of 300 mm faces
// in skin), the ring fit asks c for R_d at the ring, and a hat spreads that over its whole
// triangle: more than 30x the power the dipole puts beyond the kernel, Σ radiosity / Σ
// irradiance 18 for 0.43. Where region P holds the hats the equation is kept: the closure's flat
// target misses what a curved or thin surface adds (3D distances shorter than along it; the
// skin bunny's reference holds 1.075 R_total in red), and closing every texel to it raised the
// bunny's red RMSE by 18-46% at 1,000-4,000 vertices (0.076 → 0.111 at 2,000). At chunk edges, which the
// equation skipped, the closure helps: skin sphere RMSE 0.039, 0.081, 0.134 → 0.034, 0.075,
// 0.134, Spot 0.044, 0.092, 0.165 → 0.043, 0.091, 0.165 (tests/translucency). With R_S − D where
// c can be topped up, and the edge cap of global.h, Spot 0.042, 0.088, 0.157 → 0.040, 0.079,
// 0.119, the skin sphere unchanged (0.034, 0.075, 0.135), measured one after the other.
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
BlendWeights fit_blending(const Atlas& atlas, const std::vector<vec3>& position, const std::vector<uint32_t>& index, const Profile& dipole,
                          double mm_per_unit, const VertexFactors& F0, LocalKernels& kernels);

// B_D per vertex from per-texel irradiance.
std::vector<vec3> direct_vertex_radiosity(const BlendWeights& b, const LocalKernels& kernels, const Atlas& atlas, const std::vector<uint32_t>& index,
                                          size_t vertex_count, const std::vector<vec3>& E);

// Σ_i φ_i(x_t) B_i at every non-empty texel (barycentric interpolation of vertex values).
std::vector<vec3> interpolate_to_texels(const Atlas& atlas, const std::vector<uint32_t>& index, const std::vector<vec3>& vertex_value);
}  // namespace mesolab::translucency
