#pragma once
// Method kautz-consistent of technique bumpsynth: the paper's synthesis, with every octave count
// shaded by the NDF the bumps it does not resolve actually produce.
//
// [SECTION] Why
// The paper (Kautz, Heidrich, Seidel 2001, §5) shades a pixel whose eye distance resolves k of the
// K octaves with the NDF D in the frame of the k-octave facet, and the far field (k = 0) with D in
// the macro frame. But each bump of the full synthesis is itself shaded with D in its own frame,
// so what a pixel's footprint holds is D composed with the spread of the K-octave facets around the
// k-octave one: far away, the NDF convolved with itself (for Beckmann α about Beckmann α√2: half
// the peak, a lobe √2 wider), which the paper's far field misses (page: 1.22 against the truth
// where LEAN mapping has 0.64 on fig1's sphere at distance 12).
//
// [SECTION] The tables (build_consistent_ndfs)
// For k = 0..K, in the frame {t_k, b_k, m_k} of the k-octave facet (the look-up table's entry; the
// macro frame at k = 0) the NDF the footprint's bumps produce, per unit projected area:
//     D_k(h) = E_p[ D(Q_p h) / m_z,p ]                                             (sr^-1)
// where p runs over points of the surface, Q_p turns the k-frame into the frame of the K-octave
// facet at p ({t_K, b_K, m_K} as rows, expressed in the k-frame) and m_z,p = m_K·m_k. The 1/m_z,p
// is the facet's area per unit projected area: for an NDF with ∫ D(m) m dω = n (every height field's)
// ∫ D_k(h) h_z dω = E_p[m_z,p / m_z,p] = 1, so D_k is normalised as D is (ndf.h). The expectation
// is measured, not modelled: p runs over `samples` points of the uv square, stratified (one jittered
// point per cell of a √N × √N grid, a fixed seed), through the same synthesis and look-up table as
// the frame (the same noise, noise texture or index map). D_K = D exactly; k = 0 gives the
// self-convolution. The mean facet normal m̄_k = E_p[m_K in the k-frame] (|m̄| < 1) shades the
// diffuse term: E_p[max(0, m_K·wi)] ≈ max(0, m̄_k·wi), and at k = 0 the far field's diffuse is no
// longer the flat surface's (4% too bright for Beckmann 0.3, page).
// Each D_k is tabulated at the NDF's cells (value at the cell's centre, pulled inside the disk at
// the rim; Ndf::from_image renormalises the masses to 1) and, with masking, gets its Smith table.
//
// [SECTION] Assumptions (stated on the page)
// - Stationarity: the spread of the unresolved octaves is taken to be the same whatever the k-octave
//   facet (measured as one mean over the surface).
// - The paper's BRDF keeps its form: f_s cos θi = F D_k(h) (m_k·wi) / 4 where the bumps give
//   E_p[F D(h_p) (m_p·wi)] / 4 (they differ by the facets' tilt against wi: small near normal incidence).
// - The blend between k and k + 1 octaves blends their shadings as in the paper.
#include "core/bumpsynth/brdf.h"
#include "core/bumpsynth/ndf.h"
#include <functional>
#include <vector>

namespace mesolab::bumpsynth {

struct ConsistentNdfs {
    std::vector<Ndf> ndf;                 // D_k, k = 0..K
    std::vector<vec3> mean_normal;        // m̄_k in the k-frame (m̄_K = (0, 0, 1))
    std::vector<SmithTable> smith;        // with masking: the Smith table of each D_k; else empty
    int samples = 0;

    int octaves_max() const { return int(ndf.size()) - 1; }
};

// The facet of k octaves at uv (the look-up table's nearest entry; the macro frame for k = 0).
using FacetAt = std::function<LutEntry(vec2 uv, int k)>;

// The tables above for k = 0..K from `samples` points (a perfect square is used as is; otherwise the
// next one up), D tabulated at ndf's resolution. InputError (bumpsynth.consistent_samples) for
// samples < 1. Deterministic; parallel over the tables' rows.
ConsistentNdfs build_consistent_ndfs(const Ndf& ndf, const FacetAt& facet, int K, int samples, bool masking);

// The facet the synthesis `s` gives at uv with k octaves (facets_at without the blend).
LutEntry synthesis_facet(const Synthesis& s, vec2 uv, int k);
}  // namespace mesolab::bumpsynth
