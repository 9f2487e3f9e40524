#version 430 core
// Technique translucency, step translucency.local: B_local per inner texel, K x K kernels
// (core/translucency/local.cpp convolve_local).
#include "translucency.glsl"
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Texel { int texel[]; };      // inner texels
layout(std430, binding = 1) readonly buffer Weights { vec4 w[]; };       // K² per texel, RGB
layout(std430, binding = 2) readonly buffer Irradiance { vec4 E[]; };
layout(std430, binding = 3) writeonly buffer Local { vec4 B[]; };       // per texel
uniform int u_count;
uniform int u_K;
uniform int u_size;

void main() {
    int k = int(gl_GlobalInvocationID.x);
    if (k >= u_count) return;
    int t = texel[k];
    int x = t % u_size, y = t / u_size, h = (u_K - 1) / 2;
    int base = k * u_K * u_K;
    vec3 b = vec3(0.0);
    for (int dy = -h; dy <= h; ++dy)
        for (int dx = -h; dx <= h; ++dx) {
            int q = (y + dy) * u_size + (x + dx);
            int i = base + (dy + h) * u_K + (dx + h);
            b += w[i].rgb * E[q].rgb;
        }
    B[t] = vec4(b, 0.0);
}
