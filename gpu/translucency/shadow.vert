#version 430 core
// Technique translucency: a shadow map's geometry pass (see core/translucency/translucency.h ShadowMap).
layout(location = 0) in vec3 a_position;
uniform mat4 u_model;
uniform mat4 u_view_proj;
out vec3 v_world;
void main() {
    vec4 wp = u_model * vec4(a_position, 1.0);
    v_world = wp.xyz;
    gl_Position = u_view_proj * wp;
}
