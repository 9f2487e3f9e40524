#version 430 core
// Technique translucency, step translucency.illumination: irradiance entering the medium per
// lit texel, written also to the border texels that copy it (AtlasStage::copy; core/translucency/frame.cpp
// illuminate).
#include "common.glsl"
#include "lighting.glsl"
#include "translucency.glsl"
#include "shadow.glsl"
layout(local_size_x = 64) in;

uniform isamplerBuffer u_lit;       // AtlasStage::lit
uniform samplerBuffer u_position;   // per lit texel, object space
uniform samplerBuffer u_normal;
uniform isamplerBuffer u_copy_start;   // per lit texel: its copies' range in u_copy_target
uniform isamplerBuffer u_copy_target;
layout(std430, binding = 3) writeonly buffer Irradiance { vec4 E[]; };             // per texel

uniform int u_count;
uniform mat4 u_model;
uniform mat3 u_normal_matrix;
uniform float u_eta;
uniform float u_env_transmittance;  // 1 - F_dr(eta)
void main() {
    int k = int(gl_GlobalInvocationID.x);
    if (k >= u_count) return;
    vec3 p = (u_model * vec4(texelFetch(u_position, k).xyz, 1.0)).xyz;
    vec3 n = normalize(u_normal_matrix * texelFetch(u_normal, k).xyz);
    vec3 e = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, El;
        light_sample(i, p, wi, El);
        float c = dot(n, wi);
        if (c <= 0.0) continue;
        e += El * (c * fresnel_transmittance(c, u_eta) * visibility(i, p));
    }
    e += env_irradiance(n) * u_env_transmittance;
    E[texelFetch(u_lit, k).x] = vec4(e, 0.0);
    int m1 = texelFetch(u_copy_start, k + 1).x;
    for (int m = texelFetch(u_copy_start, k).x; m < m1; ++m) E[texelFetch(u_copy_target, m).x] = vec4(e, 0.0);
}
