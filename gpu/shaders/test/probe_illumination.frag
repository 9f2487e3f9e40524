#version 430 core
// Test technique `probe`, frame step probe.illumination: the irradiance from the lights at each
// texel of the object's (u,v) square (drawn in texture space), as ProbeTechnique::run_step_cpu.
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"
in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;
layout(location = 0) out vec4 o_irradiance;
void main() {
    vec3 n = normalize(v_normal);
    vec3 E = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, Ei;
        light_sample(i, v_position, wi, Ei);
        E += Ei * max(0.0, dot(n, wi));
    }
    o_irradiance = vec4(E, 1.0);
}
