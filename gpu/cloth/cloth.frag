#version 450 core
// Technique cloth (GLSL 4.50 for the fine derivatives): the fitted fabric on a garment, the GLSL twin of core/cloth/shade.cpp and
// ClothTechnique::shade_cpu (core/cloth/technique.cpp). The BRDF pyramid arrives packed as
// core/cloth/technique.h PackedPyramid describes.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

layout(std430, binding = 0) readonly buffer Pyramid { vec4 P[]; };
uniform int u_res;            // sample points per side at level 0
uniform int u_levels;
uniform int u_stride;         // vec4s per entry
uniform int u_max_lobes;      // lobes of the widest entry: the table starts at 5 + 4 u_max_lobes
uniform int u_level_first[16];
uniform float u_repeat;
uniform int u_mip;            // 0 off, 1 nearest, 2 blend
uniform float u_bias;
#define MAX_SHARED_VIEWS 128
uniform int u_shared_views;   // > 0: every entry's table holds these directions in its own frame (PackedPyramid::shared_views)
uniform vec3 u_views[MAX_SHARED_VIEWS];

// Fragment outputs o_<aov> are generated from the technique's declaration and inserted after #version.

// T(v) of lafortune.cpp ViewTable::at: the three nearest directions by angle, inverse-angle weights.
vec4 table_at(int first, int count, vec3 w) {
    if (count == 0) return vec4(1.0);
    int b0 = -1, b1 = -1, b2 = -1;
    float c0 = -2.0, c1 = -2.0, c2 = -2.0;
    for (int i = 0; i < count; ++i) {
        float c = dot(P[first + 2 * i].xyz, w);
        if (c <= c2) continue;
        if (c > c0) { b2 = b1; c2 = c1; b1 = b0; c1 = c0; b0 = i; c0 = c; }
        else if (c > c1) { b2 = b1; c2 = c1; b1 = i; c1 = c; }
        else { b2 = i; c2 = c; }
    }
    int best[3] = int[3](b0, b1, b2);
    vec4 sum = vec4(0.0);
    float wsum = 0.0;
    for (int k = 0; k < 3 && best[k] >= 0; ++k) {
        vec3 d = P[first + 2 * best[k]].xyz;
        float angle = atan(length(cross(d, w)), dot(d, w));
        if (angle < 1e-7) return P[first + 2 * best[k] + 1];
        sum += P[first + 2 * best[k] + 1] / angle;
        wsum += 1.0 / angle;
    }
    return sum / wsum;
}

// The same for the shared views, once per pixel: the three nearest to w (pattern frame) and
// their normalised weights; an exact hit keeps only itself.
void nearest_views(vec3 w, out ivec3 idx, out vec3 wt) {
    int b0 = -1, b1 = -1, b2 = -1;
    float c0 = -2.0, c1 = -2.0, c2 = -2.0;
    for (int i = 0; i < u_shared_views; ++i) {
        float c = dot(u_views[i], w);
        if (c <= c2) continue;
        if (c > c0) { b2 = b1; c2 = c1; b1 = b0; c1 = c0; b0 = i; c0 = c; }
        else if (c > c1) { b2 = b1; c2 = c1; b1 = i; c1 = c; }
        else { b2 = i; c2 = c; }
    }
    idx = ivec3(b0, b1, b2);
    wt = vec3(0.0);
    float wsum = 0.0;
    for (int k = 0; k < 3 && idx[k] >= 0; ++k) {
        vec3 d = u_views[idx[k]];
        float angle = atan(length(cross(d, w)), dot(d, w));
        if (angle < 1e-7) { idx = ivec3(idx[k], -1, -1); wt = vec3(1.0, 0.0, 0.0); return; }
        wt[k] = 1.0 / angle;
        wsum += wt[k];
    }
    wt /= wsum;
}

// core/cloth/pyramid.cpp entry_reflectance: the model only where it was fitted (light at least
// 0.05 above the entry's horizon, the view on or above it), same azimuth.
vec3 lift(vec3 w, float z) {
    if (w.z >= z) return w;
    float h = length(w.xy);
    vec2 d = h > 1e-12 ? w.xy / h : vec2(1.0, 0.0);
    return vec3(d * sqrt(1.0 - z * z), z);
}

// The entry under pattern coordinates uv at level k: radiance summed over the lights, alpha, index.
vec4 entry_radiance(int k, vec2 uv, vec3 p, vec3 T, vec3 B, vec3 N, vec3 v, ivec3 vidx, vec3 vwt, out int index) {
    int side = u_res >> k;
    vec2 w = uv - floor(uv);
    int x = min(side - 1, int(w.x * float(side))), y = min(side - 1, int(w.y * float(side)));
    index = u_level_first[k] + y * side + x;
    int base = index * u_stride;
    vec4 h = P[base];
    vec3 Fx = P[base + 1].xyz, Fy = P[base + 2].xyz, Fz = P[base + 3].xyz;
    int lobes = int(h.w), dirs = int(P[base + 1].w);
    vec3 vh = vec3(dot(Fx, v), dot(Fy, v), dot(Fz, v));
    vec3 vf = lift(vh, 0.0);
    int table = base + 5 + 4 * u_max_lobes;
    vec4 t;
    if (u_shared_views > 0) {
        t = vec4(0.0);
        for (int j = 0; j < 3 && vidx[j] >= 0; ++j) t += vwt[j] * P[table + 2 * vidx[j] + 1];
    } else {
        t = table_at(table, dirs, vh);
    }
    if (dirs == 0) t = vec4(1.0);
    vec3 f_max = P[base + 4].rgb;
    vec3 L = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, E;
        light_sample(i, p, wi, E);
        vec3 l = vec3(dot(T, wi), dot(B, wi), dot(N, wi));
        if (l.z <= 0.0) continue;  // behind the garment's surface
        vec3 lh = vec3(dot(Fx, l), dot(Fy, l), dot(Fz, l));
        if (lh.z <= 0.0) continue;
        vec3 lf = lift(lh, 0.05);
        vec3 f = h.rgb;
        for (int j = 0; j < lobes; ++j) {
            int o = base + 5 + 4 * j;
            vec3 a = P[o].rgb * (lf.x * vf.x) + P[o + 1].rgb * (lf.y * vf.y) + P[o + 2].rgb * (lf.z * vf.z);
            f += mix(vec3(0.0), pow(max(a, vec3(0.0)), P[o + 3].rgb), greaterThan(a, vec3(0.0)));
        }
        L += min(t.rgb * min(f, vec3(1e30)), f_max) * lh.z * E;  // an overflowing lobe stays finite
    }
    return vec4(L, t.a);
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
    vec3 v = vec3(dot(T, wo), dot(B, wo), dot(N, wo));
    v.z = max(v.z, 1e-4);
    v = normalize(v);

    // Mip level (core/cloth/shade.h): lambda = log2(footprint x res) + bias.
    float footprint = max(length(dFdxFine(v_uv)), length(dFdyFine(v_uv))) * u_repeat;
    int top = u_levels - 1;
    float lambda = log2(max(footprint, 1e-30) * float(u_res)) + u_bias;
    lambda = clamp(isinf(lambda) || isnan(lambda) ? 0.0 : lambda, 0.0, float(top));
    if (u_mip == 0) lambda = 0.0;
    if (u_mip == 1) lambda = floor(lambda + 0.5);
    int k0 = int(floor(lambda)), k1 = min(top, k0 + 1);
    float t = u_mip == 2 ? lambda - float(k0) : 0.0;
    vec2 uv = v_uv * u_repeat;
    ivec3 vidx = ivec3(-1);
    vec3 vwt = vec3(0.0);
    if (u_shared_views > 0) nearest_views(v, vidx, vwt);
    int index, index1;
    vec4 a = entry_radiance(k0, uv, p, T, B, N, v, vidx, vwt, index);
    if (t > 0.0 && k1 != k0) a = mix(a, entry_radiance(k1, uv, p, T, B, N, v, vidx, vwt, index1), t);
    float alpha = clamp(a.a, 0.0, 1.0);
    vec3 bg = u_texture_mode != 0 ? vec3(0.0) : env_radiance(-wo);  // holes show the background along the ray
    o_radiance = vec4(alpha * a.rgb + (1.0 - alpha) * bg, 1.0);
    o_normal = vec4(N, 1.0);
    o_alpha = vec4(alpha, 0.0, 0.0, 1.0);
    o_mip_level = vec4(u_mip == 2 ? lambda : float(k0), 0.0, 0.0, 1.0);
    o_brdf_index = vec4(float(index), 0.0, 0.0, 1.0);
}
