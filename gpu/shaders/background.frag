#version 430 core
// The environment seen through each pixel (orbit mode), written to the radiance AOV.
#include "common.glsl"
#include "lighting.glsl"
in vec2 v_ndc;
uniform mat4 u_inv_view_proj;
layout(location = 0) out vec4 o_radiance;
void main() {
    vec4 a = u_inv_view_proj * vec4(v_ndc, -1.0, 1.0);
    vec4 b = u_inv_view_proj * vec4(v_ndc, 1.0, 1.0);
    vec3 dir = normalize(b.xyz / b.w - a.xyz / a.w);
    o_radiance = vec4(env_radiance(dir), 1.0);
}
