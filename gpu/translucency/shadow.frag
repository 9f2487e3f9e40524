#version 430 core
// Technique translucency: the distance of the nearest surface from the light (ShadowMap::distance).
in vec3 v_world;
uniform int u_point;
uniform vec3 u_origin;
uniform vec3 u_dir;
layout(location = 0) out vec4 o_distance;
void main() {
    float d = u_point != 0 ? length(v_world - u_origin) : dot(v_world - u_origin, u_dir);
    o_distance = vec4(d, 0.0, 0.0, 1.0);
}
