#version 430
// One bounce's gather of technique microgeom's dependent-test scattering (Heidrich et al. 2000,
// §3.2) on the GPU, the same sum as core/microgeom/scatter.cpp's gather, one invocation per texel:
//   E(p) = pi * sum_{j in J} w_j(p) L_in,j(p) / sum_{j in J} w_j(p)
// with w_j(p) = dot(n_p, d_j) Omega_j (flat) or the curved base's bent weights (curvature.h),
// directions with w <= 0 skipped, L_in,j = the environment where S_j[p] says no hit, the previous
// bounce's radiance at the hit (bilinear for the primary gather, nearest texel for inner ones),
// 0 below p's plane or in the first gather (environment only).
// S_i and the bent weights come in chunks of directions [u_j0, u_j1) (gpu/microgeom/chunks.h):
// one dispatch per chunk accumulates (sum, wsum) in E_out; the last one divides and, for the next
// bounce, forms that bounce's radiance L_next = direct + albedo / pi * E (when u_form_next).
layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) readonly buffer Vis { uint S[]; };          // [direction - u_j0][row][column]
layout(std430, binding = 1) readonly buffer Normals { vec4 normals[]; };  // xyz per texel
layout(std430, binding = 2) readonly buffer Dirs { vec4 dirs[]; };       // xyz, w = Omega_j
layout(std430, binding = 3) readonly buffer Bent { float bent_w[]; };    // [texel][direction - u_j0] (curved base)
layout(std430, binding = 4) readonly buffer Env { vec4 L_env[]; };       // per direction
layout(std430, binding = 5) readonly buffer Prev { vec4 L_prev[]; };     // per texel
layout(std430, binding = 6) readonly buffer Subset { int J[]; };
layout(std430, binding = 7) buffer Out { vec4 E_out[]; };               // (sum, wsum) until the last chunk, then (E, 1)
layout(std430, binding = 8) readonly buffer Direct { vec4 direct[]; };  // per texel
layout(std430, binding = 9) readonly buffer Albedo { vec4 albedo[]; };  // per texel
layout(std430, binding = 10) writeonly buffer Next { vec4 L_next[]; };  // per texel

uniform ivec2 u_size;
uniform int u_j0, u_j1, u_first, u_last, u_J_count, u_periodic, u_has_bent, u_has_prev, u_primary, u_form_next;

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;
const uint kNoHit = 0xFFFFFFFFu, kBelow = 0xFFFFFFFEu;

int wrap_index(int i, int n) { return u_periodic != 0 ? ((i % n) + n) % n : clamp(i, 0, n - 1); }
vec3 prev_at(int x, int y) { return L_prev[y * u_size.x + x].xyz; }

// core/microgeom/scatter.cpp sample_bilinear.
vec3 bilinear(float c, float r) {
    float c0f = floor(c), r0f = floor(r), fc = c - c0f, fr = r - r0f;
    int c0 = wrap_index(int(c0f), u_size.x), c1 = wrap_index(int(c0f) + 1, u_size.x);
    int r0 = wrap_index(int(r0f), u_size.y), r1 = wrap_index(int(r0f) + 1, u_size.y);
    return (prev_at(c0, r0) * (1.0 - fc) + prev_at(c1, r0) * fc) * (1.0 - fr) + (prev_at(c0, r1) * (1.0 - fc) + prev_at(c1, r1) * fc) * fr;
}

void main() {
    ivec2 g = ivec2(gl_GlobalInvocationID.xy);
    if (g.x >= u_size.x || g.y >= u_size.y) return;
    int T = u_size.x * u_size.y, p = g.y * u_size.x + g.x;
    vec3 n = normals[p].xyz;
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int m = 0; m < u_J_count; ++m) {
        int j = J[m];
        if (j < u_j0 || j >= u_j1) continue;
        float w = u_has_bent != 0 ? bent_w[p * (u_j1 - u_j0) + (j - u_j0)] : dot(n, dirs[j].xyz) * dirs[j].w;
        if (w <= 0.0) continue;
        wsum += w;
        uint hit = S[(j - u_j0) * T + p];
        if (hit == kNoHit) {
            sum += w * L_env[j].xyz;
        } else if (hit != kBelow && u_has_prev != 0) {
            vec2 t = vec2(float(hit >> 16), float(hit & 0xFFFFu)) / 16.0;
            if (u_primary != 0) {
                sum += w * bilinear(t.x, t.y);
            } else {
                int x = clamp(int(floor(t.x + 0.5)) % u_size.x, 0, u_size.x - 1), y = clamp(int(floor(t.y + 0.5)) % u_size.y, 0, u_size.y - 1);
                sum += w * prev_at(x, y);
            }
        }
    }
    vec4 acc = vec4(sum, wsum);
    if (u_first == 0) acc += E_out[p];
    if (u_last == 0) {
        E_out[p] = acc;
        return;
    }
    vec3 E = acc.w > 0.0 ? PI * acc.xyz / acc.w : vec3(0.0);
    E_out[p] = vec4(E, 1.0);
    if (u_form_next != 0) L_next[p] = vec4(direct[p].xyz + albedo[p].xyz * INV_PI * E, 0.0);
}
