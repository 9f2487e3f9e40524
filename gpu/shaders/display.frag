#version 430 core
// GUI display pass (gpu/display.cpp): one float AOV texel per pixel -> display-encoded RGBA8.
//   u_mode 0: colour, linear * u_exposure, clamped, sRGB-encoded (IEC 61966-2-1)
//   u_mode 1: normal, n * 0.5 + 0.5 (no transfer function)
#include "common.glsl"
uniform sampler2D u_source;
uniform int u_mode;
uniform int u_channels;
uniform float u_exposure;
layout(location = 0) out vec4 o_color;
void main() {
    vec4 v = texelFetch(u_source, ivec2(gl_FragCoord.xy), 0);
    vec3 c = u_channels == 1 ? v.rrr : u_channels == 2 ? vec3(v.rg, 0.0) : v.rgb;
    // NaN (x != x) displays as black rather than whatever clamp() does with it.
    c = vec3(c.r != c.r ? 0.0 : c.r, c.g != c.g ? 0.0 : c.g, c.b != c.b ? 0.0 : c.b);
    if (u_mode == 1) c = clamp(c * 0.5 + 0.5, 0.0, 1.0);
    else c = linear_to_srgb(clamp(c * u_exposure, 0.0, 1.0));
    o_color = vec4(c, 1.0);
}
