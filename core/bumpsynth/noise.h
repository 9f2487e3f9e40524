#pragma once
// Fractal Perlin noise with distance-dependent detail, the inputs (r1, r2) of the normal look-up
// table (Kautz, Heidrich, Seidel 2001, §4, §5.1, §5.2.2).
//
// [SECTION] Gradient noise
// Perlin's gradient noise (Perlin 2002: quintic fade 6t⁵ - 15t⁴ + 10t³) on the integer lattice, with
// one of 8 unit gradients per lattice point chosen by an integer hash (no permutation table, so the
// GLSL version in gpu/bumpsynth/synthesis.glsl computes the same bits). The lattice is periodic with
// `period` cells, so noise laid over a surface's uv square tiles (no seam at u = 0 = 1 on a sphere).
// Its values lie in [-√½, √½] (unit gradients in 2D), 0 at lattice points.
// Cost (it dominates a procedural frame): the fractal noise first reduces uv to the periodic square,
// uv - floor(uv) (the same noise up to float rounding outside [0, 1)², bit for bit inside), so the
// lattice cells of octave o lie in [0, 2 period) and wrap with one conditional subtraction (a SIMD
// GPU has no integer division; gradient_noise itself takes any p, with the exact modulo); the y
// hashes are shared by the two corners of a row (6 hashes per lookup), and the GLSL picks the
// gradient by selects instead of indexing a table: the same bits.
//
// [SECTION] Fractal noise ("turbulence", §4)
// Octave o (o = 0, 1, ...) of channel c at uv:  n_o,c(uv) = gain^o · noise(F_c 2^o uv + offset_o,c)
// with F_c = base_frequency + c (lattice cells per unit of uv, integers so the noise tiles uv), a period
// of F_c 2^o cells, a hash seed per (seed, channel, octave), and an irrational offset per octave and
// channel so that the octaves' lattice zeros never line up. The k-octave sum T_k = Σ_{o<k} n_o,c is
// mapped to r_k = 1/2 + T_k / (2 √½ A_k), A_k = Σ_{o<k} gain^o, which lies in [0, 1]. Channels 0 and 1
// (r1, r2) use unrelated seeds and offsets, and lattices of different periods: gradient noise's
// variance varies within a lattice cell (0 at the lattice points), so two channels on lattices of the
// same period depend on each other through that pattern whatever their offset (a 200k-sample χ² test
// sees it); with F and F + 1 the patterns beat and average out over the uv square. What remains is
// the finite square's sampling dependence, ~1/sqrt(cells): |corr| ~ 0.03 for F = 8, ~1e-4 for F = 256. The paper's turbulence is this sum (its
// "Gaussian distributed" random numbers, §4); Perlin's |noise| variant would fold the distribution.
// The per-octave constants (period, seed, offset, gain^o and the scale 1 / (2 √½ A_k)) are computed
// once (NoiseOctaves; the shader's uniforms), and T_k is summed octave by octave in float in this
// order on both backends, so r_{k+1} is r_k's sums plus octave k: the two octave counts of a fade
// cost k + 1 octaves. r_k = 1/2 + T_k · scale_k multiplies by the scale rather than dividing by
// 2 √½ A_k: GLSL leaves a division's rounding to the implementation, not a multiplication's, and
// the GPU must reproduce these bits (gpu/bumpsynth/synthesis.glsl says why).
//
// [SECTION] Input CDFs per octave count (§4)
// The paper assumes the distribution of the turbulence "remains constant independent of the number of
// octaves"; it does not (one octave is far from Gaussian), so G_k is measured for every octave count
// k = 1..K and each channel (NoiseCdfs, from stratified samples over the uv square), and the look-up
// uses u = G_k,c(r_k,c), uniform for every k. Per channel, because on a finite (periodic) square the
// two channels' empirical distributions differ by ~1/sqrt(lattice cells): one pooled G is off by
// ~0.005 in u for a first octave of 64² cells, which a 200k-sample χ² test sees.
//
// [SECTION] The resampled input CDFs (what a frame evaluates)
// A measured G_k,c has up to ~8k knots at irregular r (lut.h: dense where the density is high), so
// G(r) is a binary search, ~13 dependent reads per channel per pixel on the GPU. The frame uses G̃,
// G resampled: kCdfNodes = 4097 nodes at r = i/4096 (G_k,c at the nodes, exact), linear in
// between, i.e. one index and two adjacent reads. Both backends evaluate the same float table with
// the same float operations (NoiseCdfs::input), so they still agree to float rounding. The table is
// a piecewise-linear interpolant of a piecewise-linear G: it differs from G only inside the node
// intervals (h = 1/4096) that hold knots, by at most h/4 · |the jump of G's slope| at a lone knot.
// Where the equal-count knots are dense (the bell's middle: 2-4 knots per node interval, a knot
// every 1/4096 in G) it smooths the measured staircase's sampling wiggles: max |G̃ - G| over r is
// ~1.1e-4 for the noise CDFs (K = 4..8, F = 8..256, 512² and 1024² samples; the test allows 2e-4;
// twice the nodes would only bring it to ~0.9e-4). That is a tenth of the measured G's own
// sampling error (~sqrt(G (1 - G) / samples²) ~ 1e-3), so u = G̃_k,c(r) is as uniform as u = G(r)
// within that Kolmogorov distance; the χ² tests with the real noise inputs use the table.
//
// [SECTION] Detail by distance (§5.1)
// At eye distance d the octave count is o(d) = clamp(log2(detail_distance / d), 0, K): no bumps at
// d >= detail_distance (the surface is shaded with the NDF alone), one more octave at every halving of
// the distance. A fractional o = k + w blends the shading of k and k + 1 octaves with weight w, so an
// octave fades in continuously while zooming (no popping); k = 0 is the NDF alone.
//
// [SECTION] The mip-mapped noise texture (§5.2.2, the paper's hardware path)
// noise = texture: level l of a mip chain (level 0: size², halving) holds u = G̃_{K-l}(r_{K-l}) of both
// channels (the finest level the most octaves, each coarser level one octave less, box-filtered from
// 4 x 4 samples of its own octave count per texel: the filtered indices of §6). The inputs of k
// octaves are a bilinear, wrapping look-up in level K - k (clamped to the chain), and a fractional
// octave count blends the shading of two levels exactly as the procedural path blends k and k + 1.
#include "core/bumpsynth/lut.h"
#include "core/math.h"
#include <cstdint>
#include <vector>

namespace mesolab::bumpsynth {

struct NoiseParams {
    int base_frequency = 8;  // lattice cells per unit of uv in octave 0 (>= 1)
    float gain = 0.5f;       // amplitude ratio between octaves, in (0, 1]
    uint32_t seed = 1;
    int octaves_max = 8;     // K, in [1, 16]
    // InputError naming bumpsynth.noise_frequency, noise_gain or octaves_max when out of range.
    void validate() const;
};

// 32-bit integer hash (lowbias32 finaliser), shared with the GLSL.
uint32_t hash32(uint32_t x);
// Gradient noise at p, periodic with `period` lattice cells (period >= 1), seeded.
float gradient_noise(vec2 p, int period, uint32_t seed);
// The hash seed and lattice offset (in cells) of octave o of channel c (uniforms of the shader).
uint32_t octave_seed(uint32_t seed, int octave, int channel);
vec2 octave_offset(int octave, int channel);

// The per-octave constants of NoiseParams, once ([o][c]: octave o, channel c).
struct NoiseOctaves {
    static constexpr int kMax = 16;
    NoiseOctaves() = default;
    explicit NoiseOctaves(const NoiseParams& n);
    int count = 0;                  // K
    int period[kMax][2] = {};       // (base_frequency + c) 2^o lattice cells
    uint32_t seed[kMax][2] = {};    // octave_seed
    vec2 offset[kMax][2] = {};      // octave_offset
    float gain[kMax] = {};          // gain^o
    float unit_scale[kMax + 1] = {};  // [k], k >= 1: 1 / (2 √½ A_k), A_k = Σ_{o<k} gain^o summed in float
};

// Octave o of both channels at uv (already in [0, 1]², see above), including gain^o.
vec2 noise_octave_pair(const NoiseOctaves& oct, vec2 uv, int octave);

// Octave o of channel c (0 or 1), including its gain^o.
float noise_octave(const NoiseParams& n, vec2 uv, int octave, int channel);
// r_k: the first k octaves of channel c mapped to [0, 1] (k >= 1).
float fractal_noise(const NoiseParams& n, vec2 uv, int k, int channel);
// r_k of both channels for every k = 1..K at once: out[k-1] = (r1, r2) of k octaves.
void fractal_noise_all(const NoiseParams& n, vec2 uv, vec2* out);
// The same for k = 1..count (count <= K) with the constants computed once.
void fractal_noise_all(const NoiseOctaves& oct, vec2 uv, int count, vec2* out);

// The octave count at eye distance d (see above); texture mode renders at the full K.
float octaves_at_distance(float distance, float detail_distance, int octaves_max);

// G_k,c for k = 1..K and channels c = 0, 1, measured and resampled (see above).
struct NoiseCdfs {
    static constexpr int kCdfNodes = 4097;  // nodes of a resampled G: r = i / (kCdfNodes - 1)
    NoiseParams params;
    NoiseOctaves octaves;     // of params
    std::vector<InputCdf> G;  // G[2 (k-1) + c], the measured knots
    std::vector<float> table; // G[2 (k-1) + c] at the nodes: table[(2 (k-1) + c) kCdfNodes + i]
    const InputCdf& of(int k, int channel) const { return G[size_t(2 * (k - 1) + channel)]; }
    // The resampled G_k,c(r) (r clamped to [0, 1], NaN counts as 0): what a frame uses, on both backends.
    float input(int k, int channel, float r) const;
};
// Measures G_k from samples² stratified jittered points over [0, 1)² (fixed seed), both channels,
// and resamples them. ~0.15-0.2 s for K = 8, samples = 512 on 2 cores (mostly sorting the 2K sample sets).
NoiseCdfs measure_noise_cdfs(const NoiseParams& n, int samples = 512);
// The nodes of the resampled G (kCdfNodes values G(i / (kCdfNodes - 1))).
std::vector<float> resample_input_cdf(const InputCdf& G);

// The uniformised inputs u = (G_k,0(r1), G_k,1(r2)) of k >= 1 octaves at uv (resampled G).
vec2 noise_inputs(const NoiseCdfs& cdfs, vec2 uv, int k);
// The inputs of k and k + 1 octaves in one pass (k + 1 <= K): the fine sums are the coarse sums
// plus octave k, so `fine` is noise_inputs(k + 1) exactly; for k = 0 `coarse` is left unchanged.
void noise_inputs_fading(const NoiseCdfs& cdfs, vec2 uv, int k, vec2& coarse, vec2& fine);

// The paper's mip-mapped noise texture (level l: K - l octaves; levels of size >> l down to size 1
// or K levels, whichever comes first; levels beyond K hold 1 octave).
struct NoiseTexture {
    int size = 0;                    // level 0 width = height (a power of two)
    int octaves_max = 0;
    std::vector<std::vector<vec2>> levels;  // row-major, row 0 at v = 0
    int level_of(int k) const;              // K - k, clamped to [0, levels - 1]
    vec2 bilinear(int level, vec2 uv) const;  // GL_LINEAR + GL_REPEAT at one level
    vec2 inputs(vec2 uv, int k) const { return bilinear(level_of(k), uv); }
};
// InputError (bumpsynth.noise_texture_size) unless size is a power of two in [16, 4096].
NoiseTexture make_noise_texture(const NoiseCdfs& cdfs, int size);
}  // namespace mesolab::bumpsynth
