#pragma once
// The sweep metric `bumpsynth.ndf_histogram` (`mesolab sweep --metric bumpsynth.ndf_histogram`):
// how far the distribution of the normals the renderer synthesises is from the NDF it was asked for.
//
// [SECTION] Definition
// For the first bumpsynth object of the scene, N = kSamplesPerSide² uv points, one per cell of a
// kSamplesPerSide² grid over the uv square, jittered within it (fixed seed), each synthesise a
// normal at full detail (all octaves_max octaves) through facets_at: the uniformised noise inputs
// and the nearest look-up-table entry, exactly as the renderer's pixels do (procedural noise or the
// noise texture). Their projected (m_x, m_y) are counted on B x B bins over [-1, 1]² (B = kBins),
// giving p; q is the reference setting's tabulated NDF (R x R cells, B divides R) with its cell
// masses summed into the same bins, exact because every bin is a union of cells. The metric is the
// total-variation distance TV(p, q) = ½ Σ |p_b − q_b|, in [0, 1]: the probability mass that would
// have to move between bins.
// What it sees: the look-up table's quantisation of the inputs (1/S: nearest-entry look-up), the
// noise inputs' departure from independent uniform inputs, and the NDF's bin masses. What it does
// not see: detail finer than a bin. Every cell mass of a tabulated analytic NDF is the exact
// integral whatever the resolution R, and the bins are unions of cells, so the NDF's resolution
// reaches the metric only through where the look-up table's entries fall inside a bin.
//
// [SECTION] Noise floor
// N independent samples from q would give an expected TV of ½ Σ_b E|X_b − N q_b| / N with X_b
// binomial(N, q_b), computed exactly with de Moivre's mean absolute deviation
//   E|X − Np| = 2 (k+1) C(N, k+1) p^(k+1) (1−p)^(N−k),  k = ⌊Np⌋
// (≈ Σ_b sqrt(q_b (1−q_b) / (2π N)), at most sqrt(B² / (2π N)) = 0.0125 for B = 32, N = 2^20 when q
// is spread over every bin; a lobe covering fewer bins has a lower floor). The synthesised normals
// are not independent samples: their inputs come from one realisation of the fractal noise over the
// uv square (stratified, so they are more even than independent ones, but the finite square's noise
// is slightly non-uniform and its two channels slightly dependent). The metric at the reference
// setting itself measures the floor that this realisation and the reference's table set.
// Cost: ~2^20 syntheses at 8 octaves, a fraction of a second on 2 cores (not part of the sweep's time).
#include "core/bumpsynth/ndf.h"
#include "core/bumpsynth/brdf.h"
#include "core/technique.h"
#include <cstdint>
#include <vector>

namespace mesolab::bumpsynth {

constexpr int kHistogramBins = 32;            // B
constexpr int kHistogramSamplesPerSide = 1024;  // N = 1024² = 2^20

// Bin masses of the normals synthesised at full detail at side² jittered uv points (B x B,
// row-major j B + i, bin (i, j) covering x in [-1 + 2i/B, -1 + 2(i+1)/B], y likewise; sum 1).
std::vector<double> synthesised_histogram(const Synthesis& s, int bins = kHistogramBins, int side = kHistogramSamplesPerSide);
// The NDF's cell masses summed into B x B bins (std::invalid_argument unless B divides R).
std::vector<double> ndf_bin_masses(const Ndf& ndf, int bins = kHistogramBins);
// ½ Σ |p − q| (std::invalid_argument for different sizes).
double total_variation(const std::vector<double>& p, const std::vector<double>& q);
// The expected TV of n independent samples from q against q (exact, see above).
double multinomial_tv_floor(const std::vector<double>& q, int64_t n);

// The metric's declaration (Technique::sweep_metrics of bumpsynth).
SweepMetricDecl ndf_histogram_metric();
}  // namespace mesolab::bumpsynth
