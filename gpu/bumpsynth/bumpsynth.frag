#version 430 core
// Technique bumpsynth: bump map synthesis from an NDF (Kautz et al. 2001), the GLSL twin of
// core/bumpsynth/{noise,lut,shading,bumpsynth}.cpp: the same bits of noise, of the resampled input
// CDFs and of the nearest look-up-table entries for the same uv (synthesis.glsl), and the same BRDF.
// bumpsynth_pass.cpp draws a depth pre-pass first (depth.frag), so this runs once per visible pixel;
// both passes put the vertices on the CPU rasteriser's sub-pixel grid (mesh.vert,
// MESOLAB_SNAP_VERTICES), so that uv is interpolated as on the CPU to a few ULP.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"
#include "synthesis.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

// [SECTION] Data
uniform sampler2DArray u_ndf;        // (R + 2)² per layer: (value, 1 where the cell meets the disk), an empty border;
                                     // layer k: the NDF for a facet of k octaves (kautz-consistent), else one layer
uniform int u_ndf_res;
uniform sampler2DArray u_lut;        // S x S x 3: m, t, b
uniform sampler2DArray u_smith;      // 64 (phi) x 65 (theta): G1, layers as u_ndf's
uniform int u_consistent;            // kautz-consistent: the NDF, Smith table and diffuse normal of k octaves' unresolved bumps
uniform vec3 u_mean_normal[17];      // kautz-consistent: their mean normal in the facet's frame, k = 0..K
uniform int u_masking;
uniform int u_fresnel;
uniform vec3 u_ks;
uniform vec3 u_kd;
uniform float u_detail_distance;
uniform int u_has_albedo;
uniform sampler2D u_albedo;          // top row at t = 0: sampled at (u, 1 - v)

// Fragment outputs o_<aov> (radiance, normal, then the technique's AOVs) are generated from the
// technique's declaration (gpu/renderer.h fragment_outputs) and inserted after #version.

// [SECTION] Look-up table and NDF (core/bumpsynth/lut.cpp, ndf.cpp)
void lut_lookup(ivec2 e, out vec3 m, out vec3 t, out vec3 b) {
    m = texelFetch(u_lut, ivec3(e, 0), 0).xyz;
    t = texelFetch(u_lut, ivec3(e, 1), 0).xyz;
    b = texelFetch(u_lut, ivec3(e, 2), 0).xyz;
}

// u_ndf has a border of one empty cell, (0, 0), all round (bumpsynth_pass.cpp upload_ndf): the four
// taps need no bounds test, and since D is 0 wherever the disk flag is 0, summing every tap with
// weights w·flag is the sum over the cells in the disk, the same bits. When no tap meets the disk the
// cell holding xy is outside it too, and D is 0 there.
float ndf_eval(vec3 m, int layer) {
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
    vec2 v00 = texelFetch(u_ndf, ivec3(c, layer), 0).rg, v10 = texelFetch(u_ndf, ivec3(c + ivec2(1, 0), layer), 0).rg;
    vec2 v01 = texelFetch(u_ndf, ivec3(c + ivec2(0, 1), layer), 0).rg, v11 = texelFetch(u_ndf, ivec3(c + ivec2(1, 1), layer), 0).rg;
    float w00 = s.x * s.y, w10 = t.x * s.y, w01 = s.x * t.y, w11 = t.x * t.y;
    float sum = w00 * v00.x + w10 * v10.x + w01 * v01.x + w11 * v11.x;
    float sum_w = w00 * v00.y + w10 * v10.y + w01 * v01.y + w11 * v11.y;
    return sum_w > 0.0 ? sum / sum_w : 0.0;
}

float smith_g1(vec3 w, int layer) {
    if (!(w.z > 0.0)) return 0.0;
    float theta = acos(clamp(w.z / length(w), 0.0, 1.0));
    float phi = atan(w.y, w.x);
    if (phi < 0.0) phi += TWO_PI;
    float ft = theta / (PI / 2.0) * 64.0, fp = phi / TWO_PI * 64.0;
    int t0 = min(int(ft), 63), p0 = int(fp) % 64, p1 = (p0 + 1) % 64;
    float at = clamp(ft - float(t0), 0.0, 1.0), ap = fp - floor(fp);
    float g00 = texelFetch(u_smith, ivec3(p0, t0, layer), 0).r, g01 = texelFetch(u_smith, ivec3(p1, t0, layer), 0).r;
    float g10 = texelFetch(u_smith, ivec3(p0, t0 + 1, layer), 0).r, g11 = texelFetch(u_smith, ivec3(p1, t0 + 1, layer), 0).r;
    float a = g00 + ap * (g01 - g00), b = g10 + ap * (g11 - g10);
    return a + at * (b - a);
}

// [SECTION] The BRDF in a facet's frame (core/bumpsynth/brdf.cpp shade_facet)
// k: the facet's octaves, which pick the tables and the diffuse normal under kautz-consistent.
vec3 shade_facet(vec3 fm, vec3 ft, vec3 fb, int k, vec3 wo, vec3 wi, vec3 E, vec3 albedo) {
    int layer = u_consistent != 0 ? k : 0;
    if (!(wo.z > 0.0) || !(wi.z > 0.0)) return vec3(0.0);
    vec3 o = vec3(dot(wo, ft), dot(wo, fb), dot(wo, fm));
    vec3 i = vec3(dot(wi, ft), dot(wi, fb), dot(wi, fm));
    if (!(i.z > 0.0)) return vec3(0.0);
    vec3 L = u_kd * albedo * (INV_PI * (u_consistent != 0 ? max(0.0, dot(i, u_mean_normal[k])) : i.z));
    if (o.z > 0.0) {
        vec3 h = normalize(o + i);
        float D = ndf_eval(h, layer);
        vec3 F = u_fresnel != 0 ? u_ks + (vec3(1.0) - u_ks) * pow(clamp(1.0 - dot(i, h), 0.0, 1.0), 5.0) : u_ks;
        if (u_masking != 0) {
            float g1o = max(smith_g1(o, layer), 1e-7), g1i = max(smith_g1(i, layer), 1e-7);
            float G2 = 1.0 / (1.0 / g1o + 1.0 / g1i - 1.0);
            L += F * (D * G2 / (4.0 * max(o.z, 1e-7)));
        } else {
            L += F * (D * i.z / 4.0);
        }
    }
    return L * E;
}

// The environment's diffuse light on a facet of k octaves: at its normal (the paper), or at its
// unresolved bumps' mean normal, |m̄| times the irradiance along it (kautz-consistent).
vec3 env_diffuse(vec3 fm, vec3 ft, vec3 fb, int k, mat3 to_world, vec3 albedo) {
    if (u_consistent == 0) return u_kd * albedo * INV_PI * env_irradiance(to_world * fm);
    vec3 mb = u_mean_normal[k];
    vec3 mbar = mb.x * ft + mb.y * fb + mb.z * fm;
    float len = length(mbar);
    return u_kd * albedo * (INV_PI * len) * env_irradiance(to_world * (mbar / len));
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
    synthesis_inputs(v_uv, k, w > 0.0, uc, uf);
    ivec2 ec = ivec2(-1), ef = ivec2(-1);
    if (k > 0) lut_lookup(ec = lut_entry(uc), cm, ct, cb);
    vec3 fm = cm, ft = ct, fb = cb;
    if (w > 0.0) lut_lookup(ef = lut_entry(uf), fm, ft, fb);

    vec3 albedo = u_has_albedo != 0 ? texture(u_albedo, vec2(v_uv.x, 1.0 - v_uv.y)).rgb : vec3(1.0);
    vec3 Lc = vec3(0.0), Lf = vec3(0.0);
    for (int li = 0; li < u_light_count; ++li) {
        vec3 wi, E;
        light_sample(li, p, wi, E);
        vec3 wi_t = vec3(dot(wi, T), dot(wi, B), dot(wi, N));
        Lc += shade_facet(cm, ct, cb, k, wo_t, wi_t, E, albedo);
        if (w > 0.0) Lf += shade_facet(fm, ft, fb, k + 1, wo_t, wi_t, E, albedo);
    }
    Lc += env_diffuse(cm, ct, cb, k, to_world, albedo);
    if (w > 0.0) Lf += env_diffuse(fm, ft, fb, k + 1, to_world, albedo);
    vec3 L = w > 0.0 ? mix(Lc, Lf, w) : Lc;
    vec3 n = w > 0.0 ? normalize(mix(cm, fm, w)) : cm;
    o_radiance = vec4(L, 1.0);
    o_normal = vec4(n, 1.0);
    o_octaves = vec4(oct, 0.0, 0.0, 1.0);
    o_entry = vec4(vec2(ec), float(k), 1.0);
    o_entry_fine = w > 0.0 ? vec4(vec2(ef), float(k + 1), 1.0) : o_entry;
}
