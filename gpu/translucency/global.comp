#version 430 core
// Technique translucency, step translucency.global: B_i = sum_j F_ij E_j + B_D,i for the rows
// [u_row0, u_row1) over the factors' complete rows (core/translucency/global.cpp
// expand_directed, multiply_directed), each padded to an even length. Ev holds E_j A_j / 3 x
// scale (vertices.comp), so an entry is R_d / scale. Entries and Ev are read through buffer
// textures, a texel holding two entries; the piece's texels start at pair u_base.
#include "translucency.glsl"
// Eight invocations share a row (x: every eighth pair), eight rows a work group (y): the
// invocations that run in step read neighbouring texels and loop as long as each other.
layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) readonly buffer Outer { int outer[]; };
// Two 8-byte entries per texel, each: R and G as halves; B as a half and the column's low 16 bits.
layout(rgba32ui, binding = 0) readonly uniform uimageBuffer u_entry;
// With more than 65,536 vertices: the columns' high 16 bits, one texel per pair.
uniform usamplerBuffer u_col_hi;
layout(rgba32f, binding = 1) readonly uniform imageBuffer u_Ev;
layout(std430, binding = 6) readonly buffer VertexD { vec4 D[]; };
layout(std430, binding = 7) writeonly buffer VertexB { vec4 Bv[]; };
uniform int u_row0;
uniform int u_row1;
uniform int u_base;

shared vec3 partial[8][8];

void main() {
    int lane = int(gl_LocalInvocationID.x), r = int(gl_LocalInvocationID.y);
    int i = u_row0 + int(gl_WorkGroupID.x) * 8 + r;
    vec3 b = vec3(0.0);
    if (i < u_row1) {
        int k1 = (outer[i + 1] >> 1) - u_base;
        // Rows hold a multiple of 16 texels (translucency_pass.cpp kRowQuantum).
        for (int k = (outer[i] >> 1) - u_base + lane; k < k1; k += 16) {
            uvec4 p = imageLoad(u_entry, k), q = imageLoad(u_entry, k + 8);
            int j0 = int(p.y >> 16u), j1 = int(p.w >> 16u), j2 = int(q.y >> 16u), j3 = int(q.w >> 16u);
#ifdef WIDE_COLUMNS
            uint hp = texelFetch(u_col_hi, k).x, hq = texelFetch(u_col_hi, k + 8).x;
            j0 |= int(hp & 0xffffu) << 16;
            j1 |= int(hp >> 16u) << 16;
            j2 |= int(hq & 0xffffu) << 16;
            j3 |= int(hq >> 16u) << 16;
#endif
            b += vec3(unpackHalf2x16(p.x), unpackHalf2x16(p.y).x) * imageLoad(u_Ev, j0).rgb;
            b += vec3(unpackHalf2x16(p.z), unpackHalf2x16(p.w).x) * imageLoad(u_Ev, j1).rgb;
            b += vec3(unpackHalf2x16(q.x), unpackHalf2x16(q.y).x) * imageLoad(u_Ev, j2).rgb;
            b += vec3(unpackHalf2x16(q.z), unpackHalf2x16(q.w).x) * imageLoad(u_Ev, j3).rgb;
        }
    }
    partial[r][lane] = b;
    barrier();
    if (lane != 0 || i >= u_row1) return;
    for (int l = 1; l < 8; ++l) b += partial[r][l];
    Bv[i] = vec4(b + D[i].rgb, 0.0);
}
