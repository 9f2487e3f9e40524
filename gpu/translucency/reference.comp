#version 430 core
// Technique translucency, step translucency.reference: the brute-force radiosity (core/translucency/
// reference.cpp): every lit inner texel's power times R_d (the same table) at every inner texel,
// never nearer than the source's disk radius, the texel itself as a disk; written filled (fill
// source) into an image.
#include "translucency.glsl"
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Fill { int fill[]; };
layout(std430, binding = 1) readonly buffer Sources { vec4 src[]; };    // 2 per lit inner texel: position (mm) and ρ² (mm², local.h), power
layout(std430, binding = 2) readonly buffer Position { vec4 x[]; };     // per texel, mm; w = 1 for inner texels
layout(std430, binding = 3) readonly buffer Self { vec4 self_w[]; };    // per texel: the disk term's weight
layout(std430, binding = 4) readonly buffer Irradiance { vec4 E[]; };
layout(std430, binding = 5) readonly buffer Table { vec4 Rd[]; };       // RdTable samples
layout(rgba32f, binding = 0) writeonly uniform image2D u_reference;
uniform int u_size;
uniform int u_sources;
uniform int u_table_n;
uniform float u_inv_r_max;
uniform float u_r_max2;

vec3 rd_at_r2(float r2) {
    float q = sqrt(sqrt(r2) * u_inv_r_max) * float(u_table_n - 1);
    if (!(q < float(u_table_n - 1))) return r2 <= u_r_max2 ? Rd[u_table_n - 1].rgb : vec3(0.0);
    int i = int(q);
    float f = q - float(i);
    return Rd[i].rgb * (1.0 - f) + Rd[i + 1].rgb * f;
}

void main() {
    int t = int(gl_GlobalInvocationID.x);
    if (t >= u_size * u_size) return;
    int s = fill[t] >= 0 ? fill[t] : t;
    vec3 b = vec3(0.0);
    if (x[s].w > 0.0) {
        vec3 xs = x[s].xyz;
        for (int k = 0; k < u_sources; ++k) {
            vec3 d = src[2 * k].xyz - xs;
            b += rd_at_r2(max(dot(d, d), src[2 * k].w)) * src[2 * k + 1].rgb;
        }
        b += self_w[s].rgb * E[s].rgb;
    }
    imageStore(u_reference, ivec2(t % u_size, t / u_size), vec4(b, 1.0));
}
