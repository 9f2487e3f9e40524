#version 430 core
// Method separable of technique translucency, before the blur: the irradiance entering the medium
// at the pixel's surface point, its view depth and the size of a pixel there (mm), and its object
// (core/translucency/separable.cpp; entering_irradiance in core/translucency/illumination.cpp).
#include "common.glsl"
#include "camera.glsl"
#include "lighting.glsl"
#include "translucency.glsl"
#include "shadow.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform float u_eta;
uniform float u_env_transmittance;  // the hemispherical mean of T
uniform float u_mm_per_world;
uniform float u_object;
uniform mat4 u_view;
uniform float u_proj11;             // the projection's [1][1]: 1 / tan(fov_y / 2)
uniform float u_height;             // the frame's height in pixels

layout(location = 0) out vec4 o_E;
layout(location = 1) out vec4 o_G;  // view depth (mm), pixel size (mm), object

void main() {
    vec3 p = v_position;
    vec3 n = normalize(v_normal);
    vec3 e = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 wi, El;
        light_sample(i, p, wi, El);
        float c = dot(n, wi);
        if (c <= 0.0) continue;
        e += El * (c * fresnel_transmittance(c, u_eta) * visibility(i, p));
    }
    e += env_irradiance(n) * u_env_transmittance;
    float z = -(u_view * vec4(p, 1.0)).z;
    o_E = vec4(e, 1.0);
    o_G = vec4(z * u_mm_per_world, 2.0 * z / (u_proj11 * u_height) * u_mm_per_world, u_object, 1.0);
}
