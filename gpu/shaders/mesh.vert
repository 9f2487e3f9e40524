#version 430 core
// Vertex shader shared by the techniques' mesh passes.
#include "common.glsl"
#include "camera.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_tangent;
layout(location = 3) in vec2 a_uv;

out vec3 v_position;
out vec3 v_normal;
out vec3 v_tangent;
out vec2 v_uv;

invariant gl_Position;  // the same depth in every pass that draws a mesh (bumpsynth: depth pre-pass, then shading with GL_LEQUAL)

#ifdef MESOLAB_SNAP_VERTICES
// Positions on the CPU rasteriser's sub-pixel grid (core/raster.cpp: window positions snap to 1/256
// pixel), for passes whose shading makes discrete choices from the interpolated attributes
// (bumpsynth's nearest table entry). Hardware interpolates attributes from the snapped positions too
// (Direct3D 11.3 functional specification, 3.2.4; OpenGL leaves it open), but llvmpipe snaps only
// for coverage and interpolates from the unsnapped float positions: up to 1/512 pixel apart, which
// moved bumpsynth's uv by up to 6e-6 (llvmpipe, 512 x 512 frames) and picked other table entries at
// ~1% of a sphere's pixels. Snapped here, a conformant rasteriser's snapping changes nothing.
// The clip position is the CPU's, bit for bit where division rounds correctly (llvmpipe): the
// matrix proj · view · model made on the CPU, the product in glm's order and `precise`, so that a
// vertex near the middle between two grid points goes the same way.
uniform mat4 u_clip_from_object;  // proj · view · model (Renderer::set_camera_uniforms)
uniform vec2 u_viewport_size;     // the frame's width and height in pixels

vec4 glm_product(mat4 m, vec4 v) {
    precise vec4 r = (m[0] * v.x + m[1] * v.y) + (m[2] * v.z + m[3] * v.w);
    return r;
}

// 1 / w rounded as the CPU's float division rounds it: GLSL leaves division to 2.5 ULP (NVIDIA
// computes an approximate reciprocal); one Newton step on the exact residual (fma) corrects it.
float reciprocal(float w) {
    float r = 1.0 / w;
    return fma(r, fma(-w, r, 1.0), r);
}

vec4 snapped(vec4 c) {
    if (!(c.w > 0.0)) return c;  // clipped away, or clipped by GL after this shader
    float inv_w = reciprocal(c.w);
    vec2 half_size = 0.5 * u_viewport_size;
    precise vec2 window = (c.xy * inv_w + 1.0) * half_size;
    vec2 grid = roundEven(window * 256.0) / 256.0;  // llrint in the CPU rasteriser
    return vec4((grid / half_size - 1.0) * c.w, c.z, c.w);
}
#endif

void main() {
    vec4 wp = u_model * vec4(a_position, 1.0);
    v_position = wp.xyz;
    v_normal = u_normal_matrix * a_normal;
    v_tangent = mat3(u_model) * a_tangent;
    v_uv = a_uv;
#ifdef MESOLAB_SNAP_VERTICES
    gl_Position = snapped(u_texture_mode != 0 ? vec4(a_uv * 2.0 - 1.0, 0.0, 1.0) : glm_product(u_clip_from_object, vec4(a_position, 1.0)));
#else
    gl_Position = u_texture_mode != 0 ? vec4(a_uv * 2.0 - 1.0, 0.0, 1.0) : u_view_proj * wp;
#endif
}
