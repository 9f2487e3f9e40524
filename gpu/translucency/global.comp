#version 430 core
// Technique translucency, step translucency.global: B_i = sum_j F_ij E_j + B_D,i for the rows
// [u_row0, u_row1) over the factors' complete rows (core/translucency/global.cpp
// expand_directed, multiply_directed). Ev holds E_j A_j / 3 x scale (vertices.comp), so an
// entry is R_d / scale. The entries are bound from entry u_base on, so that buffers above the
// GL's storage block size go in pieces.
#include "translucency.glsl"
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Outer { int outer[]; };
// One 8-byte entry per factor: R and G as halves; B as a half and the column's low 16 bits.
layout(std430, binding = 1) readonly buffer Entries { uvec2 entry[]; };
// With more than 65,536 vertices: the column's high 16 bits, two entries per uint.
layout(std430, binding = 2) readonly buffer ColHi { uint col_hi[]; };
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
    for (int k = outer[i] - u_base; k < outer[i + 1] - u_base; ++k) {
        uvec2 p = entry[k];
        int j = int(p.y >> 16u);
#ifdef WIDE_COLUMNS
        j |= int((col_hi[k >> 1] >> (uint(k & 1) * 16u)) & 0xffffu) << 16;
#endif
        b += vec3(unpackHalf2x16(p.x), unpackHalf2x16(p.y).x) * Ev[j].rgb;
    }
    Bv[i] = vec4(b + D[i].rgb, 0.0);
}
