#version 430 core
// Technique bumpsynth: bump map synthesis from an NDF (Kautz et al. 2001), the GLSL twin of
// core/bumpsynth/{noise,lut,shading,bumpsynth}.cpp: the same bits of noise, the same resampled input
// CDFs, the same nearest look-up-table entries and the same BRDF. bumpsynth_pass.cpp draws a depth
// pre-pass first (depth.frag), so this runs once per visible pixel.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"
#include "noise_texture.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

// [SECTION] Data
uniform sampler2D u_ndf;             // (R + 2)²: (value, 1 where the cell meets the disk), an empty border
uniform int u_ndf_res;
uniform sampler2DArray u_lut;        // S x S x 3: m, t, b
uniform int u_lut_size;
layout(std430, binding = 0) readonly buffer Cdfs { float cdf_table[]; };  // G_k,c at u_cdf_nodes nodes, from [(2 (k-1) + c) u_cdf_nodes]
uniform int u_cdf_nodes;
uniform int u_octaves_max;
uniform int u_octave_period[32];     // [2 o + c]
uniform uint u_octave_seed[32];
uniform vec2 u_octave_offset[32];
uniform float u_octave_gain[16];     // gain^o
uniform int u_noise_texture;         // 1: noise = texture
uniform sampler2D u_noise;           // RG: uniformised inputs, level l = K - l octaves (noise_texture.glsl)
uniform int u_noise_levels;
uniform int u_index_map;             // 1: §7 index texture (core/bumpsynth/bump_map.h)
uniform sampler2D u_index;           // W x H: RG = look-up-table inputs, row 0 at the top (v = 1)
uniform ivec2 u_index_size;
uniform float u_index_noise;         // detail amplitude; the octave uniforms are then the detail noise's (period W + c)
uniform sampler2D u_smith;           // 64 (phi) x 65 (theta): G1
uniform int u_masking;
uniform int u_fresnel;
uniform vec3 u_ks;
uniform vec3 u_kd;
uniform float u_detail_distance;
uniform int u_has_albedo;
uniform sampler2D u_albedo;          // top row at t = 0: sampled at (u, 1 - v)

// Fragment outputs o_<aov> (radiance, normal, then the technique's AOVs) are generated from the
// technique's declaration (gpu/renderer.h fragment_outputs) and inserted after #version.

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

float fade(float t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// Gradient h dotted with d, by selects (no indexed array): the same bits as the table.
float grad_dot(uint h, vec2 d) {
    float sx = (h & 1u) != 0u ? -d.x : d.x, sy = (h & 2u) != 0u ? -d.y : d.y;
    float axis = (h & 2u) != 0u ? ((h & 1u) != 0u ? -d.y : d.y) : sx;
    return h < 4u ? axis : kS * sx + kS * sy;
}

// p in [0, 2 period): uv was wrapped to [0, 1] (noise.h), so the cell wraps by one subtraction.
float gradient_noise(vec2 p, int period, uint seed) {
    vec2 f0 = floor(p);
    vec2 f = p - f0;
    ivec2 c0 = ivec2(f0);
    int x0 = c0.x >= period ? c0.x - period : c0.x, y0 = c0.y >= period ? c0.y - period : c0.y;
    int x1 = x0 + 1 == period ? 0 : x0 + 1, y1 = y0 + 1 == period ? 0 : y0 + 1;
    uint hy0 = hash32(uint(y0) + seed), hy1 = hash32(uint(y1) + seed);
    float n00 = grad_dot(hash32(uint(x0) + hy0) & 7u, f), n10 = grad_dot(hash32(uint(x1) + hy0) & 7u, f - vec2(1, 0));
    float n01 = grad_dot(hash32(uint(x0) + hy1) & 7u, f - vec2(0, 1)), n11 = grad_dot(hash32(uint(x1) + hy1) & 7u, f - vec2(1, 1));
    float u = fade(f.x), v = fade(f.y);
    float a = n00 + u * (n10 - n00), b = n01 + u * (n11 - n01);
    return a + v * (b - a);
}

// Octave o of both channels at uv in [0, 1]², including gain^o.
vec2 octave_pair(vec2 uv, int o) {
    int i0 = 2 * o, i1 = 2 * o + 1;
    int p0 = u_octave_period[i0], p1 = u_octave_period[i1];
    return u_octave_gain[o] * vec2(gradient_noise(uv * float(p0) + u_octave_offset[i0], p0, u_octave_seed[i0]),
                                   gradient_noise(uv * float(p1) + u_octave_offset[i1], p1, u_octave_seed[i1]));
}

vec2 to_unit(vec2 T, float A) { return clamp(0.5 + T / (2.0 * kS * A), 0.0, 1.0); }

// G_k,c(r) from the resampled table (core/bumpsynth/noise.cpp NoiseCdfs::input).
float input_cdf(int k, int c, float r) {
    float x = (r > 0.0 ? (r < 1.0 ? r : 1.0) : 0.0) * float(u_cdf_nodes - 1);
    int i = min(int(x), u_cdf_nodes - 2);
    float t = x - float(i);
    int at = (2 * (k - 1) + c) * u_cdf_nodes + i;
    float g0 = cdf_table[at], g1 = cdf_table[at + 1];
    return g0 + t * (g1 - g0);
}

// [SECTION] Index texture and detail (core/bumpsynth/bump_map.cpp)
vec2 index_at(int x, int y) { return texelFetch(u_index, ivec2(x, y), 0).rg; }
int wrap_i(int i, int n) { return ((i % n) + n) % n; }

vec2 index_bilinear(vec2 uv) {
    float fx = uv.x * float(u_index_size.x) - 0.5, fy = (1.0 - uv.y) * float(u_index_size.y) - 0.5;
    float x0f = floor(fx), y0f = floor(fy);
    float tx = fx - x0f, ty = fy - y0f;
    int x0 = wrap_i(int(x0f), u_index_size.x), y0 = wrap_i(int(y0f), u_index_size.y);
    int x1 = x0 + 1 == u_index_size.x ? 0 : x0 + 1, y1 = y0 + 1 == u_index_size.y ? 0 : y0 + 1;
    vec2 a = index_at(x0, y0) + tx * (index_at(x1, y0) - index_at(x0, y0));
    vec2 b = index_at(x0, y1) + tx * (index_at(x1, y1) - index_at(x0, y1));
    return a + ty * (b - a);
}

float reflect_unit(float r) {
    r -= 2.0 * floor(r * 0.5);
    return r > 1.0 ? 2.0 - r : r;
}

vec2 index_inputs(vec2 uv, int k) {
    vec2 u = index_bilinear(uv);
    if (k < 2 || !(u_index_noise > 0.0)) return u;
    uv -= floor(uv);  // the periodic square, as the noise needs (bump_map.cpp)
    vec2 T = vec2(0.0);
    for (int o = 0; o < k - 1; ++o) T += octave_pair(uv, o);
    u += (u_index_noise / kS) * T;
    return vec2(reflect_unit(u.x), reflect_unit(u.y));
}

vec2 input_cdfs(int k, vec2 r) { return vec2(input_cdf(k, 0, r.x), input_cdf(k, 1, r.y)); }

// The inputs of k octaves (coarse, k >= 1) and, with fine, of k + 1 octaves: one pass over the
// octaves, the fine sums being the coarse sums plus octave k (noise.cpp noise_inputs_fading).
void inputs(vec2 uv, int k, bool fine, inout vec2 coarse, out vec2 finer) {
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
    vec2 T = vec2(0.0);
    float A = 0.0;
    for (int o = 0; o < k; ++o) {
        T += octave_pair(uv, o);
        A += u_octave_gain[o];
    }
    if (k > 0) coarse = input_cdfs(k, to_unit(T, A));
    if (fine) {
        T += octave_pair(uv, k);
        A += u_octave_gain[k];
        finer = input_cdfs(k + 1, to_unit(T, A));
    }
}

// [SECTION] Look-up table and NDF (core/bumpsynth/lut.cpp, ndf.cpp)
void lut_lookup(vec2 r, out vec3 m, out vec3 t, out vec3 b) {
    int a = min(u_lut_size - 1, int(clamp(r.x, 0.0, 1.0) * float(u_lut_size)));
    int c = min(u_lut_size - 1, int(clamp(r.y, 0.0, 1.0) * float(u_lut_size)));
    m = texelFetch(u_lut, ivec3(a, c, 0), 0).xyz;
    t = texelFetch(u_lut, ivec3(a, c, 1), 0).xyz;
    b = texelFetch(u_lut, ivec3(a, c, 2), 0).xyz;
}

// u_ndf has a border of one empty cell, (0, 0), all round (bumpsynth_pass.cpp upload_ndf): the four
// taps need no bounds test, and since D is 0 wherever the disk flag is 0, summing every tap with
// weights w·flag is the sum over the cells in the disk, the same bits. When no tap meets the disk the
// cell holding xy is outside it too, and D is 0 there.
float ndf_eval(vec3 m) {
    float len = length(m);
    if (!(len > 0.0) || m.z < 0.0) return 0.0;
    vec2 xy = m.xy / len;
    float r2 = dot(xy, xy);
    if (!(r2 <= 1.0 + 1e-6)) return 0.0;
    if (r2 > 1.0) xy /= sqrt(r2);
    float h = 2.0 / float(u_ndf_res);
    vec2 f = (xy + 1.0) / h - 0.5;
    vec2 f0 = floor(f);
    ivec2 c = ivec2(f0) + 1;
    vec2 t = f - f0, s = 1.0 - t;
    vec2 v00 = texelFetch(u_ndf, c, 0).rg, v10 = texelFetch(u_ndf, c + ivec2(1, 0), 0).rg;
    vec2 v01 = texelFetch(u_ndf, c + ivec2(0, 1), 0).rg, v11 = texelFetch(u_ndf, c + ivec2(1, 1), 0).rg;
    float w00 = s.x * s.y, w10 = t.x * s.y, w01 = s.x * t.y, w11 = t.x * t.y;
    float sum = w00 * v00.x + w10 * v10.x + w01 * v01.x + w11 * v11.x;
    float sum_w = w00 * v00.y + w10 * v10.y + w01 * v01.y + w11 * v11.y;
    return sum_w > 0.0 ? sum / sum_w : 0.0;
}

float smith_g1(vec3 w) {
    if (!(w.z > 0.0)) return 0.0;
    float theta = acos(clamp(w.z / length(w), 0.0, 1.0));
    float phi = atan(w.y, w.x);
    if (phi < 0.0) phi += TWO_PI;
    float ft = theta / (PI / 2.0) * 64.0, fp = phi / TWO_PI * 64.0;
    int t0 = min(int(ft), 63), p0 = int(fp) % 64, p1 = (p0 + 1) % 64;
    float at = clamp(ft - float(t0), 0.0, 1.0), ap = fp - floor(fp);
    float g00 = texelFetch(u_smith, ivec2(p0, t0), 0).r, g01 = texelFetch(u_smith, ivec2(p1, t0), 0).r;
    float g10 = texelFetch(u_smith, ivec2(p0, t0 + 1), 0).r, g11 = texelFetch(u_smith, ivec2(p1, t0 + 1), 0).r;
    float a = g00 + ap * (g01 - g00), b = g10 + ap * (g11 - g10);
    return a + at * (b - a);
}

// [SECTION] The BRDF in a facet's frame (core/bumpsynth/shading.cpp shade_facet)
vec3 shade_facet(vec3 fm, vec3 ft, vec3 fb, vec3 wo, vec3 wi, vec3 E, vec3 albedo) {
    if (!(wo.z > 0.0) || !(wi.z > 0.0)) return vec3(0.0);
    vec3 o = vec3(dot(wo, ft), dot(wo, fb), dot(wo, fm));
    vec3 i = vec3(dot(wi, ft), dot(wi, fb), dot(wi, fm));
    if (!(i.z > 0.0)) return vec3(0.0);
    vec3 L = u_kd * albedo * (INV_PI * i.z);
    if (o.z > 0.0) {
        vec3 h = normalize(o + i);
        float D = ndf_eval(h);
        vec3 F = u_fresnel != 0 ? u_ks + (vec3(1.0) - u_ks) * pow(clamp(1.0 - dot(i, h), 0.0, 1.0), 5.0) : u_ks;
        if (u_masking != 0) {
            float g1o = max(smith_g1(o), 1e-7), g1i = max(smith_g1(i), 1e-7);
            float G2 = 1.0 / (1.0 / g1o + 1.0 / g1i - 1.0);
            L += F * (D * G2 / (4.0 * max(o.z, 1e-7)));
        } else {
            L += F * (D * i.z / 4.0);
        }
    }
    return L * E;
}

void main() {
    vec3 p = v_position;
    vec3 wo = camera_wo(p);
    // Shading frame (core/render.cpp tangent_frame).
    vec3 N = normalize(v_normal);
    if (dot(N, wo) < 0.0) N = -N;
    vec3 T = v_tangent - N * dot(v_tangent, N);
    T = dot(T, T) > 1e-12 ? normalize(T) : (abs(N.x) < 0.9 ? normalize(cross(N, vec3(1, 0, 0))) : normalize(cross(N, vec3(0, 1, 0))));
    vec3 B = cross(N, T);
    mat3 to_world = mat3(T, B, N);
    vec3 wo_t = vec3(dot(wo, T), dot(wo, B), dot(wo, N));

    // Octaves at this distance (core/bumpsynth/noise.cpp octaves_at_distance).
    float K = float(u_octaves_max);
    float oct = K;
    if (u_texture_mode == 0) {
        float d = length(u_eye - p);
        oct = d > 0.0 ? clamp(log2(u_detail_distance / d), 0.0, K) : K;
    }
    int k = int(floor(oct));
    float w = oct - float(k);
    if (k >= u_octaves_max) { k = u_octaves_max; w = 0.0; }

    vec3 cm = vec3(0, 0, 1), ct = vec3(1, 0, 0), cb = vec3(0, 1, 0);
    vec2 uc = vec2(0.5), uf;
    inputs(v_uv, k, w > 0.0, uc, uf);
    if (k > 0) lut_lookup(uc, cm, ct, cb);
    vec3 fm = cm, ft = ct, fb = cb;
    if (w > 0.0) lut_lookup(uf, fm, ft, fb);

    vec3 albedo = u_has_albedo != 0 ? texture(u_albedo, vec2(v_uv.x, 1.0 - v_uv.y)).rgb : vec3(1.0);
    vec3 Lc = vec3(0.0), Lf = vec3(0.0);
    for (int li = 0; li < u_light_count; ++li) {
        vec3 wi, E;
        light_sample(li, p, wi, E);
        vec3 wi_t = vec3(dot(wi, T), dot(wi, B), dot(wi, N));
        Lc += shade_facet(cm, ct, cb, wo_t, wi_t, E, albedo);
        if (w > 0.0) Lf += shade_facet(fm, ft, fb, wo_t, wi_t, E, albedo);
    }
    Lc += u_kd * albedo * INV_PI * env_irradiance(to_world * cm);
    if (w > 0.0) Lf += u_kd * albedo * INV_PI * env_irradiance(to_world * fm);
    vec3 L = w > 0.0 ? mix(Lc, Lf, w) : Lc;
    vec3 n = w > 0.0 ? normalize(mix(cm, fm, w)) : cm;
    o_radiance = vec4(L, 1.0);
    o_normal = vec4(n, 1.0);
    o_octaves = vec4(oct, 0.0, 0.0, 1.0);
}
