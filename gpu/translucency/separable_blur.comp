#version 430 core
// Method separable of technique translucency: one of the two 1D blurs over the pixels of one object
// (core/translucency/separable_blur.h blur_pixel is the CPU twin).
layout(local_size_x = 8, local_size_y = 8) in;

uniform sampler2D u_value;  // rgb: what is blurred
uniform sampler2D u_geom;   // view depth (mm), pixel size (mm), object (-1: none)
layout(rgba32f, binding = 0) writeonly uniform image2D u_out;
uniform int u_vertical;
uniform float u_object;
uniform int u_taps;
uniform vec4 u_tap[63];     // xyz: the weight a_i per channel, w: the offset x_i (mm)

vec3 centre;
float z;

vec3 tap(ivec2 q, int along, int i, float offset, ivec2 size) {
    int n = along == 1 ? size.y : size.x;
    if (i < 0 || i >= n) return centre;
    ivec2 j = along == 1 ? ivec2(q.x, i) : ivec2(i, q.y);
    vec4 g = texelFetch(u_geom, j, 0);
    if (g.z != u_object) return centre;
    float s = min(1.0, abs(g.x - z) / abs(offset));
    return mix(texelFetch(u_value, j, 0).rgb, centre, s);
}

void main() {
    ivec2 size = textureSize(u_geom, 0);
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (q.x >= size.x || q.y >= size.y) return;
    vec4 g = texelFetch(u_geom, q, 0);
    if (g.z != u_object) return;
    centre = texelFetch(u_value, q, 0).rgb;
    z = g.x;
    float inv_pixel = 1.0 / g.y;
    int along = u_vertical;
    int n = along == 1 ? size.y : size.x;
    float a = float(along == 1 ? q.y : q.x);
    vec3 sum = vec3(0.0);
    for (int k = 0; k < u_taps; ++k) {
        float offset = u_tap[k].w;
        vec3 w = u_tap[k].xyz;
        if (offset == 0.0) {
            sum += w * centre;
            continue;
        }
        float u = a + offset * inv_pixel;
        if (!(u > -1.0 && u < float(n))) {
            sum += w * centre;
            continue;
        }
        float f0 = floor(u);
        int i0 = int(f0);
        sum += w * mix(tap(q, along, i0, offset, size), tap(q, along, i0 + 1, offset, size), u - f0);
    }
    imageStore(u_out, q, vec4(sum, 1.0));
}
