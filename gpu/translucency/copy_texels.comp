#version 430 core
// Technique translucency, step translucency.illumination, second half: border texels whose
// surface another chunk holds take that chunk's texel (AtlasStage::copy; core/translucency/frame.cpp
// illuminate).
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Pairs { ivec2 copy_pair[]; };  // (texel, source)
layout(std430, binding = 3) buffer Irradiance { vec4 E[]; };               // per texel

uniform int u_count;

void main() {
    int k = int(gl_GlobalInvocationID.x);
    if (k >= u_count) return;
    ivec2 p = copy_pair[k];
    E[p.x] = E[p.y];
}
