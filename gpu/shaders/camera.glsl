// Camera and object transforms shared by mesh passes (see core/render.h FrameCamera).
uniform mat4 u_model;
uniform mat3 u_normal_matrix;  // transpose(inverse(mat3(u_model)))
uniform mat4 u_view_proj;
uniform int u_texture_mode;    // 1: clip = (2u-1, 2v-1, 0, 1)
uniform vec3 u_eye;            // orbit: eye position (world)
uniform vec3 u_view_dir;       // texture mode: unit direction towards the viewer

// Unit direction from world point p towards the viewer.
vec3 camera_wo(vec3 p) { return u_texture_mode != 0 ? u_view_dir : normalize(u_eye - p); }
