#version 430 core
// Technique microgeom, bump level of detail: the GLSL twin of MicrogeomTechnique::shade_cpu
// (core/microgeom/microgeom.cpp). Exact shadows from the visibility textures S_i (a texture
// array, one layer per direction), the spherical triangle of the light located with a grid
// guess and a walk across edges (the same triangle and barycentrics as DirectionSet::locate),
// scattered light from the stages' irradiance textures (non-planar bases: blended over the
// light's triangle from the per-direction table, located as for the shadows). All look-ups are texelFetch with the
// CPU's bilinear weights, so the two paths agree to rounding.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

layout(std430, binding = 0) readonly buffer Dirs { vec4 dirs[]; };
layout(std430, binding = 1) readonly buffer Tris { ivec4 tris[]; };
layout(std430, binding = 2) readonly buffer Adj { ivec4 adj[]; };   // neighbour across the edge opposite corner k
layout(std430, binding = 3) readonly buffer Grid { int grid[]; };   // lat-long guess of the containing triangle

uniform usampler2DArray u_vis;  // S_i: 0xFFFFFFFF = no hit
uniform sampler2D u_normals;    // heightfield normals (local frame), rgb
uniform sampler2D u_albedo;
uniform sampler2D u_E_env;      // microgeom.scatter_env: irradiance, rgb
uniform sampler2D u_E_light;    // microgeom.scatter: irradiance per unit light irradiance, rgb; light i at rows i * u_size.y
uniform sampler2DArray u_E_dirs;  // microgeom.scatter_directions (non-planar bases): layer j = direction j, j < u_dir_scatters
uniform int u_dir_scatters;     // M, the directions above the horizon (0: no table)
uniform sampler2D u_folded;     // microgeom.importance: 1 where the curvature folds the triangulation
uniform int u_has_folded;
uniform int u_use_ellipse;      // microgeom.shadows == ellipse
uniform float u_ellipse_edge;
uniform sampler2D u_ellipse0;   // (cx, cy, cos angle, sin angle)
uniform sampler2D u_ellipse1;   // (a, b, -, -)
uniform ivec2 u_size;           // heightfield texels
uniform ivec2 u_grid;           // grid cells (phi, theta)
uniform int u_tri_count;
uniform float u_tiling;
uniform int u_has_env, u_light_scatters, u_shadows, u_phong;
uniform vec3 u_ks;
uniform float u_shininess;
// BRDF level of detail (microgeom.lod = brdf): SimulatedBrdf's table, as SimulatedBrdf::eval.
uniform int u_lod_brdf;
uniform sampler2D u_brdf;       // texel (view node, light node): rgb = T(l, v), a = shadow fraction
uniform sampler2D u_brdf_env;   // texel (view node, 0): rgb = T_env(v)
uniform ivec2 u_brdf_nodes;     // (n_theta, n_phi)

// Fragment outputs o_<aov> (radiance, normal, then the technique's AOVs) are generated from the
// technique's declaration (gpu/renderer.h fragment_outputs) and inserted after #version.

// Cone coordinates of w in triangle t; barycentrics once normalised.
vec3 cone(int t, vec3 w) {
    ivec4 v = tris[t];
    vec3 a = dirs[v.x].xyz, b = dirs[v.y].xyz, c = dirs[v.z].xyz;
    return vec3(dot(cross(b, c), w), dot(cross(c, a), w), dot(cross(a, b), w));
}

int locate(vec3 w, out vec3 bary) {
    vec2 ll = latlong_uv(w);
    ivec2 cell = clamp(ivec2(ll * vec2(u_grid)), ivec2(0), u_grid - 1);
    int t = grid[cell.y * u_grid.x + cell.x];
    vec3 c = cone(t, w);
    for (int step = 0; step < 64 && min(c.x, min(c.y, c.z)) < -1e-7; ++step) {
        int k = c.x <= c.y && c.x <= c.z ? 0 : (c.y <= c.z ? 1 : 2);
        t = adj[t][k];
        c = cone(t, w);
    }
    if (min(c.x, min(c.y, c.z)) < -1e-7) {  // not expected: the best triangle overall
        float best = -1e30;
        for (int f = 0; f < u_tri_count; ++f) {
            vec3 cf = cone(f, w);
            float m = min(cf.x, min(cf.y, cf.z));
            if (m > best) { best = m; t = f; c = cf; }
        }
    }
    c = max(c, vec3(0.0));
    float sum = c.x + c.y + c.z;
    bary = sum > 0.0 ? c / sum : vec3(1.0 / 3.0);
    return t;
}

ivec2 wrap(ivec2 t) { return ((t % u_size) + u_size) % u_size; }

// The paper's ellipse test (§4), as ellipse_visibility in core/microgeom/ellipse.cpp.
float ellipse_vis(vec4 t0, vec4 t1, vec3 w, float edge) {
    if (w.z <= 0.0) return 0.0;
    vec2 p = w.xy - t0.xy;
    vec2 uv = vec2(dot(t0.zw, p), dot(vec2(-t0.w, t0.z), p)) / t1.xy;
    float q = dot(uv, uv);
    if (edge <= 0.0) return q <= 1.0 ? 1.0 : 0.0;
    float g = 2.0 * length(uv / t1.xy);
    return clamp(0.5 - (q - 1.0) / (max(g, 1e-6) * edge), 0.0, 1.0);
}
vec3 fetch_rgb(sampler2D s, ivec2 t) { return texelFetch(s, wrap(t), 0).rgb; }

// Fraction of direction w (local) reaching texel t, given w's triangle and barycentrics.
float visible(ivec2 t, int tri, vec3 bary, vec3 w) {
    t = wrap(t);
    if (dot(texelFetch(u_normals, t, 0).xyz, w) <= 0.0) return 0.0;
    ivec4 v = tris[tri];
    float f = 0.0;
    f += bary.x * (texelFetch(u_vis, ivec3(t, v.x), 0).r == 0xFFFFFFFFu ? 1.0 : 0.0);
    f += bary.y * (texelFetch(u_vis, ivec3(t, v.y), 0).r == 0xFFFFFFFFu ? 1.0 : 0.0);
    f += bary.z * (texelFetch(u_vis, ivec3(t, v.z), 0).r == 0xFFFFFFFFu ? 1.0 : 0.0);
    return f;
}

// Light-driven irradiance per unit light irradiance from local direction w (microgeom.scatter_directions):
// the 3 corners of w's triangle, bilinear over the 4 texels, blended with the barycentrics
// (DirectionalScatter::irradiance; corners at or below the horizon hold 0).
vec3 directional_irradiance(vec3 w, ivec2 tk[4], float wk[4]) {
    vec3 bary;
    ivec4 v = tris[locate(w, bary)];
    vec3 sum = vec3(0.0);
    for (int corner = 0; corner < 3; ++corner) {
        int j = v[corner];
        if (j >= u_dir_scatters) continue;
        vec3 e = vec3(0.0);
        for (int k = 0; k < 4; ++k) e += wk[k] * texelFetch(u_E_dirs, ivec3(wrap(tk[k]), j), 0).rgb;
        sum += bary[corner] * e;
    }
    return sum;
}

// Table nodes and bilinear weights of a direction (see core/microgeom/goniometer.h).
void brdf_nodes(vec3 w, out ivec4 node, out vec4 wt) {
    int nt = u_brdf_nodes.x, np = u_brdf_nodes.y;
    float tt = clamp(acos(clamp(w.z, 0.0, 1.0)) / (0.5 * PI) * float(nt - 1), 0.0, float(nt - 1));
    int i0 = min(int(floor(tt)), nt - 2);
    float ft = tt - float(i0);
    float ph = (w.x == 0.0 && w.y == 0.0) ? 0.0 : atan(w.y, w.x) / (2.0 * PI);
    ph -= floor(ph);
    float tp = ph * float(np);
    int j0 = int(floor(tp));
    float fp = tp - float(j0);
    j0 = j0 % np;
    int j1 = (j0 + 1) % np;
    node = ivec4(i0 * np + j0, i0 * np + j1, (i0 + 1) * np + j0, (i0 + 1) * np + j1);
    wt = vec4((1.0 - ft) * (1.0 - fp), (1.0 - ft) * fp, ft * (1.0 - fp), ft * fp);
}

vec4 brdf_eval(vec3 l, vec3 v) {
    l = normalize(l);
    v = normalize(v);
    if (!(l.z > 0.0) || !(v.z > 0.0)) return vec4(0.0);
    ivec4 nl, nv;
    vec4 wl, wv;
    brdf_nodes(l, nl, wl);
    brdf_nodes(v, nv, wv);
    vec4 r = vec4(0.0);
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) r += wl[a] * wv[b] * texelFetch(u_brdf, ivec2(nv[b], nl[a]), 0);
    return r;
}

vec3 brdf_eval_env(vec3 v) {
    v = normalize(v);
    if (!(v.z > 0.0)) return vec3(0.0);
    ivec4 nv;
    vec4 wv;
    brdf_nodes(v, nv, wv);
    vec3 r = vec3(0.0);
    for (int b = 0; b < 4; ++b) r += wv[b] * texelFetch(u_brdf_env, ivec2(nv[b], 0), 0).rgb;
    return r;
}

void main() {
    vec3 p = v_position;
    vec3 wo = camera_wo(p);
    vec3 N = normalize(v_normal);
    if (dot(N, wo) < 0.0) N = -N;
    vec3 T = v_tangent - N * dot(v_tangent, N);
    T = dot(T, T) > 1e-12 ? normalize(T) : (abs(N.x) < 0.9 ? normalize(cross(N, vec3(1, 0, 0))) : normalize(cross(N, vec3(0, 1, 0))));
    vec3 B = cross(N, T);
    if (u_lod_brdf != 0) {
        vec3 v_loc = vec3(dot(wo, T), dot(wo, B), dot(wo, N));
        vec3 Lo_lights = vec3(0.0);
        float shadow_first = 0.0;
        for (int i = 0; i < u_light_count; ++i) {
            vec3 wi, E;
            light_sample(i, p, wi, E);
            vec4 f = brdf_eval(vec3(dot(wi, T), dot(wi, B), dot(wi, N)), v_loc);
            Lo_lights += f.rgb * E;
            if (i == 0) shadow_first = f.a;
        }
        vec3 Lo_env = u_env_lighting != 0 ? brdf_eval_env(v_loc) * env_irradiance(N) / PI : vec3(0.0);
        o_radiance = vec4(Lo_lights + Lo_env, 1.0);
        o_normal = vec4(N, 1.0);
        o_direct = vec4(Lo_lights, 1.0);
        o_indirect = vec4(Lo_env, 1.0);
        o_shadow = vec4(shadow_first, 0.0, 0.0, 1.0);
        o_folded = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    float tiling = u_texture_mode != 0 ? 1.0 : u_tiling;
    float c = v_uv.x * float(u_size.x) * tiling - 0.5, r = (1.0 - v_uv.y) * float(u_size.y) * tiling - 0.5;
    float c0 = floor(c), r0 = floor(r), fc = c - c0, fr = r - r0;
    ivec2 t00 = ivec2(int(c0), int(r0));
    ivec2 tk[4] = ivec2[4](t00, t00 + ivec2(1, 0), t00 + ivec2(0, 1), t00 + ivec2(1, 1));
    float wk[4] = float[4]((1.0 - fc) * (1.0 - fr), fc * (1.0 - fr), (1.0 - fc) * fr, fc * fr);

    vec3 n_loc = vec3(0.0), albedo = vec3(0.0), E_env = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
        n_loc += wk[k] * fetch_rgb(u_normals, tk[k]);
        albedo += wk[k] * fetch_rgb(u_albedo, tk[k]);
        if (u_has_env != 0) E_env += wk[k] * fetch_rgb(u_E_env, tk[k]);
    }
    n_loc = normalize(n_loc);
    vec3 n = normalize(T * n_loc.x + B * n_loc.y + N * n_loc.z);

    vec3 direct = vec3(0.0);
    float shadow0 = 0.0;
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, E;
        light_sample(i, p, wi, E);
        float cos_i = dot(n, wi);
        float V = 0.0;
        if (cos_i > 0.0) {
            if (u_shadows == 0) {
                V = 1.0;
            } else {
                vec3 l_loc = normalize(vec3(dot(wi, T), dot(wi, B), dot(wi, N)));
                if (u_use_ellipse != 0) {
                    for (int k = 0; k < 4; ++k) {
                        ivec2 t = wrap(tk[k]);
                        if (dot(texelFetch(u_normals, t, 0).xyz, l_loc) > 0.0)
                            V += wk[k] * ellipse_vis(texelFetch(u_ellipse0, t, 0), texelFetch(u_ellipse1, t, 0), l_loc, u_ellipse_edge);
                    }
                } else {
                    vec3 bary;
                    int tri = locate(l_loc, bary);
                    for (int k = 0; k < 4; ++k) V += wk[k] * visible(tk[k], tri, bary, l_loc);
                }
            }
        }
        if (i == 0) shadow0 = V;
        if (cos_i <= 0.0 || V <= 0.0) continue;
        vec3 f = albedo / PI;
        if (u_phong != 0) {
            vec3 h = normalize(wo + wi);
            f += u_ks * (u_shininess + 8.0) / (8.0 * PI) * pow(max(0.0, dot(n, h)), u_shininess);
        }
        direct += f * E * cos_i * V;
    }

    vec3 E_ind = E_env;
    for (int i = 0; i < u_light_scatters; ++i) {
        vec3 wi, E;
        light_sample(i, p, wi, E);
        vec3 E_light = vec3(0.0);
        for (int k = 0; k < 4; ++k) E_light += wk[k] * texelFetch(u_E_light, wrap(tk[k]) + ivec2(0, i * u_size.y), 0).rgb;
        E_ind += E_light * E;
    }
    for (int i = 0; u_dir_scatters > 0 && i < u_light_count; ++i) {
        vec3 wi, E;
        light_sample(i, p, wi, E);
        E_ind += directional_irradiance(normalize(vec3(dot(wi, T), dot(wi, B), dot(wi, N))), tk, wk) * E;
    }
    vec3 indirect = albedo / PI * E_ind;
    o_radiance = vec4(direct + indirect, 1.0);
    o_normal = vec4(n, 1.0);
    o_direct = vec4(direct, 1.0);
    o_indirect = vec4(indirect, 1.0);
    o_shadow = vec4(shadow0, 0.0, 0.0, 1.0);
    float folded = u_has_folded != 0 ? texelFetch(u_folded, wrap(ivec2(int(floor(c + 0.5)), int(floor(r + 0.5)))), 0).r : 0.0;
    o_folded = vec4(folded, 0.0, 0.0, 1.0);
}
