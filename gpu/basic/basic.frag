#version 430 core
// Technique basic: Lambert + energy-normalised Blinn-Phong (see core/basic/basic.h).
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform vec3 u_kd;
uniform vec3 u_ks;
uniform float u_shininess;
uniform int u_has_albedo;
uniform sampler2D u_albedo;  // top row at t = 0: sampled at (u, 1 - v)

// Fragment outputs o_<aov> (radiance, normal, then the technique's AOVs) are generated from the
// technique's declaration (gpu/renderer.h fragment_outputs) and inserted after #version.

void main() {
    vec3 p = v_position;
    vec3 wo = camera_wo(p);
    vec3 n = normalize(v_normal);
    if (dot(n, wo) < 0.0) n = -n;  // two-sided
    vec3 tex = u_has_albedo != 0 ? texture(u_albedo, vec2(v_uv.x, 1.0 - v_uv.y)).rgb : vec3(1.0);
    vec3 L = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, E;
        light_sample(i, p, wi, E);
        float cos_i = dot(n, wi);
        if (cos_i <= 0.0) continue;
        vec3 h = normalize(wo + wi);
        float spec = (u_shininess + 8.0) / (8.0 * PI) * pow(max(0.0, dot(n, h)), u_shininess);
        L += (u_kd * tex / PI + u_ks * spec) * E * cos_i;
    }
    L += u_kd * tex / PI * env_irradiance(n);
    o_radiance = vec4(L, 1.0);
    o_normal = vec4(n, 1.0);
}
