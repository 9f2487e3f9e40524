#version 430 core
// Method horizon of technique microgeom: horizon mapping with GTAO's multi-bounce ambient
// visibility, the GLSL twin of HorizonMethod::shade_cpu and HorizonMap (core/microgeom/horizon.{h,cpp},
// where the maths is explained). The map, normals and albedo are texelFetch'd with the CPU's weights.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform sampler2DArray u_horizon;  // microgeom.horizon_map: sin θ_j, one layer per azimuth
uniform sampler2D u_normals;       // heightfield normals (local frame), rgb
uniform sampler2D u_albedo;
uniform ivec2 u_size;              // heightfield texels
uniform int u_directions;
uniform float u_tiling;
uniform int u_phong;
uniform vec3 u_ks;
uniform float u_shininess;

ivec2 wrap(ivec2 t) { return ((t % u_size) + u_size) % u_size; }

float sin_at(int j, ivec2 t) { return texelFetch(u_horizon, ivec3(wrap(t), j), 0).r; }

// HorizonMap::sin_horizon
float sin_horizon(float c, float r, float phi) {
    float a = phi / (2.0 * PI) * float(u_directions);
    float af = floor(a);
    float t = a - af;
    int j0 = ((int(af) % u_directions) + u_directions) % u_directions, j1 = (j0 + 1) % u_directions;
    float cf = floor(c), rf = floor(r), fc = c - cf, fr = r - rf;
    ivec2 t00 = ivec2(int(cf), int(rf));
    float h[2];
    for (int k = 0; k < 2; ++k) {
        int j = k == 0 ? j0 : j1;
        float top = sin_at(j, t00) + fc * (sin_at(j, t00 + ivec2(1, 0)) - sin_at(j, t00));
        float bot = sin_at(j, t00 + ivec2(0, 1)) + fc * (sin_at(j, t00 + ivec2(1, 1)) - sin_at(j, t00 + ivec2(0, 1)));
        h[k] = top + fr * (bot - top);
    }
    return h[0] + t * (h[1] - h[0]);
}

float occ(ivec2 t) {
    float s = 0.0;
    for (int j = 0; j < u_directions; ++j) {
        float v = max(0.0, sin_at(j, t));
        s += v * v;
    }
    return 1.0 - s / float(u_directions);
}

// HorizonMap::ambient
float ambient(float c, float r) {
    float cf = floor(c), rf = floor(r), fc = c - cf, fr = r - rf;
    ivec2 t00 = ivec2(int(cf), int(rf));
    float o00 = occ(t00), o10 = occ(t00 + ivec2(1, 0)), o01 = occ(t00 + ivec2(0, 1)), o11 = occ(t00 + ivec2(1, 1));
    float top = o00 + fc * (o10 - o00), bot = o01 + fc * (o11 - o01);
    return top + fr * (bot - top);
}

// gtao_multibounce, per channel
vec3 multibounce(float A, vec3 rho) {
    vec3 a = 2.0404 * rho - 0.3324, b = -4.7951 * rho + 0.6417, c = 2.7552 * rho + 0.6903;
    return max(vec3(A), ((a * A + b) * A + c) * A);
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
    float c = v_uv.x * float(u_size.x) * tiling - 0.5, r = (1.0 - v_uv.y) * float(u_size.y) * tiling - 0.5;

    float cf = floor(c), rf = floor(r), fc = c - cf, fr = r - rf;
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
        vec3 l = normalize(vec3(dot(wi, T), dot(wi, B), dot(wi, N)));
        float V = 0.0;
        if (cos_i > 0.0 && l.z > 0.0) {
            float phi = atan(l.y, l.x);
            if (phi < 0.0) phi += 2.0 * PI;
            V = l.z > sin_horizon(c, r, phi) ? 1.0 : 0.0;
        }
        if (i == 0) shadow0 = V;
        if (cos_i <= 0.0 || V <= 0.0) continue;
        vec3 f = albedo * INV_PI;
        if (u_phong != 0) {
            vec3 h = normalize(wo + wi);
            f += u_ks * (u_shininess + 8.0) / (8.0 * PI) * pow(max(0.0, dot(n, h)), u_shininess);
        }
        direct += f * E * cos_i;
    }
    vec3 env = albedo * INV_PI * env_irradiance(n) * multibounce(ambient(c, r), albedo);
    o_radiance = vec4(direct + env, 1.0);
    o_normal = vec4(n, 1.0);
    o_direct = vec4(direct, 1.0);
    o_indirect = vec4(env, 1.0);
    o_shadow = vec4(shadow0, 0.0, 0.0, 1.0);
    o_folded = vec4(0.0, 0.0, 0.0, 1.0);
}
