#version 430 core
// Technique translucency: display, L_o = rho T(cos theta_o) B / pi (core/translucency/technique.cpp shade_cpu).
// One variant per set of maps the frame reads (translucency_pass.cpp): the radiance samples the
// displayed response's map alone; the other maps are sampled only where their AOV is in the frame.
#include "common.glsl"
#include "camera.glsl"
#include "translucency.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;

uniform sampler2D u_B;            // the displayed response: radiosity, local, global or reference
uniform sampler2D u_irradiance;
uniform sampler2D u_local;
uniform sampler2D u_global;
uniform sampler2D u_radiosity;    // local + global
uniform sampler2D u_reference;
uniform sampler2D u_rho;
uniform float u_eta;
uniform float u_t_mean;           // the hemispherical mean of T: exitance = B t_mean (dipole.h diffuse_transmittance)

// Fragment outputs o_<aov> are generated from the technique's declaration (gpu/renderer.h).

void main() {
    vec3 p = v_position;
    vec3 wo = camera_wo(p);
    vec3 n = normalize(v_normal);
    if (dot(n, wo) < 0.0) n = -n;
    vec2 st = vec2(v_uv.x, 1.0 - v_uv.y);  // texel row y at t = (y + 0.5) / size
    vec3 B = texture(u_B, st).rgb;
#ifdef HAS_RHO
    vec3 rho = texture(u_rho, st).rgb;
#else
    vec3 rho = vec3(1.0);
#endif
    float T = fresnel_transmittance(clamp(dot(n, wo), 0.0, 1.0), u_eta);
    o_radiance = vec4(rho * B * (T * INV_PI), 1.0);
    o_normal = vec4(n, 1.0);
    o_exitance = vec4(B * u_t_mean, 1.0);
#ifdef NEED_IRRADIANCE
    o_irradiance = vec4(texture(u_irradiance, st).rgb, 1.0);
#else
    o_irradiance = vec4(0.0);
#endif
#ifdef NEED_PARTS
    o_local = vec4(texture(u_local, st).rgb, 1.0);
    o_global = vec4(texture(u_global, st).rgb, 1.0);
#else
    o_local = vec4(0.0);
    o_global = vec4(0.0);
#endif
#ifdef NEED_RADIOSITY
    vec3 radiosity = texture(u_radiosity, st).rgb;
#else
    vec3 radiosity = vec3(0.0);
#endif
    o_radiosity = vec4(radiosity, 1.0);
#ifdef NEED_REFERENCE
    vec3 ref = texture(u_reference, st).rgb;
    o_reference = vec4(ref, 1.0);
    o_error = vec4(radiosity - ref, 1.0);
#else
    o_reference = vec4(0.0, 0.0, 0.0, 1.0);
    o_error = vec4(0.0, 0.0, 0.0, 1.0);
#endif
}
