#version 430 core
// Technique translucency, step translucency.global: B_i = sum_j F_ij E_j + B_D,i for the rows
// [u_row0, u_row1) over the factors' complete rows (core/translucency/global.cpp
// expand_directed, multiply_directed), each padded to an even length. Ev holds E_j A_j / 3 x
// scale (vertices.comp), so an entry is R_d / scale. Entries and Ev are read through buffer
// textures, a texel holding two entries; the piece's texels start at pair u_base.
#include "translucency.glsl"
// LANES invocations share a row, ROWS rows a work group, chosen per renderer
// (translucency_pass.cpp, gpu/gl.h tuned_for_hardware): the invocations that run in step read
// neighbouring texels and loop as long as each other.
// - llvmpipe (the defaults): 8 lanes, each reading two texels per step (k and k + 8), 8 rows:
//   one SIMD vector a row, and no bounds test (rows are a multiple of 16 texels).
// - A hardware GPU (LANES 32, ROWS 2): a warp a row, one texel per lane and step, so that a row's
//   32 lanes read 512 contiguous bytes at once, and 32 invocations a row (the bunny: 320,000) to
//   keep enough reads in flight for the memory's bandwidth (8 a row fill a third of an H100).
#ifndef LANES
#define LANES 8
#endif
#ifndef ROWS
#define ROWS 8
#endif
layout(local_size_x = LANES, local_size_y = ROWS) in;

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

shared vec3 partial[ROWS][LANES];

int column(uint low, int k, bool high_half) {
    int j = int(low >> 16u);
#ifdef WIDE_COLUMNS
    uint h = texelFetch(u_col_hi, k).x;
    j |= int(high_half ? h >> 16u : h & 0xffffu) << 16;
#endif
    return j;
}

void main() {
    int lane = int(gl_LocalInvocationID.x), r = int(gl_LocalInvocationID.y);
    int i = u_row0 + int(gl_WorkGroupID.x) * ROWS + r;
    vec3 b = vec3(0.0);
    if (i < u_row1) {
        int k1 = (outer[i + 1] >> 1) - u_base;
#if LANES == 8
        // Rows hold a multiple of 16 texels (core/translucency/gpu_layout.h kRowQuantum).
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
#else
        for (int k = (outer[i] >> 1) - u_base + lane; k < k1; k += LANES) {
            uvec4 p = imageLoad(u_entry, k);
            b += vec3(unpackHalf2x16(p.x), unpackHalf2x16(p.y).x) * imageLoad(u_Ev, column(p.y, k, false)).rgb;
            b += vec3(unpackHalf2x16(p.z), unpackHalf2x16(p.w).x) * imageLoad(u_Ev, column(p.w, k, true)).rgb;
        }
#endif
    }
    partial[r][lane] = b;
    barrier();
    if (lane != 0 || i >= u_row1) return;
    for (int l = 1; l < LANES; ++l) b += partial[r][l];
    Bv[i] = vec4(b + D[i].rgb, 0.0);
}
