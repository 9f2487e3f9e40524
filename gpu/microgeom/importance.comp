#version 430
// Curved-base importance of technique microgeom (Heidrich et al. 2000, §5) on the GPU: the same
// I_j(p), w_j(p) and folded flags as core/microgeom/curvature.cpp's compute_importance (read the
// model in core/microgeom/curvature.h first), one invocation per texel of a batch of rows.
//
// Per texel p, with no per-direction arrays in the invocation (N is not bounded here), global
// memory serves as scratch: the Bent buffer ([direction][texel], so that neighbouring invocations
// touch neighbouring entries) and the texel's own rows of I and w:
//   1. d_j'(p) for every j (towards the hit S_j[p] names, lowered), with its hit flag, into Bent;
//      I[p][.] := 0 and w[p][.] := 0: the bent (a1) and unbent (a0) fan areas, accumulated next.
//   2. One walk over the M triangles of the direction triangulation, in index order: the
//      orientation a . (b x c) of the bent corners (<= 0: the triangle turned over, p is folded)
//      and, between three hits that keep their orientation, the bent solid angle added to a1 of
//      each corner and the unbent one to a0. A fan lists its triangles in increasing index
//      (make_direction_set), so each a1, a0 is summed in the CPU's order.
//   3. I_j = max(a1 / a0, 1e-6) for hits with a0 > 0, else 1.
//   4. w_j = max(0, n_p . d_j') Omega_j I_j for hits, max(0, n_p . d_j) Omega_j for the rest;
//      sums H (hits), F (environment) and the flat total W0 = sum_j max(0, n_p . d_j) Omega_j.
//   5. Hits scaled down to W0 if they exceed it (or if there is no environment), the environment
//      gets what is left of W0, and everything is divided by the total: sum_j w_j = 1.
//
// Float agreement with the CPU (which runs the same float expressions, and double where noted):
//   * bent directions and orientations are `precise`, written in the CPU's order of operations
//     (glm::dot, glm::cross), so no FMA contraction separates them from the CPU's floats, and
//     std::round (halves away from zero) is spelled out for the periodic nearest image;
//   * the bent solid angle (Van Oosterom & Strackee, in double on the CPU) takes
//     det(a, b, c) = a . ((b - a) x (c - a)), whose float error is relative to the triangle's
//     size rather than to 1, and its own atan (angle_of, ~1e-7 relative) instead of the
//     builtin's driver-dependent one;
//   * the sums W0, H, F (double on the CPU) are compensated (Kahan) float sums.
layout(local_size_x = 64) in;

struct Tri {
    ivec3 v;      // corners, counter-clockwise seen from outside
    float area0;  // unbent solid angle (spherical_triangle_area on the host)
};

layout(std430, binding = 0) readonly buffer Vis { uint S[]; };            // [direction][row - u_row0][column]
layout(std430, binding = 1) readonly buffer Normals { vec4 normals[]; };  // [row - u_row0][column]: n_p
layout(std430, binding = 2) readonly buffer Dirs { vec4 dirs[]; };        // xyz: d_j, w: Omega_j
layout(std430, binding = 3) readonly buffer Tris { Tri tris[]; };
layout(std430, binding = 4) buffer Importance { float I[]; };             // [texel - batch start][direction]
layout(std430, binding = 5) buffer Weights { float w[]; };                // [texel - batch start][direction]
layout(std430, binding = 6) writeonly buffer Folded { uint folded[]; };   // [texel - batch start]
layout(std430, binding = 7) buffer Bent { vec4 bent[]; };                 // [direction][texel - batch start]: d_j'(p), w: 1 = hit

uniform ivec2 u_size;   // W, H (texels)
uniform int u_row0;     // first row of this batch
uniform int u_rows;     // rows in this batch
uniform int u_N, u_M;   // directions, triangles
uniform int u_periodic;
uniform vec2 u_kappa;   // (kappa_u, kappa_v), radians per texel

const uint kNoHit = 0xFFFFFFFFu, kBelow = 0xFFFFFFFEu;

bool is_hit(uint s) { return s != kNoHit && s != kBelow; }

// std::round: to the nearest integer, halves away from zero.
float round_away(float v) {
    float a = abs(v), r = floor(a);
    if (a - r >= 0.5) r += 1.0;
    return v < 0.0 ? -r : r;
}

// [SECTION] Bent directions (curvature.cpp bent_direction)
// Direction j at texel (x, y) with S_j[p] = s: unbent for the environment and below the plane;
// for a hit, towards the hit point q lowered by the paraboloid, q' - p normalised.
vec3 bent_direction(int j, uint s, int x, int y) {
    const vec3 d = dirs[j].xyz;
    if (!is_hit(s)) return d;
    // Horizontal offset to the hit in texels (local x = +column, local y = -row), nearest image.
    const vec2 t = vec2(float(s >> 16), float(s & 0xFFFFu)) / 16.0;
    precise float dx = t.x - float(x), dy = -(t.y - float(y));
    if (u_periodic != 0) {
        const float W = float(u_size.x), H = float(u_size.y);
        dx -= W * round_away(dx / W);
        dy -= H * round_away(dy / H);
    }
    // The hit point relative to p along the ray, lowered by kappa_u dx^2 / 2 + kappa_v dy^2 / 2.
    precise float horiz = sqrt(d.x * d.x + d.y * d.y);
    precise float len = horiz > 1e-6 ? sqrt(dx * dx + dy * dy) / horiz : 0.0;
    precise vec3 q = d * len;
    q.z -= 0.5 * (u_kappa.x * dx * dx + u_kappa.y * dy * dy);
    precise float l2 = q.x * q.x + q.y * q.y + q.z * q.z;
    precise vec3 b = q / sqrt(l2);
    return l2 > 1e-20 ? b : d;
}

// [SECTION] Spherical triangles
// a . (b x c), as glm::dot(a, glm::cross(b, c)) on the CPU: > 0 for a counter-clockwise triangle.
float orientation(vec3 a, vec3 b, vec3 c) {
    precise vec3 bxc = vec3(b.y * c.z - c.y * b.z, b.z * c.x - c.z * b.x, b.x * c.y - c.x * b.y);
    precise float o = a.x * bxc.x + a.y * bxc.y + a.z * bxc.z;
    return o;
}

// The angle of (x, y), y > 0, in (0, pi), to ~1e-7 relative. The builtin atan may be a bare
// polynomial (Mesa's is 0.99998 z near 0: 2e-5 relative), which would bias every bent solid angle
// by that much. Here: mirrored into [0, pi/2], halved three times (the angle of (x + |(x, y)|, y)
// is half that of (x, y), no cancellation for x >= 0), then the Taylor series of atan to z^9 at
// z <= tan(pi/16) ~ 0.2 (truncation ~1e-8 relative).
float angle_of(float x, float y) {
    const bool mirrored = x < 0.0;
    x = abs(x);
    for (int k = 0; k < 3; ++k) x += sqrt(x * x + y * y);
    const float z = y / x, z2 = z * z;
    const float a = 8.0 * z * (1.0 + z2 * (-1.0 / 3.0 + z2 * (1.0 / 5.0 + z2 * (-1.0 / 7.0 + z2 * (1.0 / 9.0)))));
    return mirrored ? 3.14159265358979323846 - a : a;
}

// Solid angle of (a, b, c) (Van Oosterom & Strackee): 2 atan2(|det|, 1 + a.b + b.c + c.a).
float spherical_triangle_area(vec3 a, vec3 b, vec3 c) {
    precise vec3 e1 = b - a, e2 = c - a;
    precise float num = abs(dot(a, cross(e1, e2)));
    precise float den = 1.0 + dot(a, b) + dot(b, c) + dot(c, a);
    return num > 0.0 ? 2.0 * angle_of(den, num) : 0.0;
}

// Compensated sum: (s, c) += v.
void kahan_add(inout float s, inout float c, float v) {
    precise float y = v - c;
    precise float t = s + y;
    precise float e = (t - s) - y;  // precise: (s + y - s) - y must not fold to 0
    c = e;
    s = t;
}

void main() {
    const int W = u_size.x;
    const int i = int(gl_GlobalInvocationID.x);  // texel within the batch
    if (i >= u_rows * W) return;
    const int x = i % W, y = u_row0 + i / W;
    const int N = u_N, stride = u_rows * W;  // S_j of the batch: S[j * stride + i]
    const int base = i * N;                   // this texel's I and w
    const vec3 n = normals[i].xyz;

    // [SECTION] Bent directions, once per direction
    for (int j = 0; j < N; ++j) {
        const uint s = S[j * stride + i];
        bent[j * stride + i] = vec4(bent_direction(j, s, x, y), is_hit(s) ? 1.0 : 0.0);
        I[base + j] = 0.0;  // a1
        w[base + j] = 0.0;  // a0
    }

    // [SECTION] Fan areas: bent over the hit-only triangles, folding over all
    bool turned = false;
    for (int t = 0; t < u_M; ++t) {
        const ivec3 v = tris[t].v;
        const vec4 a = bent[v.x * stride + i], b = bent[v.y * stride + i], c = bent[v.z * stride + i];
        const float o = orientation(a.xyz, b.xyz, c.xyz);
        turned = turned || o <= 0.0;
        if (o > 0.0 && a.w * b.w * c.w > 0.0) {
            const float area = spherical_triangle_area(a.xyz, b.xyz, c.xyz), area0 = tris[t].area0;
            I[base + v.x] += area;
            I[base + v.y] += area;
            I[base + v.z] += area;
            w[base + v.x] += area0;
            w[base + v.y] += area0;
            w[base + v.z] += area0;
        }
    }
    folded[i] = turned ? 1u : 0u;

    // [SECTION] Importance and unnormalised weights
    float W0 = 0.0, W0c = 0.0, Hs = 0.0, Hc = 0.0, F = 0.0, Fc = 0.0;
    for (int j = 0; j < N; ++j) {
        const vec4 dj = dirs[j], bj = bent[j * stride + i];
        const float omega = dj.w;
        precise float cos0 = max(0.0, n.x * dj.x + n.y * dj.y + n.z * dj.z);
        precise float flat_w = cos0 * omega;
        kahan_add(W0, W0c, flat_w);
        if (bj.w > 0.0) {
            const float a1 = I[base + j], a0 = w[base + j];
            const float Ij = a0 > 0.0 ? max(a1 / a0, 1e-6) : 1.0;
            const vec3 d = bj.xyz;
            precise float wj = max(0.0, n.x * d.x + n.y * d.y + n.z * d.z) * omega * Ij;
            I[base + j] = Ij;
            w[base + j] = wj;
            kahan_add(Hs, Hc, wj);
        } else {
            I[base + j] = 1.0;
            w[base + j] = flat_w;
            kahan_add(F, Fc, flat_w);
        }
    }

    // [SECTION] Normalised gather weights
    // The environment takes what the bent hits leave of W0; hits beyond W0 are scaled to it.
    const float hit_scale = Hs > W0 || F <= 0.0 ? (Hs > 0.0 ? W0 / Hs : 0.0) : 1.0;
    const float env_scale = F > 0.0 ? max(0.0, W0 - Hs * hit_scale) / F : 0.0;
    const float total = Hs * hit_scale + F * env_scale;
    for (int j = 0; j < N; ++j) {
        const bool hit = bent[j * stride + i].w > 0.0;
        w[base + j] = total > 0.0 ? w[base + j] * (hit ? hit_scale : env_scale) / total : 0.0;
    }
}
