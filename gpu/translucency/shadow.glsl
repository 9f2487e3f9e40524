// Technique translucency: the lights' shadow maps (core/translucency/translucency.h ShadowMap),
// one per light, up to 4, as the layers of u_shadow (gpu/translucency/shadow_maps.h sets them).
uniform int u_shadow_count;
uniform sampler2DArray u_shadow;
uniform int u_shadow_res;
uniform mat4 u_shadow_view_proj[4];
uniform int u_shadow_point[4];
uniform vec3 u_shadow_origin[4];
uniform vec3 u_shadow_dir[4];
uniform float u_shadow_bias[4];
uniform int u_shadow_valid[4];

// 1 when world point p is lit by light i, 0 when a nearer surface hides it (ShadowMap::visibility).
float visibility(int i, vec3 p) {
    if (i >= u_shadow_count || u_shadow_valid[i] == 0) return 1.0;
    vec4 c = u_shadow_view_proj[i] * vec4(p, 1.0);
    if (!(c.w > 0.0)) return 1.0;
    float nx = c.x / c.w, ny = c.y / c.w;
    if (!(abs(nx) <= 1.0 && abs(ny) <= 1.0)) return 1.0;
    int res = u_shadow_res;
    int x = clamp(int(floor((nx * 0.5 + 0.5) * float(res))), 0, res - 1);
    int y = clamp(int(floor((0.5 - 0.5 * ny) * float(res))), 0, res - 1);  // row 0 at the top
    float d = u_shadow_point[i] != 0 ? length(p - u_shadow_origin[i]) : dot(p - u_shadow_origin[i], u_shadow_dir[i]);
    return d - u_shadow_bias[i] <= texelFetch(u_shadow, ivec3(x, res - 1 - y, i), 0).r ? 1.0 : 0.0;  // GL rows from the bottom
}
