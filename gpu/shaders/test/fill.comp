#version 430 core
// Test: writes values[i] = i * SCALE + OFFSET into an SSBO and the texel coordinates into an
// rgba32f image. SCALE comes from a define; OFFSET from the include below.
#include "fill_offset.glsl"
layout(local_size_x = 8, local_size_y = 4) in;
layout(std430, binding = 0) buffer Values { float values[]; };
layout(rgba32f, binding = 0) uniform writeonly image2D u_image;
uniform uint u_count;
void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    uint i = id.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x + id.x;
    if (i < u_count) values[i] = float(i) * SCALE + OFFSET;
    ivec2 size = imageSize(u_image);
    if (all(lessThan(ivec2(id), size))) imageStore(u_image, ivec2(id), vec4(vec2(id), latlong_uv(vec3(0.0, 1.0, 0.0))));
}
