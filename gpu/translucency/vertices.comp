#version 430 core
// Technique translucency, step translucency.vertices: E_j and B_D,j per vertex from the gather
// table (core/translucency/frame.cpp gather_vertices); E_j leaves scaled for the global step.
#include "translucency.glsl"
layout(local_size_x = 64) in;

uniform isamplerBuffer u_start;
uniform isamplerBuffer u_texel;
uniform samplerBuffer u_w;
uniform samplerBuffer u_E;        // irradiance per texel
// E'_j = E_j A_j / 3 x scale: the global step's factors are R_d / scale (VertexFactors::weight).
uniform samplerBuffer u_weight;
layout(std430, binding = 4) writeonly buffer VertexE { vec4 Ev[]; };
layout(std430, binding = 5) writeonly buffer VertexD { vec4 D[]; };
uniform int u_count;

void main() {
    int v = int(gl_GlobalInvocationID.x);
    if (v >= u_count) return;
    vec3 e = vec3(0.0), d = vec3(0.0);
    int k1 = texelFetch(u_start, v + 1).x;
    for (int k = texelFetch(u_start, v).x; k < k1; ++k) {
        vec3 Et = texelFetch(u_E, texelFetch(u_texel, k).x).rgb;
        vec4 w = texelFetch(u_w, k);
        e += w.x * Et;
        d += w.yzw * Et;
    }
    Ev[v] = vec4(e * texelFetch(u_weight, v).rgb, 0.0);
    D[v] = vec4(d, 0.0);
}
