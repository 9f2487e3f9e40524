#version 430 core
// Technique translucency, step translucency.local: B_local per inner texel, K x K kernels
// (core/translucency/local.cpp convolve_local). Tables are read through buffer textures.
// The weights' layout is chosen per renderer (translucency_pass.cpp, gpu/gl.h tuned_for_hardware):
// - llvmpipe: kernel by kernel ([texel][tap]), each invocation reading its own K² in a row
//   (4.4–5.4 ms tap by tap against 3.8 ms here, bunny 10,000 vertices, 512² atlas, K = 7);
// - a hardware GPU (TAP_MAJOR): tap by tap ([tap][texel]), so that a warp's 32 invocations read
//   one tap of 32 neighbouring kernels, 512 contiguous bytes, at each step.
#include "translucency.glsl"
layout(local_size_x = 64) in;

uniform isamplerBuffer u_texel;    // inner texels
uniform samplerBuffer u_w;         // K² per texel, RGB
uniform samplerBuffer u_E;         // irradiance per texel
layout(std430, binding = 3) writeonly buffer Local { vec4 B[]; };       // per texel
uniform int u_count;
uniform int u_K;
uniform int u_size;

void main() {
    int k = int(gl_GlobalInvocationID.x);
    if (k >= u_count) return;
    int t = texelFetch(u_texel, k).x;
    int h = (u_K - 1) / 2;
#ifdef TAP_MAJOR
    int i = k, step = u_count;
#else
    int i = k * u_K * u_K, step = 1;
#endif
    vec3 b = vec3(0.0);
    for (int dy = -h; dy <= h; ++dy) {
        int q = t + dy * u_size - h;
        for (int dx = 0; dx < u_K; ++dx, i += step, ++q)
            b += texelFetch(u_w, i).rgb * texelFetch(u_E, q).rgb;
    }
    B[t] = vec4(b, 0.0);
}
