#version 430 core
// Method separable of technique translucency: display, L_o = T(cos theta_o) B / pi with B the
// blurred irradiance at this pixel (core/translucency/separable.cpp shade_cpu is the CPU twin).
#include "common.glsl"
#include "camera.glsl"
#include "translucency.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform sampler2D u_B;   // after both blurs, at the frame's pixels
uniform sampler2D u_E;   // the irradiance before them
uniform float u_eta;
uniform float u_t_mean;  // the hemispherical mean of T: exitance = B t_mean

// Fragment outputs o_<aov> are generated from the technique's declaration (gpu/renderer.h).

void main() {
    ivec2 q = ivec2(gl_FragCoord.xy);
    vec3 B = texelFetch(u_B, q, 0).rgb;
    vec3 wo = camera_wo(v_position);
    vec3 n = normalize(v_normal);
    if (dot(n, wo) < 0.0) n = -n;
    float T = fresnel_transmittance(clamp(dot(n, wo), 0.0, 1.0), u_eta);
    o_radiance = vec4(B * (T * INV_PI), 1.0);
    o_normal = vec4(n, 1.0);
    o_irradiance = vec4(texelFetch(u_E, q, 0).rgb, 1.0);
    o_radiosity = vec4(B, 1.0);
    o_local = vec4(B, 1.0);
    o_global = vec4(0.0, 0.0, 0.0, 1.0);
    o_reference = vec4(0.0, 0.0, 0.0, 1.0);
    o_error = vec4(0.0, 0.0, 0.0, 1.0);
    o_exitance = vec4(B * u_t_mean, 1.0);
}
