#version 450 core
// Technique cloth (GLSL 4.50 for the fine derivatives): the fitted fabric on a garment, the GLSL twin of core/cloth/reflectance.cpp and
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

// Keeps the four nearest directions by angle (largest cosine c) as ViewTable::at
// (core/cloth/lafortune.cpp) does: directions come in index order and a later one must be
// strictly nearer to pass an earlier one, so equal cosines keep the lower index first.
// Written with constant component indices only: a vector indexed by a loop variable is kept in
// local memory on some GPUs (NVIDIA), and this runs for every view of every pixel.
void keep_nearest4(float c, int i, inout ivec4 best, inout vec4 cb) {
    if (c <= cb.w) return;
    if (!(c > cb.z)) {
        cb.w = c, best.w = i;
    } else if (!(c > cb.y)) {
        cb.w = cb.z, best.w = best.z;
        cb.z = c, best.z = i;
    } else if (!(c > cb.x)) {
        cb.wz = cb.zy, best.wz = best.zy;
        cb.y = c, best.y = i;
    } else {
        cb.wzy = cb.zyx, best.wzy = best.zyx;
        cb.x = c, best.x = i;
    }
}

// Weights of the three nearest (best, with d0..d3 their directions): 1/angle less the fourth
// nearest's, so that a direction's weight falls to 0 where it stops being one of the three and
// T(v) is continuous (ViewTable::at); an exact hit keeps only itself.
vec3 nearest_weights(ivec4 best, vec3 w, vec3 d0, vec3 d1, vec3 d2, vec3 d3) {
    vec4 angle = vec4(atan(length(cross(d0, w)), dot(d0, w)), atan(length(cross(d1, w)), dot(d1, w)),
                      atan(length(cross(d2, w)), dot(d2, w)), atan(length(cross(d3, w)), dot(d3, w)));
    if (angle[0] < 1e-7) return vec3(1.0, 0.0, 0.0);
    float floor_w = best[3] >= 0 ? 1.0 / angle[3] : 0.0;
    vec3 wt = vec3(0.0);
    for (int k = 0; k < 3; ++k) wt[k] = best[k] >= 0 ? max(0.0, 1.0 / angle[k] - floor_w) : 0.0;
    float wsum = wt[0] + wt[1] + wt[2];
    return wsum > 0.0 ? wt / wsum : vec3(1.0 / 3.0);  // the four at one angle: the mean of the three
}

// T(v) of lafortune.cpp ViewTable::at, over one entry's own table.
vec4 table_at(int first, int count, vec3 w) {
    if (count == 0) return vec4(1.0);
    ivec4 best = ivec4(-1);
    vec4 cb = vec4(-2.0);
    for (int i = 0; i < count; ++i) keep_nearest4(dot(P[first + 2 * i].xyz, w), i, best, cb);
    vec3 d[4];
    for (int k = 0; k < 4; ++k) d[k] = best[k] >= 0 ? P[first + 2 * best[k]].xyz : vec3(0.0);
    vec3 wt = nearest_weights(best, w, d[0], d[1], d[2], d[3]);
    vec4 t = vec4(0.0);
    for (int k = 0; k < 3 && best[k] >= 0; ++k) t += wt[k] * P[first + 2 * best[k] + 1];
    return t;
}

// The same for the shared views, once per pixel: the three nearest to w (pattern frame) and
// their normalised weights.
void nearest_views(vec3 w, out ivec3 idx, out vec3 wt) {
    ivec4 best = ivec4(-1);
    vec4 cb = vec4(-2.0);
    for (int i = 0; i < u_shared_views; ++i) keep_nearest4(dot(u_views[i], w), i, best, cb);
    vec3 d[4];
    for (int k = 0; k < 4; ++k) d[k] = best[k] >= 0 ? u_views[best[k]] : vec3(0.0);
    wt = nearest_weights(best, w, d[0], d[1], d[2], d[3]);
    idx = best.xyz;
}

// core/cloth/pyramid.cpp entry_reflectance: the model only where it was fitted (light at least
// 0.05 above the entry's horizon, the view on or above it), same azimuth.
vec3 lift(vec3 w, float z) {
    if (w.z >= z) return w;
    float h = length(w.xy);
    vec2 d = h > 1e-12 ? w.xy / h : vec2(1.0, 0.0);
    return vec3(d * sqrt(1.0 - z * z), z);
}

// [SECTION] The sheen of cloth.method = sheen (core/cloth/sheen.cpp): Estevez and Kulla 2017.
float sheen_L(float x, float r) {
    float t = (1.0 - r) * (1.0 - r);
    float a = mix(21.5473, 25.3245, t), b = mix(3.82987, 3.32435, t), c = mix(0.19823, 0.16801, t);
    float d = mix(-1.97760, -1.27393, t), e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}
float sheen_lambda(float mu, float r) {
    mu = clamp(mu, 0.0, 1.0);
    return mu < 0.5 ? exp(sheen_L(mu, r)) : exp(2.0 * sheen_L(0.5, r) - sheen_L(1.0 - mu, r));
}
float sheen_lobe(vec3 l, vec3 v, float r) {
    if (l.z <= 0.0 || v.z <= 0.0) return 0.0;
    vec3 h = normalize(l + v);
    float sin2 = max(0.0, 1.0 - h.z * h.z);
    float D = (2.0 + 1.0 / r) * pow(sin2, 0.5 / r) / (2.0 * 3.14159265358979);
    float G = 1.0 / (1.0 + sheen_lambda(l.z, r) + sheen_lambda(v.z, r));
    return D * G / (4.0 * l.z * v.z);
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
        for (int j = 0; j < 3; ++j) if (vidx[j] >= 0) t += vwt[j] * P[table + 2 * vidx[j] + 1];
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
        if (lobes < 0) f += P[base + 5].rgb * sheen_lobe(lf, vf, P[base + 5].w);
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

    // Mip level (core/cloth/reflectance.h): lambda = log2(footprint x res) + bias.
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
