#version 430 core
// Test: attachment 0 gets a uniform colour, attachment 1 the pixel centre coordinates.
#include "common.glsl"
uniform vec4 u_color;
layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_coord;
void main() {
    out_color = u_color;
    out_coord = vec4(gl_FragCoord.xy, PI, 1.0);
#ifdef BREAK_ME
    this line is not GLSL
#endif
}
