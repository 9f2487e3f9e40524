// bumpsynth: a pixel's look-up-table inputs and table entry from its (u, v) and octave count, the
// GLSL twin of core/bumpsynth/{noise,bump_map,lut}.cpp (noise_inputs, index_inputs,
// NoiseTexture::inputs, Lut::lookup). Included by bumpsynth.frag and by the test shader
// shaders/test/bumpsynth_inputs.comp; bumpsynth_pass.cpp sets the uniforms (set_synthesis_uniforms).
//
// The same uv gives the same bits as on the CPU, and so the same table entry: the nearest entry is
// a discontinuous function of the inputs, and one float rounding apart can pick another microfacet.
// Hence:
//   * every value on the way is `precise`, written in the CPU's order of operations: without it a
//     compiler fuses the multiply-adds (llvmpipe does, NVIDIA does), one rounding less than the
//     CPU, which with the same uv gave other inputs at 19% of the pixels (llvmpipe, fig. 1 preset)
//     and at 73% with the noise texture (whose lerps GLSL's mix computes as it likes);
//   * no division: the maps to [0, 1] multiply by scales computed once on the CPU
//     (NoiseOctaves::unit_scale, IndexDetail::scale), since GLSL leaves a division's precision to
//     the implementation (2.5 ULP), while multiplications and additions round correctly;
//   * the integer hash and the lattice wrap are exact, the table and textures are read texel by
//     texel (texelFetch), floor and int() are exact.
// `precise` acts within one function only (GLSL 4.60, 4.7.1), so each function's result is precise.

// [SECTION] Data
layout(std430, binding = 0) readonly buffer Cdfs { float cdf_table[]; };  // G_k,c at u_cdf_nodes nodes, from [(2 (k-1) + c) u_cdf_nodes]
uniform int u_cdf_nodes;
uniform int u_octaves_max;
uniform int u_octave_period[32];     // [2 o + c]
uniform uint u_octave_seed[32];
uniform vec2 u_octave_offset[32];
uniform float u_octave_gain[16];     // gain^o
uniform float u_unit_scale[17];      // [k]: 1 / (2 √½ A_k), A_k = Σ_{o<k} gain^o (NoiseOctaves::unit_scale)
uniform int u_noise_texture;         // 1: noise = texture
uniform sampler2D u_noise;           // RG: uniformised inputs, level l = K - l octaves (noise_texture.glsl)
uniform int u_noise_levels;
uniform int u_index_map;             // 1: §7 index texture (core/bumpsynth/bump_map.h)
uniform sampler2D u_index;           // W x H: RG = look-up-table inputs, row 0 at the top (v = 1)
uniform ivec2 u_index_size;
uniform float u_index_noise;         // detail amplitude / √½ (IndexDetail::scale; 0: none); the octave uniforms are then the detail noise's (period W + c)
uniform int u_lut_size;

#include "noise_texture.glsl"

// [SECTION] Noise (core/bumpsynth/noise.cpp)
const float kS = 0.70710678;
// The 8 unit gradients (noise.cpp kGrad[h]): (1, 0), (-1, 0), (0, 1), (0, -1), (±√½, ±√½) with the
// x sign from bit 0 of h and the y sign from bit 1.

uint hash32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

float fade(float t) {
    precise float r = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    return r;
}

// Gradient h dotted with d, by selects (no indexed array): the same bits as the table (an axis
// gradient's product with 0 adds nothing; the signs are exact).
float grad_dot(uint h, vec2 d) {
    float sx = (h & 1u) != 0u ? -d.x : d.x, sy = (h & 2u) != 0u ? -d.y : d.y;
    float axis = (h & 2u) != 0u ? ((h & 1u) != 0u ? -d.y : d.y) : sx;
    precise float diagonal = kS * sx + kS * sy;
    return h < 4u ? axis : diagonal;
}

// p in [0, 2 period): uv was wrapped to [0, 1] (noise.h), so the cell wraps by one subtraction.
float gradient_noise(vec2 p, int period, uint seed) {
    vec2 f0 = floor(p);
    precise vec2 f = p - f0;
    ivec2 c0 = ivec2(f0);
    int x0 = c0.x >= period ? c0.x - period : c0.x, y0 = c0.y >= period ? c0.y - period : c0.y;
    int x1 = x0 + 1 == period ? 0 : x0 + 1, y1 = y0 + 1 == period ? 0 : y0 + 1;
    uint hy0 = hash32(uint(y0) + seed), hy1 = hash32(uint(y1) + seed);
    precise vec2 f10 = vec2(f.x - 1.0, f.y), f01 = vec2(f.x, f.y - 1.0), f11 = vec2(f.x - 1.0, f.y - 1.0);
    float n00 = grad_dot(hash32(uint(x0) + hy0) & 7u, f), n10 = grad_dot(hash32(uint(x1) + hy0) & 7u, f10);
    float n01 = grad_dot(hash32(uint(x0) + hy1) & 7u, f01), n11 = grad_dot(hash32(uint(x1) + hy1) & 7u, f11);
    float u = fade(f.x), v = fade(f.y);
    precise float a = n00 + u * (n10 - n00), b = n01 + u * (n11 - n01);
    precise float r = a + v * (b - a);
    return r;
}

// Octave o of both channels at uv in [0, 1]², including gain^o.
vec2 octave_pair(vec2 uv, int o) {
    int i0 = 2 * o, i1 = 2 * o + 1;
    int p0 = u_octave_period[i0], p1 = u_octave_period[i1];
    precise vec2 q0 = uv * float(p0) + u_octave_offset[i0], q1 = uv * float(p1) + u_octave_offset[i1];
    precise vec2 r = u_octave_gain[o] * vec2(gradient_noise(q0, p0, u_octave_seed[i0]), gradient_noise(q1, p1, u_octave_seed[i1]));
    return r;
}

// r_k from the k-octave sums T (noise.cpp to_unit).
vec2 to_unit(vec2 T, int k) {
    precise vec2 r = clamp(0.5 + T * u_unit_scale[k], 0.0, 1.0);
    return r;
}

// G_k,c(r) from the resampled table (core/bumpsynth/noise.cpp NoiseCdfs::input).
float input_cdf(int k, int c, float r) {
    precise float x = (r > 0.0 ? (r < 1.0 ? r : 1.0) : 0.0) * float(u_cdf_nodes - 1);
    int i = min(int(x), u_cdf_nodes - 2);
    precise float t = x - float(i);
    int at = (2 * (k - 1) + c) * u_cdf_nodes + i;
    float g0 = cdf_table[at], g1 = cdf_table[at + 1];
    precise float g = g0 + t * (g1 - g0);
    return g;
}

vec2 input_cdfs(int k, vec2 r) { return vec2(input_cdf(k, 0, r.x), input_cdf(k, 1, r.y)); }

// [SECTION] Index texture and detail (core/bumpsynth/bump_map.cpp)
vec2 index_at(int x, int y) { return texelFetch(u_index, ivec2(x, y), 0).rg; }
int wrap_i(int i, int n) { return ((i % n) + n) % n; }

vec2 index_bilinear(vec2 uv) {
    precise float fx = uv.x * float(u_index_size.x) - 0.5, fy = (1.0 - uv.y) * float(u_index_size.y) - 0.5;
    float x0f = floor(fx), y0f = floor(fy);
    precise float tx = fx - x0f, ty = fy - y0f;
    int x0 = wrap_i(int(x0f), u_index_size.x), y0 = wrap_i(int(y0f), u_index_size.y);
    int x1 = x0 + 1 == u_index_size.x ? 0 : x0 + 1, y1 = y0 + 1 == u_index_size.y ? 0 : y0 + 1;
    vec2 i00 = index_at(x0, y0), i10 = index_at(x1, y0), i01 = index_at(x0, y1), i11 = index_at(x1, y1);
    precise vec2 a = i00 + tx * (i10 - i00), b = i01 + tx * (i11 - i01);
    precise vec2 r = a + ty * (b - a);
    return r;
}

float reflect_unit(float r) {
    precise float q = r - 2.0 * floor(r * 0.5);
    return q > 1.0 ? 2.0 - q : q;
}

vec2 index_inputs(vec2 uv, int k) {
    vec2 u = index_bilinear(uv);
    if (k < 2 || !(u_index_noise > 0.0)) return u;
    uv -= floor(uv);  // the periodic square, as the noise needs (bump_map.cpp)
    precise vec2 T = vec2(0.0);
    for (int o = 0; o < k - 1; ++o) T += octave_pair(uv, o);
    precise vec2 d = u + u_index_noise * T;
    return vec2(reflect_unit(d.x), reflect_unit(d.y));
}

// [SECTION] The inputs of a pixel
// The inputs of k octaves (coarse, k >= 1) and, with fine, of k + 1 octaves: one pass over the
// octaves, the fine sums being the coarse sums plus octave k (noise.cpp noise_inputs_fading).
void synthesis_inputs(vec2 uv, int k, bool fine, inout vec2 coarse, out vec2 finer) {
    finer = vec2(0.5);
    if (u_index_map != 0) {
        if (k > 0) coarse = index_inputs(uv, k);
        if (fine) finer = index_inputs(uv, k + 1);
        return;
    }
    if (u_noise_texture != 0) {
        if (k > 0) coarse = noise_texture_bilinear(u_noise, clamp(u_octaves_max - k, 0, u_noise_levels - 1), uv);
        if (fine) finer = noise_texture_bilinear(u_noise, clamp(u_octaves_max - k - 1, 0, u_noise_levels - 1), uv);
        return;
    }
    uv -= floor(uv);  // the periodic square (noise.cpp wrap_uv)
    precise vec2 T = vec2(0.0);
    for (int o = 0; o < k; ++o) T += octave_pair(uv, o);
    if (k > 0) coarse = input_cdfs(k, to_unit(T, k));
    if (fine) {
        T += octave_pair(uv, k);
        finer = input_cdfs(k + 1, to_unit(T, k + 1));
    }
}

// [SECTION] The nearest look-up-table entry (core/bumpsynth/lut.cpp Lut::lookup)
// In float: r S rounds where S is not a power of two, on both sides alike (Lut::entry).
ivec2 lut_entry(vec2 r) {
    precise vec2 x = clamp(r, 0.0, 1.0) * float(u_lut_size);
    return min(ivec2(u_lut_size - 1), ivec2(x));
}
