#version 430
// Visibility textures S_i of technique microgeom (Heidrich et al. 2000, §3) on the GPU: the same
// exact first hit of a ray with the triangulated heightfield as core/microgeom/visibility.cpp
// (read its [SECTION] Method first), one invocation per (texel, direction), in float.
//
// The walk is the CPU's, step for step: a 2D DDA over cells (each step leaves the current cell
// through the border reached first, t at a border computed from the border coordinate, never
// accumulated), f(t) = z(t) - S(c(t), r(t)) evaluated once per breakpoint (cell borders and
// diagonal crossings) and reused by the next piece, so the sign sequence is consistent and no
// root slips between pieces; the min/max pyramid skips blocks the ray stays strictly above or
// below ("maximum mipmap" traversal, same climb/descend rules); periodic fields wrap by whole
// periods; non-periodic ones clip to [0, W-1] x [0, H-1].
//
// Float robustness (the CPU runs in double):
//   * The ray origin is kept as an integer texel (oi, oj) plus a small float offset (fc, fr):
//     every coordinate the walk uses is relative to the current cell, (oi - i) + fc with the
//     integer difference exact, so precision does not degrade with the field's size, only with
//     the distance travelled (~1e-7 * t texels).
//   * Heights are relative too: each triangle's plane is written about a reference vertex, the
//     origin texel where it is one (else the cell's (0, 0) corner), as z0 - h_ref =
//     (hs - h_ref) + oz, with hs the origin texel's height and oz = z0 - hs the lift (both from
//     the host, in double). Near the origin f then comes from small terms only, so tall or steep
//     fields do not swamp the 1e-3 texel lift (on steep fields the lifted origin is often within
//     1e-2 texels of the surface).
//   * The culling tests (global height range, pyramid blocks) are conservative: the ray must
//     clear a block by a margin larger than the float error of its height before the block is
//     skipped; otherwise the walk descends and decides on cells, exactly as the CPU would. The
//     DDA never skips a cell: a near-tie at a corner steps through a neighbour the ray touches
//     within rounding, which keeps the f sequence continuous.
//   * The below-horizon test d . n(p) <= 0 is `precise`, in the CPU's order (glm::dot), so it
//     agrees bit for bit with the CPU's float test.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

struct Texel {
    vec4 n;  // xyz: normal (Heightfield::normal, local frame)
    vec4 o;  // (c0 - x, r0 - y, z0 - hs, hs): lifted origin relative to the texel, texel units
};
struct Dir {
    vec4 d;    // xyz: the direction as given (for the below test); w: 1 = valid, 0 = no direction
    vec4 ray;  // (dc, dr, dz, tcap): normalised texel-space direction, periodic reach in t
    vec4 inv;  // (1/dc, 1/dr, 1/(dc - dr), dc - dr); kBig where the component is 0 (never used)
};

layout(std430, binding = 0) readonly buffer Texels { Texel texels[]; };
layout(std430, binding = 1) readonly buffer Dirs { Dir dirs[]; };
layout(std430, binding = 2) readonly buffer Cells { vec4 cells[]; };  // h00, h10, h01, h11 (texels)
layout(std430, binding = 3) readonly buffer Pyramid { vec2 mm[]; };   // (min, max) per block
layout(std430, binding = 4) writeonly buffer Hits { uint hits[]; };   // [direction - u_dir0][row][col]

uniform ivec2 u_size;     // W, H (texels)
uniform ivec2 u_cells;    // Wc, Hc (cells); 0 x 0: no surface
uniform int u_periodic;
uniform int u_top;        // top pyramid level
uniform int u_loff[16];   // level offsets into mm
uniform int u_lw[16];     // level widths (blocks)
uniform float u_gmin, u_gmax;
uniform int u_steps;      // safety net on loop iterations (as the CPU's)
uniform int u_dir0;       // first direction of this dispatch
uniform int u_dir_count;  // directions in this dispatch

const uint kNoHit = 0xFFFFFFFFu;
const uint kBelow = 0xFFFFFFFEu;
const float kTMin = 1e-6;
const float kBig = 3.0e38;

int floor_int(float v) { return int(floor(clamp(v, -1e9, 1e9))); }

// Margin by which a ray must clear a height range before the culling tests trust it: a few
// times the float error of z0 + t dz.
float margin(float z0, float tdz) { return 1e-5 + 2e-6 * (abs(z0) + abs(tdz)); }

// v into [0, n); v is within a period of the range already.
float wrapf(float v, int n) {
    const float fn = float(n);
    if (v >= fn || v < 0.0) v -= floor(v / fn) * fn;
    if (v >= fn) v -= fn;
    if (v < 0.0) v = 0.0;
    return v;
}

// The hit at ray parameter th, packed as Visibility::encode (the CPU's pack_hit): relative to
// the current cell (i, j), then wrapped (periodic) or clamped to the texel centres.
uint finish(float th, int i, int j, int oi, int oj, float fc, float fr, float dc, float dr) {
    float c = float(i) + ((float(oi - i) + fc) + th * dc);
    float r = float(j) + ((float(oj - j) + fr) + th * dr);
    const int W = u_size.x, H = u_size.y;
    if (u_periodic != 0) {
        c = wrapf(c, W);
        r = wrapf(r, H);
    } else {
        c = clamp(c, 0.0, float(W - 1));
        r = clamp(r, 0.0, float(H - 1));
    }
    int qc = floor_int(c * 16.0 + 0.5), qr = floor_int(r * 16.0 + 0.5);
    if (u_periodic != 0) {
        if (qc >= 16 * W) qc -= 16 * W;
        if (qr >= 16 * H) qr -= 16 * H;
    }
    return (uint(clamp(qc, 0, 65535)) << 16) | uint(clamp(qr, 0, 65535));
}

// f(t) = z(t) - S(c(t), r(t)) = F0 + t F1 on triangle A (u >= v) or B of a cell with corner
// heights h, for the ray from the origin texel at (ku, kv) relative to the cell (plus T's offsets).
// The plane is written about a reference vertex: the origin texel where it is a vertex of the
// triangle (then f near the origin comes from small terms only, the lift and the offsets fc, fr,
// with no cancellation against the heights: steep fields lift the origin by far less than their
// height differences), else (0, 0). A: vertices (0,0), (1,0), (1,1); B: (0,0), (0,1), (1,1).
vec2 plane(vec4 h, bool A, int ku, int kv, Texel T, Dir D) {
    const float s1 = A ? h.y - h.x : h.w - h.z, s2 = A ? h.w - h.y : h.z - h.x;  // dS/du, dS/dv
    const bool on = ku >= 0 && ku <= 1 && kv >= 0 && kv <= 1 && (A ? ku >= kv : ku <= kv);
    const int ru = on ? ku : 0, rv = on ? kv : 0;
    const float F0 = ((T.o.w - h[ru + 2 * rv]) + T.o.z) - (float(ku - ru) + T.o.x) * s1 - (float(kv - rv) + T.o.y) * s2;
    return vec2(F0, D.ray.z - D.ray.x * s1 - D.ray.y * s2);
}

uint trace(int x, int y, Dir D) {
    const int W = u_size.x;
    const Texel T = texels[y * W + x];
    // Below p's tangent plane: the CPU's float glm::dot(d, n) > 0, same order, no fusing.
    precise float dn = D.d.x * T.n.x + D.d.y * T.n.y;
    precise float dn3 = dn + D.d.z * T.n.z;
    if (!(dn3 > 0.0)) return kBelow;
    const int Wc = u_cells.x, Hc = u_cells.y;
    if (D.d.w == 0.0 || Wc == 0 || Hc == 0) return kNoHit;

    const float dc = D.ray.x, dr = D.ray.y, dz = D.ray.z, tcap = D.ray.w;
    const float inv_dc = D.inv.x, inv_dr = D.inv.y, inv_ed = D.inv.z, ed = D.inv.w;
    const float fc = T.o.x, fr = T.o.y, oz = T.o.z, hs = T.o.w;
    const float z0 = hs + oz;
    const float gmin = u_gmin, gmax = u_gmax;
    const bool periodic = u_periodic != 0;
    if (dz >= 0.0 ? z0 > gmax + margin(z0, 0.0) : z0 < gmin - margin(z0, 0.0)) return kNoHit;

    int oi = x, oj = y;  // integer part of the origin (shifted by whole periods when wrapping)
    float t = 0.0;
    int i, j;
    if (periodic) {
        i = oi + floor_int(fc);
        j = oj + floor_int(fr);
        const int ki = int(floor(float(i) / float(Wc))), kj = int(floor(float(j) / float(Hc)));  // whole periods
        i -= ki * Wc;
        oi -= ki * Wc;
        j -= kj * Hc;
        oj -= kj * Hc;
    } else {
        // Clip to the domain [0, Wc] x [0, Hc].
        float t0 = 0.0, t1 = kBig;
        if (dc == 0.0) {
            const float c0 = float(oi) + fc;
            if (!(c0 >= 0.0 && c0 <= float(Wc))) return kNoHit;
        } else {
            float a = (float(-oi) - fc) * inv_dc, b = (float(Wc - oi) - fc) * inv_dc;
            if (a > b) { const float s = a; a = b; b = s; }
            t0 = max(t0, a);
            t1 = min(t1, b);
            if (!(t0 <= t1)) return kNoHit;
        }
        if (dr == 0.0) {
            const float r0 = float(oj) + fr;
            if (!(r0 >= 0.0 && r0 <= float(Hc))) return kNoHit;
        } else {
            float a = (float(-oj) - fr) * inv_dr, b = (float(Hc - oj) - fr) * inv_dr;
            if (a > b) { const float s = a; a = b; b = s; }
            t0 = max(t0, a);
            t1 = min(t1, b);
            if (!(t0 <= t1)) return kNoHit;
        }
        t = t0;
        i = clamp(oi + floor_int(fc + t * dc), 0, Wc - 1);
        j = clamp(oj + floor_int(fr + t * dr), 0, Hc - 1);
    }

    // Vertical ray: one point of the surface.
    if (dc == 0.0 && dr == 0.0) {
        const float u = float(oi - i) + fc, v = float(oj - j) + fr;
        const float f0 = plane(cells[j * Wc + i], u >= v, oi - i, oj - j, T, D).x;
        if (dz == 0.0) return kNoHit;
        const float th = -f0 / dz;
        if (!(th > kTMin)) return kNoHit;
        return finish(th, i, j, oi, oj, fc, fr, dc, dr);
    }

    float f_prev = 0.0;   // f at t (valid when f_known)
    bool f_known = false;
    int prev_sign = 0;    // sign of f at t when !f_known (from a skipped block), 0 = none
    int L = 0;
    int steps_left = u_steps;
    while (--steps_left > 0) {
        if (t > tcap) return kNoHit;
        const float zc = z0 + t * dz;
        const float mz = margin(z0, t * dz);
        if (dz >= 0.0 ? zc > gmax + mz : zc < gmin - mz) return kNoHit;
        if (L > 0) {
            const int bi = i >> L, bj = j >> L;
            const vec2 m = mm[u_loff[L] + bj * u_lw[L] + bi];
            const int bx0 = bi << L, by0 = bj << L;
            const int bx1 = min(bx0 + (1 << L), Wc), by1 = min(by0 + (1 << L), Hc);
            const float tx = dc > 0.0 ? (float(bx1 - oi) - fc) * inv_dc : dc < 0.0 ? (float(bx0 - oi) - fc) * inv_dc : kBig;
            const float ty = dr > 0.0 ? (float(by1 - oj) - fr) * inv_dr : dr < 0.0 ? (float(by0 - oj) - fr) * inv_dr : kBig;
            const float te = max(min(tx, ty), t);
            const float ze = dz == 0.0 ? z0 : z0 + te * dz;
            const float mb = margin(z0, te * dz);
            int sign;
            if (min(zc, ze) > m.y + mb)
                sign = 1;
            else if (max(zc, ze) < m.x - mb)
                sign = -1;
            else {
                --L;
                continue;
            }
            // Skip the block: leave it through the border(s) reached first.
            t = te;
            const bool sx = tx <= ty, sy = ty <= tx;
            if (sx) i = dc > 0.0 ? bx1 : bx0 - 1;
            else i = clamp(oi + floor_int(fc + t * dc), bx0, bx1 - 1);
            if (sy) j = dr > 0.0 ? by1 : by0 - 1;
            else j = clamp(oj + floor_int(fr + t * dr), by0, by1 - 1);
            f_known = false;
            prev_sign = sign;
            L = min(L + 1, u_top);
        } else {
            // One cell: pieces [t, td] and [td, tout] split by the diagonal u = v; on each
            // triangle f = F0 + t F1.
            const vec4 h = cells[j * Wc + i];  // h00, h10, h01, h11
            const float cu = float(oi - i) + fc, cv = float(oj - j) + fr;  // u, v at t = 0
            const float tx = dc > 0.0 ? (float(i + 1 - oi) - fc) * inv_dc : dc < 0.0 ? (float(i - oi) - fc) * inv_dc : kBig;
            const float ty = dr > 0.0 ? (float(j + 1 - oj) - fr) * inv_dr : dr < 0.0 ? (float(j - oj) - fr) * inv_dr : kBig;
            const float tout = max(min(tx, ty), t);
            const float e0 = float((oi - i) - (oj - j)) + (fc - fr);  // u - v at t = 0
            const vec2 FA = plane(h, true, oi - i, oj - j, T, D), FB = plane(h, false, oi - i, oj - j, T, D);
            const float FA0 = FA.x, FA1 = FA.y, FB0 = FB.x, FB1 = FB.y;
            const float td = ed != 0.0 ? -e0 * inv_ed : kBig;
            const bool split = td > t && td < tout;
            const float t1 = split ? td : tout;
            const bool A = e0 + 0.5 * (t + t1) * ed >= 0.0;  // first piece on triangle A?
            float F0 = A ? FA0 : FB0, F1 = A ? FA1 : FB1;
            float fa;
            if (f_known) {
                fa = f_prev;
            } else {
                fa = F0 + t * F1;
                if (((prev_sign > 0 && fa <= 0.0) || (prev_sign < 0 && fa >= 0.0)) && t > kTMin && t <= tcap)
                    return finish(t, i, j, oi, oj, fc, fr, dc, dr);
            }
            float fb = F0 + t1 * F1;
            if ((fa > 0.0 && fb <= 0.0) || (fa < 0.0 && fb >= 0.0)) {
                const float th = t + (t1 - t) * (fa / (fa - fb));
                if (th > kTMin) return th <= tcap ? finish(th, i, j, oi, oj, fc, fr, dc, dr) : kNoHit;
            }
            if (split) {
                F0 = A ? FB0 : FA0;
                F1 = A ? FB1 : FA1;
                fa = fb;
                fb = F0 + tout * F1;
                if ((fa > 0.0 && fb <= 0.0) || (fa < 0.0 && fb >= 0.0)) {
                    const float th = td + (tout - td) * (fa / (fa - fb));
                    if (th > kTMin) return th <= tcap ? finish(th, i, j, oi, oj, fc, fr, dc, dr) : kNoHit;
                }
            }
            f_prev = fb;
            f_known = true;
            t = tout;
            const bool sx = tx <= ty, sy = ty <= tx;
            const int pi = i, pj = j;
            if (sx) i += dc > 0.0 ? 1 : -1;
            if (sy) j += dr > 0.0 ? 1 : -1;
            // Climb back to level 1 only on entering a new 2 x 2 block.
            L = (i >> 1) != (pi >> 1) || (j >> 1) != (pj >> 1) ? min(1, u_top) : 0;
        }
        // Wrap (periodic) or leave (non-periodic).
        if (i < 0 || i >= Wc) {
            if (!periodic) return kNoHit;
            if (i >= Wc) { i -= Wc; oi -= Wc; }
            else { i += Wc; oi += Wc; }
        }
        if (j < 0 || j >= Hc) {
            if (!periodic) return kNoHit;
            if (j >= Hc) { j -= Hc; oj -= Hc; }
            else { j += Hc; oj += Hc; }
        }
    }
    return kNoHit;
}

void main() {
    const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y), k = int(gl_GlobalInvocationID.z);
    const int W = u_size.x, H = u_size.y;
    if (x >= W || y >= H || k >= u_dir_count) return;
    hits[(uint(k) * uint(H) + uint(y)) * uint(W) + uint(x)] = trace(x, y, dirs[u_dir0 + k]);
}
