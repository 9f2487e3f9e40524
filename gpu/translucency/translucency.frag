#version 430 core
// Technique translucency: display, L_o = rho T(cos theta_o) B / pi (core/translucency/technique.cpp shade_cpu).
#include "common.glsl"
#include "camera.glsl"
#include "translucency.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform sampler2D u_irradiance;
uniform sampler2D u_local;
uniform sampler2D u_global;
uniform sampler2D u_reference;
uniform sampler2D u_rho;
uniform int u_has_rho;
uniform int u_has_reference;
uniform int u_response;  // 0 both, 1 local, 2 global, 3 reference
uniform float u_eta;

// Fragment outputs o_<aov> are generated from the technique's declaration (gpu/renderer.h).

void main() {
    vec3 p = v_position;
    vec3 wo = camera_wo(p);
    vec3 n = normalize(v_normal);
    if (dot(n, wo) < 0.0) n = -n;
    vec2 st = vec2(v_uv.x, 1.0 - v_uv.y);  // texel row y at t = (y + 0.5) / size
    vec3 l = texture(u_local, st).rgb, g = texture(u_global, st).rgb;
    vec3 ref = u_has_reference != 0 ? texture(u_reference, st).rgb : vec3(0.0);
    vec3 B = u_response == 1 ? l : u_response == 2 ? g : u_response == 3 ? ref : l + g;
    vec3 rho = u_has_rho != 0 ? texture(u_rho, st).rgb : vec3(1.0);
    float T = fresnel_transmittance(clamp(dot(n, wo), 0.0, 1.0), u_eta);
    o_radiance = vec4(rho * B * (T * INV_PI), 1.0);
    o_normal = vec4(n, 1.0);
    o_irradiance = vec4(texture(u_irradiance, st).rgb, 1.0);
    o_radiosity = vec4(l + g, 1.0);
    o_local = vec4(l, 1.0);
    o_global = vec4(g, 1.0);
    o_reference = vec4(ref, 1.0);
    o_error = vec4(u_has_reference != 0 ? l + g - ref : vec3(0.0), 1.0);
}
