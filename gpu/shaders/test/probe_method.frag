#version 430 core
// Test method `microgeom/flat-probe`: radiance = gain * the heightfield's first texel's albedo / pi * E,
// with E the first light's irradiance on the macro normal (the CPU side: tests/passes/probe_method.cpp).
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"
in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;
uniform vec3 u_albedo;
void main() {
    vec3 n = normalize(v_normal);
    if (dot(n, camera_wo(v_position)) < 0.0) n = -n;
    vec3 L = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, E;
        light_sample(i, v_position, wi, E);
        L += u_albedo * INV_PI * E * max(dot(n, wi), 0.0);
    }
    o_radiance = vec4(L, 1.0);
    o_normal = vec4(n, 1.0);
    o_direct = vec4(L, 1.0);
    o_indirect = vec4(0.0, 0.0, 0.0, 1.0);
    o_shadow = vec4(1.0, 0.0, 0.0, 1.0);
    o_folded = vec4(0.0, 0.0, 0.0, 1.0);
}
