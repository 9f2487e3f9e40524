#version 430 core
// Technique translucency, step translucency.combine: the global response interpolated to the
// texels, every texel shown from its fill source (radiosity = local + global where it is drawn)
// (core/translucency/frame.cpp combine, fill_texels; blend.cpp interpolate_to_texels).
#include "translucency.glsl"
layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Fill { int fill[]; };
layout(std430, binding = 1) readonly buffer Face { int face[]; };     // per texel, -1 where empty
layout(std430, binding = 2) readonly buffer Bary { vec4 bary[]; };
layout(std430, binding = 3) readonly buffer Index { uint tri[]; };
layout(std430, binding = 4) readonly buffer VertexB { vec4 Bv[]; };
layout(std430, binding = 5) readonly buffer Irradiance { vec4 E[]; };
layout(std430, binding = 6) readonly buffer Local { vec4 L[]; };
layout(rgba32f, binding = 0) writeonly uniform image2D u_irradiance;
layout(rgba32f, binding = 1) writeonly uniform image2D u_local;
layout(rgba32f, binding = 2) writeonly uniform image2D u_global;
uniform int u_size;

void main() {
    int t = int(gl_GlobalInvocationID.x);
    if (t >= u_size * u_size) return;
    int s = fill[t] >= 0 ? fill[t] : t;
    vec3 g = vec3(0.0);
    if (face[s] >= 0) {
        int f = face[s];
        vec3 w = bary[s].xyz;
        g = w.x * Bv[tri[3 * f]].rgb + w.y * Bv[tri[3 * f + 1]].rgb + w.z * Bv[tri[3 * f + 2]].rgb;
    }
    vec3 l = L[s].rgb;
    ivec2 q = ivec2(t % u_size, t / u_size);
    imageStore(u_irradiance, q, vec4(E[s].rgb, 1.0));
    imageStore(u_local, q, vec4(l, 1.0));
    imageStore(u_global, q, vec4(g, 1.0));
}
