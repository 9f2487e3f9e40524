#version 430 core
// Test technique `probe`: radiance = kd / pi * the blurred illumination map at the pixel's texel.
#include "common.glsl"
#include "camera.glsl"
in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec2 v_uv;
uniform sampler2D u_map;  // GL row 0 = v near 0
uniform vec3 u_kd;
void main() {
    ivec2 size = textureSize(u_map, 0);
    ivec2 t = clamp(ivec2(floor(v_uv * vec2(size))), ivec2(0), size - 1);
    vec3 E = texelFetch(u_map, t, 0).rgb;
    vec3 n = normalize(v_normal);
    if (dot(n, camera_wo(v_position)) < 0.0) n = -n;
    o_radiance = vec4(u_kd / PI * E, 1.0);
    o_normal = vec4(n, 1.0);
    o_texel = vec4(vec2(t), 0.0, 1.0);
}
