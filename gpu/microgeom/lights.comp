#version 430
// Many lights' images of technique microgeom at once (the virtual goniometer and the BTF export,
// Heidrich et al. 2000 §6): for every light b of a batch and texel p, what
// core/microgeom/scatter.cpp scatter() computes with light_dir = l_b, light_E = 1, env = null,
// in three kernels chosen by u_mode (z of the dispatch = light in the batch):
//   0 direct:  shadow = V(p, l) (exact: the barycentric mix of the 3 nearest directions' S_i; or
//              the per-texel ellipse with its soft edge; 1 without shadows), 0 where n_p . l <= 0;
//              L_d = rho/pi * cos_l * shadow                       -> Direct[b][p] = (L_d, shadow)
//   1 gather:  E(p) = pi sum_{j in J} w_j(p) L_in,j(p) / sum w_j(p) (scatter.comp's sum; L_in from
//              LBuf[b], nothing from the sky: env = null)          -> E[b][p]
//   2 compose: L = L_d + rho/pi E                                  -> LBuf[b][p]
// The gather takes S_i and the bent weights in chunks of directions [u_j0, u_j1)
// (gpu/microgeom/chunks.h): one dispatch per chunk accumulates (sum, wsum) in E, the last divides.
// The exact shadow test sums, chunk by chunk too, the light's three directions held by each.
// Lit or not (n_p . l > 0) is decided in the CPU's float arithmetic (n_dot_l below), so that a facet
// lying exactly along the light is unlit on both.
layout(local_size_x = 8, local_size_y = 8) in;

struct Texel {
    vec4 n;        // xyz normal
    vec4 albedo;   // rgb
    vec4 e0;       // ellipse: centre xy, cos angle, sin angle
    vec4 e1;       // ellipse: a, b
};

layout(std430, binding = 0) readonly buffer Vis { uint S[]; };          // [direction - u_j0][row][column]
layout(std430, binding = 1) readonly buffer Texels { Texel texels[]; };
layout(std430, binding = 2) readonly buffer Dirs { vec4 dirs[]; };       // xyz, w = Omega_j
layout(std430, binding = 3) readonly buffer Bent { float bent_w[]; };    // [texel][direction - u_j0] (curved base)
layout(std430, binding = 4) buffer Direct { vec4 direct[]; };           // [light][texel]: L_d, shadow
layout(std430, binding = 5) buffer LBuf { vec4 L[]; };                  // [light][texel]
layout(std430, binding = 6) buffer EBuf { vec4 E[]; };                  // [light][texel]
layout(std430, binding = 7) readonly buffer Subset { int J[]; };

const int kMaxBatch = 64;
uniform int u_mode;
uniform ivec2 u_size;
uniform int u_j0, u_j1, u_first, u_last, u_J_count, u_periodic, u_has_bent, u_has_prev, u_primary;
uniform int u_shadows, u_ellipses;
uniform float u_edge;
uniform vec4 u_light[kMaxBatch];    // xyz direction
uniform ivec4 u_tri[kMaxBatch];     // the light's spherical triangle
uniform vec4 u_bary[kMaxBatch];     // its barycentrics

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;
const uint kNoHit = 0xFFFFFFFFu, kBelow = 0xFFFFFFFEu;

int wrap_index(int i, int n) { return u_periodic != 0 ? ((i % n) + n) % n : clamp(i, 0, n - 1); }

// [SECTION] Shadows (scatter.cpp visibility_texture, ellipse.cpp ellipse_visibility)
float ellipse_vis(Texel t, vec3 w) {
    if (w.z <= 0.0) return 0.0;
    vec2 p = w.xy - t.e0.xy;
    vec2 uv = vec2(dot(t.e0.zw, p), dot(vec2(-t.e0.w, t.e0.z), p)) / t.e1.xy;
    float q = dot(uv, uv);
    if (u_edge <= 0.0) return q <= 1.0 ? 1.0 : 0.0;
    float g = 2.0 * length(uv / t.e1.xy);
    return clamp(0.5 - (q - 1.0) / (max(g, 1e-6) * u_edge), 0.0, 1.0);
}

// n . l exactly as the CPU's float glm::dot computes it, (n_x l_x + n_y l_y) + n_z l_z with every
// product rounded: `precise` keeps the compiler from fusing the multiply-adds. Where a facet lies
// exactly along the light (n . l = 0 in float, e.g. a 45 degree facet of the triangles field under
// a light 45 degrees up facing it) a fused sum is instead the rounding error of one product
// (+-1e-8), and its sign would decide lit or not: the shadow would jump by the whole visibility
// of the texel (0.59 there) where the CPU has 0. NVIDIA's compiler fuses; llvmpipe does not.
float n_dot_l(vec3 n, vec3 l) {
    precise float xy = n.x * l.x + n.y * l.y;
    precise float xyz = xy + n.z * l.z;
    return xyz;
}

void direct_kernel(int b, int p, int T) {
    Texel t = texels[p];
    vec3 l = u_light[b].xyz;
    float nl = n_dot_l(t.n.xyz, l);
    // This chunk's part of the exact test: the barycentric mix of the 3 directions' visibility.
    float v = 0.0;
    if (u_shadows != 0 && u_ellipses == 0 && nl > 0.0) {
        ivec4 tri = u_tri[b];
        vec4 bary = u_bary[b];
        for (int k = 0; k < 3; ++k) {
            int j = tri[k];
            if (j >= u_j0 && j < u_j1) v += bary[k] * (S[(j - u_j0) * T + p] == kNoHit ? 1.0 : 0.0);
        }
    }
    if (u_first == 0) v += direct[b * T + p].w;
    if (u_last == 0) {
        direct[b * T + p] = vec4(0.0, 0.0, 0.0, v);
        return;
    }
    float shadow = u_shadows == 0 ? 1.0 : u_ellipses == 0 ? v : (nl > 0.0 ? ellipse_vis(t, l) : 0.0);
    float cos_l = max(0.0, nl);
    if (cos_l <= 0.0) shadow = 0.0;
    direct[b * T + p] = vec4(t.albedo.rgb * INV_PI * cos_l * shadow, shadow);
}

// [SECTION] Gather (scatter.comp, one light per z)
vec3 prev_at(int base, int x, int y) { return L[base + y * u_size.x + x].xyz; }

vec3 bilinear(int base, float c, float r) {
    float c0f = floor(c), r0f = floor(r), fc = c - c0f, fr = r - r0f;
    int c0 = wrap_index(int(c0f), u_size.x), c1 = wrap_index(int(c0f) + 1, u_size.x);
    int r0 = wrap_index(int(r0f), u_size.y), r1 = wrap_index(int(r0f) + 1, u_size.y);
    return (prev_at(base, c0, r0) * (1.0 - fc) + prev_at(base, c1, r0) * fc) * (1.0 - fr) +
           (prev_at(base, c0, r1) * (1.0 - fc) + prev_at(base, c1, r1) * fc) * fr;
}

void gather_kernel(int b, int p, int T) {
    vec3 n = texels[p].n.xyz;
    int base = b * T;
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int m = 0; m < u_J_count; ++m) {
        int j = J[m];
        if (j < u_j0 || j >= u_j1) continue;
        float w = u_has_bent != 0 ? bent_w[p * (u_j1 - u_j0) + (j - u_j0)] : dot(n, dirs[j].xyz) * dirs[j].w;
        if (w <= 0.0) continue;
        wsum += w;
        uint hit = S[(j - u_j0) * T + p];
        if (hit != kNoHit && hit != kBelow && u_has_prev != 0) {
            vec2 tc = vec2(float(hit >> 16), float(hit & 0xFFFFu)) / 16.0;
            if (u_primary != 0) {
                sum += w * bilinear(base, tc.x, tc.y);
            } else {
                int x = clamp(int(floor(tc.x + 0.5)) % u_size.x, 0, u_size.x - 1), y = clamp(int(floor(tc.y + 0.5)) % u_size.y, 0, u_size.y - 1);
                sum += w * prev_at(base, x, y);
            }
        }
    }
    vec4 acc = vec4(sum, wsum);
    if (u_first == 0) acc += E[base + p];
    E[base + p] = u_last != 0 ? vec4(acc.w > 0.0 ? PI * acc.xyz / acc.w : vec3(0.0), 1.0) : acc;
}

void main() {
    ivec2 g = ivec2(gl_GlobalInvocationID.xy);
    if (g.x >= u_size.x || g.y >= u_size.y) return;
    int T = u_size.x * u_size.y, p = g.y * u_size.x + g.x, b = int(gl_GlobalInvocationID.z);
    if (u_mode == 0) {
        direct_kernel(b, p, T);
    } else if (u_mode == 1) {
        gather_kernel(b, p, T);
    } else {
        L[b * T + p] = vec4(direct[b * T + p].rgb + texels[p].albedo.rgb * INV_PI * E[b * T + p].rgb, 0.0);
    }
}
