#version 430 core
// Test: the bumpsynth noise texture look-up (bumpsynth/noise_texture.glsl) at a list of points:
// points[i] = (u, v, level, unused) -> values[i].
#include "../../bumpsynth/noise_texture.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Points { vec4 points[]; };
layout(std430, binding = 1) writeonly buffer Values { vec2 values[]; };
uniform sampler2D u_noise;
uniform uint u_count;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i < u_count) values[i] = noise_texture_bilinear(u_noise, int(points[i].z), points[i].xy);
}
