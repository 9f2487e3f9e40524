#version 450 core
// Method lean of technique bumpsynth: LEAN mapping (Olano and Baker 2010), the GLSL twin of
// LeanMethod::shade_cpu, LeanMap::filter and lean_shade (core/bumpsynth/lean.{h,cpp}, where the
// maths is explained). The moments are texelFetch'd and blended with the CPU's lerps; the level
// and the taps come from the quad's uv differences, as the CPU rasteriser gives them.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform sampler2D u_moments_a;   // (B_x, B_y, M_xx, M_yy), one mip level per map level
uniform sampler2D u_moments_b;   // (M_xy, m_x, m_y, m_z)
uniform int u_size;              // texels per side of level 0
uniform int u_levels;
uniform vec3 u_sigma0;           // (xx, yy, xy)
uniform int u_anisotropy;
uniform float u_octaves;
uniform int u_masking;
uniform int u_fresnel;
uniform vec3 u_ks;
uniform vec3 u_kd;
uniform int u_has_albedo;
uniform sampler2D u_albedo;      // top row at t = 0: sampled at (u, 1 - v)

struct Moments { vec2 B; vec3 M; vec3 m; };

// Bilinear, periodic, at level l (LeanMap::at_level).
Moments at_level(int l, vec2 uv) {
    int n = u_size >> l;
    float x = uv.x * float(n) - 0.5, y = (1.0 - uv.y) * float(n) - 0.5;
    float x0f = floor(x), y0f = floor(y);
    float ax = x - x0f, ay = y - y0f;
    int x0 = ((int(x0f) % n) + n) % n, x1 = ((int(x0f) + 1) % n + n) % n;
    int y0 = ((int(y0f) % n) + n) % n, y1 = ((int(y0f) + 1) % n + n) % n;
    vec4 a00 = texelFetch(u_moments_a, ivec2(x0, y0), l), a10 = texelFetch(u_moments_a, ivec2(x1, y0), l);
    vec4 a01 = texelFetch(u_moments_a, ivec2(x0, y1), l), a11 = texelFetch(u_moments_a, ivec2(x1, y1), l);
    vec4 b00 = texelFetch(u_moments_b, ivec2(x0, y0), l), b10 = texelFetch(u_moments_b, ivec2(x1, y0), l);
    vec4 b01 = texelFetch(u_moments_b, ivec2(x0, y1), l), b11 = texelFetch(u_moments_b, ivec2(x1, y1), l);
    vec4 ta = a00 + ax * (a10 - a00), ba = a01 + ax * (a11 - a01);
    vec4 a = ta + ay * (ba - ta);
    vec4 tb = b00 + ax * (b10 - b00), bb = b01 + ax * (b11 - b01);
    vec4 b = tb + ay * (bb - tb);
    return Moments(a.xy, vec3(a.z, a.w, b.x), b.yzw);
}

Moments trilinear(vec2 uv, float lambda) {
    int last = u_levels - 1;
    float lam = clamp(isinf(lambda) || isnan(lambda) ? 0.0 : lambda, 0.0, float(last));
    int l0 = min(int(floor(lam)), last);
    float t = lam - float(l0);
    Moments mo = at_level(l0, uv);
    if (t > 0.0 && l0 < last) {
        Moments c = at_level(l0 + 1, uv);
        mo.B += t * (c.B - mo.B);
        mo.M += t * (c.M - mo.M);
        mo.m += t * (c.m - mo.m);
    }
    return mo;
}

// The footprint's moments (LeanMap::filter).
Moments filter_footprint(vec2 uv, vec2 dx, vec2 dy) {
    float lx = length(dx), ly = length(dy);
    float major = max(lx, ly), minor = min(lx, ly);
    vec2 axis = lx >= ly ? dx : dy;
    int taps = 1;
    if (u_anisotropy > 1 && minor > 0.0) taps = clamp(int(ceil(major / minor)), 1, u_anisotropy);
    else if (u_anisotropy > 1 && major > 0.0) taps = u_anisotropy;
    float extent = max(major / float(taps), minor);
    float lambda = extent > 0.0 ? log2(extent * float(u_size)) : 0.0;
    if (taps == 1) return trilinear(uv, lambda);
    Moments sum = Moments(vec2(0.0), vec3(0.0), vec3(0.0));
    for (int k = 0; k < taps; ++k) {
        float f = (float(k) + 0.5) / float(taps) - 0.5;
        Moments mo = trilinear(uv + f * axis, lambda);
        sum.B += mo.B;
        sum.M += mo.M;
        sum.m += mo.m;
    }
    float w = 1.0 / float(taps);
    sum.B *= w;
    sum.M *= w;
    sum.m *= w;
    return sum;
}

// [SECTION] The lobe (LeanLobe) and the BRDF (lean_shade)
struct Lobe { vec2 B; vec3 sigma; };  // mean slope and Σ (xx, yy, xy)

float lobe_D(Lobe lb, vec3 h) {
    if (!(h.z > 0.0)) return 0.0;
    float dx = h.x / h.z - lb.B.x, dy = h.y / h.z - lb.B.y;
    float det = lb.sigma.x * lb.sigma.y - lb.sigma.z * lb.sigma.z;
    float e = (lb.sigma.y * dx * dx - 2.0 * lb.sigma.z * dx * dy + lb.sigma.x * dy * dy) / det;
    float h2 = h.z * h.z;
    return exp(-0.5 * e) / (2.0 * PI * sqrt(det) * h2 * h2);
}

float lobe_Lambda(Lobe lb, vec3 w) {
    float r2 = w.x * w.x + w.y * w.y;
    if (!(r2 > 0.0)) return 0.0;
    if (!(w.z > 0.0)) return 1e7;
    float s2 = (w.x * w.x * lb.sigma.x + 2.0 * w.x * w.y * lb.sigma.z + w.y * w.y * lb.sigma.y) / r2;
    float a = w.z / sqrt(2.0 * s2 * r2);
    if (a >= 1.6) return 0.0;
    return (1.0 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a);
}

vec3 lean_shade(Moments mo, Lobe lb, vec3 wo, vec3 wi, vec3 E, vec3 albedo) {
    if (!(wo.z > 0.0) || !(wi.z > 0.0)) return vec3(0.0);
    vec3 L = u_kd * albedo * (INV_PI * max(0.0, dot(mo.m, wi)));
    vec3 h = normalize(wo + wi);
    float D = lobe_D(lb, h);
    vec3 F = u_fresnel != 0 ? u_ks + (vec3(1.0) - u_ks) * pow(clamp(1.0 - dot(wi, h), 0.0, 1.0), 5.0) : u_ks;
    if (u_masking != 0) {
        float G2 = 1.0 / (1.0 + lobe_Lambda(lb, wo) + lobe_Lambda(lb, wi));
        L += F * (D * G2 / (4.0 * wo.z));
    } else {
        L += F * (D * wi.z / 4.0);
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

    Moments mo = filter_footprint(v_uv, dFdxFine(v_uv), dFdyFine(v_uv));
    float sxx = max(mo.M.x - mo.B.x * mo.B.x, 0.0) + u_sigma0.x + 1e-8;
    float syy = max(mo.M.y - mo.B.y * mo.B.y, 0.0) + u_sigma0.y + 1e-8;
    float lim = 0.999 * sqrt(sxx * syy);
    float sxy = clamp(mo.M.z - mo.B.x * mo.B.y + u_sigma0.z, -lim, lim);
    Lobe lb = Lobe(mo.B, vec3(sxx, syy, sxy));

    vec3 albedo = u_has_albedo != 0 ? texture(u_albedo, vec2(v_uv.x, 1.0 - v_uv.y)).rgb : vec3(1.0);
    float mlen = length(mo.m);
    vec3 n = mlen > 0.0 ? mo.m / mlen : vec3(0, 0, 1);
    vec3 L = vec3(0.0);
    for (int li = 0; li < u_light_count; ++li) {
        vec3 wi, E;
        light_sample(li, p, wi, E);
        vec3 wi_t = vec3(dot(wi, T), dot(wi, B), dot(wi, N));
        L += lean_shade(mo, lb, wo_t, wi_t, E, albedo);
    }
    L += u_kd * albedo * INV_PI * env_irradiance(to_world * n);
    o_radiance = vec4(L, 1.0);
    o_normal = vec4(n, 1.0);
    o_octaves = vec4(u_octaves, 0.0, 0.0, 1.0);
    o_entry = vec4(-1.0, -1.0, u_octaves, 1.0);
    o_entry_fine = o_entry;
}
