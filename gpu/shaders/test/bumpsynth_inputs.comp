#version 430 core
// Test: bumpsynth's look-up-table inputs and entries (bumpsynth/synthesis.glsl) at a list of points:
// points[i] = (u, v, k, fine) -> inputs[i] = (u1, u2 of k octaves, u1, u2 of k + 1 octaves when
// fine != 0), entries[i] = the nearest table entries (a, b) of both.
#include "../../bumpsynth/synthesis.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = 1) readonly buffer Points { vec4 points[]; };
layout(std430, binding = 2) writeonly buffer Inputs { vec4 inputs[]; };
layout(std430, binding = 3) writeonly buffer Entries { ivec4 entries[]; };
uniform uint u_count;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= u_count) return;
    vec4 q = points[i];
    vec2 coarse = vec2(0.5), fine;
    synthesis_inputs(q.xy, int(q.z), q.w != 0.0, coarse, fine);
    inputs[i] = vec4(coarse, fine);
    entries[i] = ivec4(lut_entry(coarse), lut_entry(fine));
}
