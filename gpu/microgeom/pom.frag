#version 430 core
// Method pom of technique microgeom: parallax occlusion mapping with self-shadowing, the GLSL
// twin of PomMethod::shade_cpu and pom_march / pom_visibility (core/microgeom/pom.cpp, where the
// steps are explained). Heights, normals and albedo are texelFetch'd with the CPU's bilinear
// weights, so the two paths take the same steps up to float rounding.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform sampler2D u_heights;   // microgeom.pom_field: heights in texels above the base, r
uniform sampler2D u_normals;   // heightfield normals (local frame), rgb
uniform sampler2D u_albedo;
uniform ivec2 u_size;          // heightfield texels
uniform vec2 u_z_range;        // (z_min, z_max)
uniform float u_tiling;
uniform int u_steps, u_refine, u_shadow_steps;
uniform int u_phong;
uniform vec3 u_ks;
uniform float u_shininess;

const float kMinCos = 1.0 / 64.0;  // kPomMinCos

ivec2 wrap(ivec2 t) { return ((t % u_size) + u_size) % u_size; }

// Bilinear, periodic height at texel coordinates (c, r), as sample_bilinear.
float height_at(float c, float r) {
    float c0 = floor(c), r0 = floor(r), fc = c - c0, fr = r - r0;
    ivec2 t = ivec2(int(c0), int(r0));
    float h00 = texelFetch(u_heights, wrap(t), 0).r, h10 = texelFetch(u_heights, wrap(t + ivec2(1, 0)), 0).r;
    float h01 = texelFetch(u_heights, wrap(t + ivec2(0, 1)), 0).r, h11 = texelFetch(u_heights, wrap(t + ivec2(1, 1)), 0).r;
    return (1.0 - fc) * (1.0 - fr) * h00 + fc * (1.0 - fr) * h10 + (1.0 - fc) * fr * h01 + fc * fr * h11;
}

// The view ray's hit (c, r, z) from base point (c0, r0) towards the eye v (tangent frame).
vec3 pom_march(float c0, float r0, vec3 v) {
    float vz = max(v.z, kMinCos);
    float dc = v.x / vz, dr = -v.y / vz;
    float z_min = u_z_range.x, z_max = u_z_range.y, span = z_max - z_min;
    if (!(span > 0.0)) return vec3(c0 + z_max * dc, r0 + z_max * dr, z_max);
    int n = max(1, u_steps);
    float dz = span / float(n);
    float z_hi = z_max, z_lo = z_min;
    for (int i = 1; i <= n; ++i) {
        float z = i == n ? z_min : z_max - float(i) * dz;
        if (i == n || z - height_at(c0 + z * dc, r0 + z * dr) <= 0.0) {
            z_lo = z;
            z_hi = i == 1 ? z_max : z_max - float(i - 1) * dz;
            break;
        }
    }
    for (int k = 0; k < u_refine; ++k) {
        float zm = 0.5 * (z_lo + z_hi);
        if (zm - height_at(c0 + zm * dc, r0 + zm * dr) <= 0.0) z_lo = zm;
        else z_hi = zm;
    }
    float g_hi = z_hi - height_at(c0 + z_hi * dc, r0 + z_hi * dr), g_lo = z_lo - height_at(c0 + z_lo * dc, r0 + z_lo * dr);
    float t = g_hi <= 0.0 ? 0.0 : (g_lo <= 0.0 ? g_hi / (g_hi - g_lo) : 1.0);
    float z = z_hi + t * (z_lo - z_hi);
    return vec3(c0 + z * dc, r0 + z * dr, z);
}

// 1 when the ray from (c, r, z) towards l (tangent frame) stays above the field, as pom_visibility.
float pom_visibility(float c, float r, float z, vec3 l) {
    if (u_shadow_steps <= 0) return 1.0;
    if (!(l.z > 0.0)) return 0.0;
    float lz = max(l.z, kMinCos);
    float dc = l.x / lz, dr = -l.y / lz;
    float span = u_z_range.y - z;
    if (!(span > 0.0)) return 1.0;
    float dz = span / float(u_shadow_steps);
    float bias = 1e-3 * (u_z_range.y - u_z_range.x);
    for (int j = 1; j < u_shadow_steps; ++j) {
        float zj = float(j) * dz;
        if (height_at(c + zj * dc, r + zj * dr) > z + zj + bias) return 0.0;
    }
    return 1.0;
}

void main() {
    vec3 p = v_position;
    vec3 wo = camera_wo(p);
    vec3 N = normalize(v_normal);
    if (dot(N, wo) < 0.0) N = -N;
    vec3 T = v_tangent - N * dot(v_tangent, N);
    T = dot(T, T) > 1e-12 ? normalize(T) : (abs(N.x) < 0.9 ? normalize(cross(N, vec3(1, 0, 0))) : normalize(cross(N, vec3(0, 1, 0))));
    vec3 B = cross(N, T);
    float tiling = u_texture_mode != 0 ? 1.0 : u_tiling;
    float c0 = v_uv.x * float(u_size.x) * tiling - 0.5, r0 = (1.0 - v_uv.y) * float(u_size.y) * tiling - 0.5;
    vec3 hit = pom_march(c0, r0, vec3(dot(wo, T), dot(wo, B), dot(wo, N)));

    float cf = floor(hit.x), rf = floor(hit.y), fc = hit.x - cf, fr = hit.y - rf;
    ivec2 t00 = ivec2(int(cf), int(rf));
    ivec2 tk[4] = ivec2[4](t00, t00 + ivec2(1, 0), t00 + ivec2(0, 1), t00 + ivec2(1, 1));
    float wk[4] = float[4]((1.0 - fc) * (1.0 - fr), fc * (1.0 - fr), (1.0 - fc) * fr, fc * fr);
    vec3 n_loc = vec3(0.0), albedo = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        n_loc += wk[k] * texelFetch(u_normals, wrap(tk[k]), 0).rgb;
        albedo += wk[k] * texelFetch(u_albedo, wrap(tk[k]), 0).rgb;
    }
    n_loc = normalize(n_loc);
    vec3 n = normalize(T * n_loc.x + B * n_loc.y + N * n_loc.z);

    vec3 direct = vec3(0.0);
    float shadow0 = 0.0;
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, E;
        light_sample(i, p, wi, E);
        float cos_i = dot(n, wi);
        float V = cos_i > 0.0 ? pom_visibility(hit.x, hit.y, hit.z, normalize(vec3(dot(wi, T), dot(wi, B), dot(wi, N)))) : 0.0;
        if (i == 0) shadow0 = V;
        if (cos_i <= 0.0 || V <= 0.0) continue;
        vec3 f = albedo * INV_PI;
        if (u_phong != 0) {
            vec3 h = normalize(wo + wi);
            f += u_ks * (u_shininess + 8.0) / (8.0 * PI) * pow(max(0.0, dot(n, h)), u_shininess);
        }
        direct += f * E * cos_i * V;
    }
    vec3 env = albedo * INV_PI * env_irradiance(n);
    o_radiance = vec4(direct + env, 1.0);
    o_normal = vec4(n, 1.0);
    o_direct = vec4(direct, 1.0);
    o_indirect = vec4(env, 1.0);
    o_shadow = vec4(shadow0, 0.0, 0.0, 1.0);
    o_folded = vec4(0.0, 0.0, 0.0, 1.0);
}
