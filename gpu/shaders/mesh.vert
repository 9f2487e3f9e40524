#version 430 core
// Vertex shader shared by the techniques' mesh passes.
#include "common.glsl"
#include "camera.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_tangent;
layout(location = 3) in vec2 a_uv;

out vec3 v_position;
out vec3 v_normal;
out vec3 v_tangent;
out vec2 v_uv;

invariant gl_Position;  // the same depth in every pass that draws a mesh (bumpsynth: depth pre-pass, then shading with GL_LEQUAL)

void main() {
    vec4 wp = u_model * vec4(a_position, 1.0);
    v_position = wp.xyz;
    v_normal = u_normal_matrix * a_normal;
    v_tangent = mat3(u_model) * a_tangent;
    v_uv = a_uv;
    gl_Position = u_texture_mode != 0 ? vec4(a_uv * 2.0 - 1.0, 0.0, 1.0) : u_view_proj * wp;
}
