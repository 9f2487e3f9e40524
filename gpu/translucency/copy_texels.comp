#version 430 core
// Technique translucency, step translucency.illumination, second half: border texels whose
// surface another chunk holds take that chunk's texel (AtlasStage::copy; core/translucency/frame.cpp
// illuminate).
layout(local_size_x = 64) in;

uniform isamplerBuffer u_copy;  // (texel, source)
uniform samplerBuffer u_E;      // the irradiance below, read where it was lit
layout(std430, binding = 3) writeonly buffer Irradiance { vec4 E[]; };  // per texel

uniform int u_count;

void main() {
    int k = int(gl_GlobalInvocationID.x);
    if (k >= u_count) return;
    ivec2 p = texelFetch(u_copy, k).xy;
    E[p.x] = texelFetch(u_E, p.y);
}
