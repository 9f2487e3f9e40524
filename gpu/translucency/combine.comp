#version 430 core
// Technique translucency, step translucency.combine: the global response interpolated to the
// texels, every texel shown from its fill source (radiosity = local + global where it is drawn)
// (core/translucency/frame.cpp combine, fill_texels; blend.cpp interpolate_to_texels). Only the
// non-empty texels run: the maps' empty texels are cleared once, when the maps are made. Without
// WRITE_PARTS only the radiosity map is written (the irradiance, local and global maps are made
// when a frame shows them: translucency_pass.cpp).
#include "translucency.glsl"
layout(local_size_x = 64) in;

uniform isamplerBuffer u_shown;   // per non-empty texel: texel, source, the source's vertices 0 and 1 (-1: none)
uniform samplerBuffer u_bary;     // per non-empty texel: the source's barycentrics, the bits of its vertex 2
uniform samplerBuffer u_Bv;       // global response per vertex
uniform samplerBuffer u_E;        // irradiance per texel
uniform samplerBuffer u_L;        // local response per texel
#ifdef WRITE_PARTS
layout(rgba32f, binding = 0) writeonly uniform image2D u_irradiance;
layout(rgba32f, binding = 1) writeonly uniform image2D u_local;
layout(rgba32f, binding = 2) writeonly uniform image2D u_global;
#endif
layout(rgba32f, binding = 3) writeonly uniform image2D u_radiosity;  // local + global
uniform int u_count;
uniform int u_size;

void main() {
    int k = int(gl_GlobalInvocationID.x);
    if (k >= u_count) return;
    ivec4 r = texelFetch(u_shown, k);
    int t = r.x, s = r.y;
    vec3 g = vec3(0.0);
    if (r.z >= 0) {
        vec4 w = texelFetch(u_bary, k);
        g = w.x * texelFetch(u_Bv, r.z).rgb + w.y * texelFetch(u_Bv, r.w).rgb + w.z * texelFetch(u_Bv, floatBitsToInt(w.w)).rgb;
    }
    ivec2 q = ivec2(t % u_size, t / u_size);
    vec3 l = texelFetch(u_L, s).rgb;
    imageStore(u_radiosity, q, vec4(l + g, 1.0));
#ifdef WRITE_PARTS
    imageStore(u_irradiance, q, vec4(texelFetch(u_E, s).rgb, 1.0));
    imageStore(u_local, q, vec4(l, 1.0));
    imageStore(u_global, q, vec4(g, 1.0));
#endif
}
