#version 430 core
// Technique translucency, step translucency.global: B_i = sum_j F_ij E_j + B_D,i for the rows
// [u_row0, u_row1) (core/translucency/global.cpp VertexFactors::multiply). The entries are bound
// from entry u_base on, so that buffers above the GL's storage block size go in pieces.
#include "translucency.glsl"
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Outer { int outer[]; };
// One 16-byte entry per factor: (column as int bits, R, G, B): a single load each.
layout(std430, binding = 1) readonly buffer Entries { vec4 entry[]; };
layout(std430, binding = 5) readonly buffer VertexE { vec4 Ev[]; };
layout(std430, binding = 6) readonly buffer VertexD { vec4 D[]; };
layout(std430, binding = 7) writeonly buffer VertexB { vec4 Bv[]; };
uniform int u_row0;
uniform int u_row1;
uniform int u_base;

void main() {
    int i = u_row0 + int(gl_GlobalInvocationID.x);
    if (i >= u_row1) return;
    vec3 b = vec3(0.0);
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
        vec4 e = entry[k - u_base];
        b += e.yzw * Ev[floatBitsToInt(e.x)].rgb;
    }
    Bv[i] = vec4(b + D[i].rgb, 0.0);
}
