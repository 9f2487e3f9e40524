#version 430 core
// Technique translucency, step translucency.vertices: E_j and B_D,j per vertex from the gather
// table (core/translucency/frame.cpp gather_vertices); E_j leaves scaled for the global step.
#include "translucency.glsl"
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Start { int start[]; };
layout(std430, binding = 1) readonly buffer Texel { int texel[]; };
layout(std430, binding = 2) readonly buffer Weight { vec4 w[]; };
layout(std430, binding = 3) readonly buffer Irradiance { vec4 E[]; };
layout(std430, binding = 4) writeonly buffer VertexE { vec4 Ev[]; };
layout(std430, binding = 5) writeonly buffer VertexD { vec4 D[]; };
// E'_j = E_j A_j / 3 x scale: the global step's factors are R_d / scale (VertexFactors::weight).
layout(std430, binding = 6) readonly buffer VertexWeight { vec4 Wt[]; };
uniform int u_count;

void main() {
    int v = int(gl_GlobalInvocationID.x);
    if (v >= u_count) return;
    vec3 e = vec3(0.0), d = vec3(0.0);
    for (int k = start[v]; k < start[v + 1]; ++k) {
        vec3 Et = E[texel[k]].rgb;
        e += w[k].x * Et;
        d += w[k].yzw * Et;
    }
    Ev[v] = vec4(e * Wt[v].rgb, 0.0);
    D[v] = vec4(d, 0.0);
}
