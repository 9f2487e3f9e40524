// Visibility textures S_i (Heidrich et al. 2000, §3): exact first hits of rays against the
// triangulated heightfield.
//
// [SECTION] Method
// All ray work happens in texel space: continuous texel coordinates (c, r) with texel (x, y) at
// (x, y) (r grows down the image), and heights in texels (z = h / s). The local frame maps to it
// by c = X/s - 1/2, r = H - 1/2 - Y/s, z = Z/s, and directions by (dx, dy, dz) -> (dx, -dy, dz):
// a uniform scale plus a mirror, so ray parameters t are simply measured in texels.
//
// Cell (i, j) spans [i, i+1] x [j, j+1] with corner heights h00 = h(i, j), h10 = h(i+1, j),
// h01 = h(i, j+1), h11 = h(i+1, j+1); with u = c - i, v = r - j its two triangles are
//   A (u >= v): z = h00 + u (h10 - h00) + v (h11 - h10)
//   B (u <= v): z = h00 + u (h11 - h01) + v (h01 - h00).
// The surface is the graph of a continuous, piecewise-linear function S(c, r), so along a ray
// f(t) = z(t) - S(c(t), r(t)) is continuous and linear between breakpoints (cell borders and
// diagonal crossings). The first intersection is the first root of f beyond t_min = 1e-6 texels:
// the walk evaluates f once at each breakpoint, in order, and a sign change between consecutive
// breakpoints gives the root by linear interpolation (exact for a linear piece). Each breakpoint
// value is computed once and reused by the next piece, so the sequence of signs is consistent
// and no root can slip between two pieces (watertight by construction, including the case where
// both triangles of a cell or two neighbouring cells round differently at a shared border). A
// ray that starts below the surface finds the point where it leaves it (two-sided, like a
// two-sided ray/triangle test). A piece lying exactly in the surface (f = 0 at both ends) counts
// as no hit, as a parallel ray misses a triangle in a ray/triangle test.
//
// Cells are visited by an exact 2D DDA (each step leaves the current cell through the border the
// ray reaches first; t at a border is computed directly from the border coordinate, never
// accumulated). A min/max pyramid over cells (level L: blocks of 2^L x 2^L cells, partial at the
// far borders) lets the walk skip whole blocks: at the current position the ray's height range
// over its stretch through the block is compared with the block's [min, max]; if the ray stays
// strictly above (or strictly below) the block, the block is skipped at once and the sign of f at
// the far side is known; otherwise the walk descends a level, down to single cells. After every
// skip it climbs one level again, and after a cell it returns to level 1 when it enters a new
// 2 x 2 block (the "maximum mipmap" traversal). A ray above the global maximum going up (or
// below the global minimum going down) can never meet the surface again: no hit.
//
// Periodic fields wrap: the walk keeps its cell indices in [0, W) x [0, H) and shifts the ray
// origin by whole periods when it crosses a border (exact in double). A ray that stays between the
// global min and max forever (horizontal or nearly so) would walk forever: periodic rays are
// followed for a horizontal distance of at most kPeriodicReach * (W + H) texels (t_cap), beyond
// which they report no hit; trace_brute_force applies the same cap. Non-periodic fields end at the
// outermost texel centres: the walk is clipped to [0, W-1] x [0, H-1] and leaving it is no hit.
//
// The walk runs in scalar double (as fast as scalar float on x86-64; the roots are then exact to
// ~1e-12 texels for the stored heights); heights are stored as float texel units (h / s rounded
// once, ~1e-7 relative), four per cell, one 16-byte load. No libm calls in the loop (floor is
// done by integer conversion: baseline x86-64 has no inline floor, and the calls cost ~20%).
// compute_visibility: per-texel normals and lifted origins once, per-direction constants once,
// then TBB tasks of (direction, block of rows) writing contiguous rows of [dir][row][col].
#include "core/microgeom/visibility.h"
#include "core/parallel.h"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace mesolab::microgeom {

namespace {

constexpr double kTMin = 1e-6;       // hits closer than this (texels) are ignored
constexpr float kLift = 1e-3f;       // compute_visibility: origin lift along n, texel sizes
constexpr double kPeriodicReach = 4; // periodic rays: horizontal reach in units of (W + H) texels
constexpr double kInf = std::numeric_limits<double>::infinity();

// [SECTION] Acceleration structure (texel units)
struct MinMax {
    float lo, hi;
};

struct Field {
    int W = 0, H = 0;    // texels
    int Wc = 0, Hc = 0;  // cells: W x H periodic, (W-1) x (H-1) otherwise
    bool periodic = true;
    double s = 1;        // texel size
    std::vector<std::array<float, 4>> cell;  // h00, h10, h01, h11 per cell (texels), row-major
    // Pyramid: level L has blocks of 2^L x 2^L cells, lw[L] x lh[L] of them, stored from
    // mm[loff[L]] row-major; level 0 is the cells, level `top` a single block.
    std::vector<MinMax> mm;
    std::array<size_t, 32> loff{};
    std::array<int, 32> lw{}, lh{};
    int top = 0;
    double gmin = 0, gmax = 0;  // global height range (texels)
    double reach = 0;           // periodic: horizontal reach, texels
};

Field build_field(const Heightfield& hf) {
    Field F;
    F.W = hf.width;
    F.H = hf.height;
    F.periodic = hf.periodic;
    F.s = double(hf.texel_size);
    if (F.W <= 0 || F.H <= 0 || hf.h.size() < size_t(F.W) * size_t(F.H) || !(F.s > 0)) return F;  // no surface
    F.Wc = F.periodic ? F.W : F.W - 1;
    F.Hc = F.periodic ? F.H : F.H - 1;
    F.reach = kPeriodicReach * double(F.W + F.H);
    if (F.Wc <= 0 || F.Hc <= 0) {
        F.Wc = F.Hc = 0;
        return F;
    }
    auto h = [&](int x, int y) {
        if (x >= F.W) x -= F.W;
        if (y >= F.H) y -= F.H;
        return float(double(hf.h[size_t(y) * size_t(F.W) + size_t(x)]) / F.s);
    };
    F.cell.resize(size_t(F.Wc) * size_t(F.Hc));
    F.lw[0] = F.Wc;
    F.lh[0] = F.Hc;
    size_t total = 0;
    for (int L = 0;; ++L) {
        F.loff[size_t(L)] = total;
        total += size_t(F.lw[size_t(L)]) * size_t(F.lh[size_t(L)]);
        if (F.lw[size_t(L)] == 1 && F.lh[size_t(L)] == 1) {
            F.top = L;
            break;
        }
        F.lw[size_t(L) + 1] = (F.lw[size_t(L)] + 1) / 2;
        F.lh[size_t(L) + 1] = (F.lh[size_t(L)] + 1) / 2;
    }
    F.mm.resize(total);
    float gmin = std::numeric_limits<float>::infinity(), gmax = -gmin;
    for (int y = 0; y < F.Hc; ++y)
        for (int x = 0; x < F.Wc; ++x) {
            const std::array<float, 4> c{h(x, y), h(x + 1, y), h(x, y + 1), h(x + 1, y + 1)};
            const size_t k = size_t(y) * size_t(F.Wc) + size_t(x);
            F.cell[k] = c;
            F.mm[k] = {std::min(std::min(c[0], c[1]), std::min(c[2], c[3])), std::max(std::max(c[0], c[1]), std::max(c[2], c[3]))};
            gmin = std::min(gmin, F.mm[k].lo);
            gmax = std::max(gmax, F.mm[k].hi);
        }
    F.gmin = gmin;
    F.gmax = gmax;
    for (int L = 1; L <= F.top; ++L) {
        const MinMax* p = F.mm.data() + F.loff[size_t(L) - 1];
        MinMax* q = F.mm.data() + F.loff[size_t(L)];
        const int pw = F.lw[size_t(L) - 1], ph = F.lh[size_t(L) - 1], w = F.lw[size_t(L)], hh = F.lh[size_t(L)];
        for (int y = 0; y < hh; ++y)
            for (int x = 0; x < w; ++x) {
                MinMax m{std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()};
                for (int py = 2 * y; py < std::min(2 * y + 2, ph); ++py)
                    for (int px = 2 * x; px < std::min(2 * x + 2, pw); ++px) {
                        const MinMax& e = p[size_t(py) * size_t(pw) + size_t(px)];
                        m.lo = std::min(m.lo, e.lo);
                        m.hi = std::max(m.hi, e.hi);
                    }
                q[size_t(y) * size_t(w) + size_t(x)] = m;
            }
    }
    return F;
}

// [SECTION] Rays
// Per-direction constants (texel space). The direction is normalised; components below 1e-12
// are snapped to 0 (their drift over any walk is far below the hit tolerance).
struct RayDir {
    bool valid = false;
    double dc = 0, dr = 0, dz = 0;
    double inv_dc = kInf, inv_dr = kInf;  // inf where the component is 0 (never multiplied by 0 there)
    double ed = 0, inv_ed = kInf;         // d(u - v)/dt
    double tcap = kInf;                   // periodic reach
};

RayDir make_ray_dir(const Field& F, vec3 dir_local) {
    RayDir R;
    double dc = double(dir_local.x), dr = -double(dir_local.y), dz = double(dir_local.z);
    const double len = std::sqrt(dc * dc + dr * dr + dz * dz);
    if (!(len > 0) || !std::isfinite(len)) return R;
    dc /= len;
    dr /= len;
    dz /= len;
    auto snap = [](double v) { return std::abs(v) < 1e-12 ? 0.0 : v; };
    R.dc = snap(dc);
    R.dr = snap(dr);
    R.dz = snap(dz);
    if (R.dc != 0) R.inv_dc = 1.0 / R.dc;
    if (R.dr != 0) R.inv_dr = 1.0 / R.dr;
    R.ed = R.dc - R.dr;
    if (R.ed != 0) R.inv_ed = 1.0 / R.ed;
    const double hl = std::sqrt(R.dc * R.dc + R.dr * R.dr);
    if (F.periodic) R.tcap = hl > 0 ? F.reach / hl : kInf;
    R.valid = true;
    return R;
}

struct Origin {
    double c, r, z;
};

inline Origin to_texel(const Field& F, vec3 p) {
    return {double(p.x) / F.s - 0.5, double(F.H) - 0.5 - double(p.y) / F.s, double(p.z) / F.s};
}

// floor() as an int without a libm call (baseline x86-64 has no inline floor); v is clamped to
// a safe range first.
inline int floor_int(double v) {
    v = std::clamp(v, -1e9, 1e9);
    const int i = int(v);
    return i - (double(i) > v);
}

// v modulo n into [0, n); v is near the range already (the walk keeps it within a period).
inline double wrap(double v, int n) {
    if (v >= n || v < 0) v -= double(floor_int(v / n)) * n;
    if (v >= n) v -= n;  // rounding of v slightly below 0
    if (v < 0) v = 0;
    return v;
}

// Surface height at (u, v) of a cell, triangle A (u >= v) or B.
inline double surf(const std::array<float, 4>& h, double u, double v, bool A) {
    const double h00 = h[0], h10 = h[1], h01 = h[2], h11 = h[3];
    return A ? h00 + u * (h10 - h00) + v * (h11 - h10) : h00 + u * (h11 - h01) + v * (h01 - h00);
}

// The walk: true and the first hit's (c, r), wrapped for periodic fields, or false for no hit.
bool walk(const Field& F, const RayDir& R, Origin o, double& hit_c, double& hit_r) {
    if (!R.valid || F.Wc == 0 || !std::isfinite(o.c) || !std::isfinite(o.r) || !std::isfinite(o.z)) return false;
    if (R.dz >= 0 ? o.z > F.gmax : o.z < F.gmin) return false;  // above everything going up, or below going down
    const int Wc = F.Wc, Hc = F.Hc;
    const double dc = R.dc, dr = R.dr, dz = R.dz;
    double c0 = o.c, r0 = o.r;
    const double z0 = o.z;
    double t = 0;
    int i, j;
    auto finish = [&](double th) {
        double c = c0 + th * dc, r = r0 + th * dr;
        if (F.periodic) {
            c = wrap(c, F.W);
            r = wrap(r, F.H);
        } else {
            c = std::clamp(c, 0.0, double(F.W - 1));
            r = std::clamp(r, 0.0, double(F.H - 1));
        }
        hit_c = c;
        hit_r = r;
        return true;
    };

    if (F.periodic) {
        if (c0 < 0 || c0 >= Wc) c0 -= std::floor(c0 / Wc) * Wc;
        if (r0 < 0 || r0 >= Hc) r0 -= std::floor(r0 / Hc) * Hc;
        i = std::clamp(floor_int(c0), 0, Wc - 1);
        j = std::clamp(floor_int(r0), 0, Hc - 1);
    } else {
        // Clip to the domain [0, Wc] x [0, Hc].
        double t0 = 0, t1 = kInf;
        auto slab = [&](double p, double d, double inv, double hi) {
            if (d == 0) return p >= 0 && p <= hi;
            double a = (0 - p) * inv, b = (hi - p) * inv;
            if (a > b) std::swap(a, b);
            t0 = std::max(t0, a);
            t1 = std::min(t1, b);
            return t0 <= t1;
        };
        if (!slab(c0, dc, R.inv_dc, Wc) || !slab(r0, dr, R.inv_dr, Hc)) return false;
        t = t0;
        i = std::clamp(floor_int(c0 + t * dc), 0, Wc - 1);
        j = std::clamp(floor_int(r0 + t * dr), 0, Hc - 1);
    }

    // Vertical ray: one point of the surface.
    if (dc == 0 && dr == 0) {
        const auto& h = F.cell[size_t(j) * size_t(Wc) + size_t(i)];
        const double u = c0 - i, v = r0 - j;
        const double f0 = z0 - surf(h, u, v, u >= v);
        if (dz == 0) return false;
        const double th = -f0 / dz;
        if (!(th > kTMin)) return false;
        return finish(th);
    }

    const double gmin = F.gmin, gmax = F.gmax;
    const double tcap = R.tcap;
    double f_prev = 0;      // f at t (valid when f_known)
    bool f_known = false;
    int prev_sign = 0;      // sign of f at t when !f_known (from a skipped block), 0 = none
    int L = 0;
    // Safety net against endless loops (cannot trigger for finite inputs: every move enters a new
    // cell, the reach bounds the cells crossed, and each move costs at most top + 2 iterations).
    const double cells = F.periodic ? 1.5 * F.reach + 4 : double(Wc + Hc) + 4;
    long long steps_left = static_cast<long long>(cells) * (F.top + 2) + 64;

    while (--steps_left > 0) {
        if (t > tcap) return false;
        const double zc = z0 + t * dz;
        if (dz >= 0 ? zc > gmax : zc < gmin) return false;
        if (L > 0) {
            const int bi = i >> L, bj = j >> L;
            const MinMax m = F.mm[F.loff[size_t(L)] + size_t(bj) * size_t(F.lw[size_t(L)]) + size_t(bi)];
            const int bx0 = bi << L, by0 = bj << L;
            const int bx1 = std::min(bx0 + (1 << L), Wc), by1 = std::min(by0 + (1 << L), Hc);
            const double tx = dc > 0 ? (bx1 - c0) * R.inv_dc : dc < 0 ? (bx0 - c0) * R.inv_dc : kInf;
            const double ty = dr > 0 ? (by1 - r0) * R.inv_dr : dr < 0 ? (by0 - r0) * R.inv_dr : kInf;
            const double te = std::max(std::min(tx, ty), t);
            const double ze = dz == 0 ? z0 : z0 + te * dz;
            int sign;
            if (std::min(zc, ze) > double(m.hi))
                sign = 1;
            else if (std::max(zc, ze) < double(m.lo))
                sign = -1;
            else {
                --L;
                continue;
            }
            // Skip the block: leave it through the border(s) reached first.
            t = te;
            const bool sx = tx <= ty, sy = ty <= tx;
            if (sx) i = dc > 0 ? bx1 : bx0 - 1;
            else i = std::clamp(floor_int(c0 + t * dc), bx0, bx1 - 1);
            if (sy) j = dr > 0 ? by1 : by0 - 1;
            else j = std::clamp(floor_int(r0 + t * dr), by0, by1 - 1);
            f_known = false;
            prev_sign = sign;
            L = std::min(L + 1, F.top);
        } else {
            // One cell: pieces [t, td] and [td, tout] split by the diagonal u = v. On each
            // triangle f is linear in t: f = F0 + t F1.
            const std::array<float, 4>& h = F.cell[size_t(j) * size_t(Wc) + size_t(i)];
            const double h00 = h[0], h10 = h[1], h01 = h[2], h11 = h[3];
            const double cu = c0 - i, cv = r0 - j;  // u, v at t = 0
            const double tx = dc > 0 ? (1 - cu) * R.inv_dc : dc < 0 ? (-cu) * R.inv_dc : kInf;
            const double ty = dr > 0 ? (1 - cv) * R.inv_dr : dr < 0 ? (-cv) * R.inv_dr : kInf;
            const double tout = std::max(std::min(tx, ty), t);
            const double e0 = cu - cv;  // u - v at t = 0
            const double ta1 = h10 - h00, ta2 = h11 - h10, tb1 = h11 - h01, tb2 = h01 - h00;
            const double base = z0 - h00;
            const double FA0 = base - cu * ta1 - cv * ta2, FA1 = dz - dc * ta1 - dr * ta2;
            const double FB0 = base - cu * tb1 - cv * tb2, FB1 = dz - dc * tb1 - dr * tb2;
            const double td = R.ed != 0 ? -e0 * R.inv_ed : kInf;
            const bool split = td > t && td < tout;
            const double t1 = split ? td : tout;
            const bool A = e0 + 0.5 * (t + t1) * R.ed >= 0;  // first piece on triangle A?
            double F0 = A ? FA0 : FB0, F1 = A ? FA1 : FB1;
            double fa;
            if (f_known) {
                fa = f_prev;
            } else {
                fa = F0 + t * F1;
                if (((prev_sign > 0 && fa <= 0) || (prev_sign < 0 && fa >= 0)) && t > kTMin && t <= tcap) return finish(t);
            }
            double fb = F0 + t1 * F1;
            if ((fa > 0 && fb <= 0) || (fa < 0 && fb >= 0)) {
                const double th = t + (t1 - t) * (fa / (fa - fb));
                if (th > kTMin) return th <= tcap ? finish(th) : false;
            }
            if (split) {
                F0 = A ? FB0 : FA0;
                F1 = A ? FB1 : FA1;
                fa = fb;
                fb = F0 + tout * F1;
                if ((fa > 0 && fb <= 0) || (fa < 0 && fb >= 0)) {
                    const double th = td + (tout - td) * (fa / (fa - fb));
                    if (th > kTMin) return th <= tcap ? finish(th) : false;
                }
            }
            f_prev = fb;
            f_known = true;
            t = tout;
            const bool sx = tx <= ty, sy = ty <= tx;
            const int oi = i, oj = j;
            if (sx) i += dc > 0 ? 1 : -1;
            if (sy) j += dr > 0 ? 1 : -1;
            // Climb back to level 1 only on entering a new 2 x 2 block: within the same block
            // the level-1 test has just failed from an earlier t.
            L = (i >> 1) != (oi >> 1) || (j >> 1) != (oj >> 1) ? std::min(1, F.top) : 0;
        }
        // Wrap (periodic) or leave (non-periodic).
        if (i < 0 || i >= Wc) {
            if (!F.periodic) return false;
            if (i >= Wc) { i -= Wc; c0 -= Wc; }
            else { i += Wc; c0 += Wc; }
        }
        if (j < 0 || j >= Hc) {
            if (!F.periodic) return false;
            if (j >= Hc) { j -= Hc; r0 -= Hc; }
            else { j += Hc; r0 += Hc; }
        }
    }
    return false;
}

// Pack a hit for the texture (as Visibility::encode): quantise to 1/16 texel and wrap the
// quantised value (periodic) so that a hit just below W does not round up to W.
uint32_t pack_hit(const Field& F, double c, double r) {
    int qc = floor_int(c * 16.0 + 0.5), qr = floor_int(r * 16.0 + 0.5);
    if (F.periodic) {
        const int nc = 16 * F.W, nr = 16 * F.H;
        if (qc >= nc) qc -= nc;
        if (qr >= nr) qr -= nr;
    }
    return (uint32_t(std::clamp(qc, 0, 65535)) << 16) | uint32_t(std::clamp(qr, 0, 65535));
}
}  // namespace

// [SECTION] Public API
uint32_t Visibility::encode(float c, float r) {
    auto q = [](float v) -> uint32_t {
        if (!(v > 0)) return 0;  // negative or NaN
        const float s = std::round(v * 16.f);
        return s >= 65535.f ? 65535u : uint32_t(s);
    };
    return (q(c) << 16) | q(r);
}

vec2 Visibility::decode(uint32_t packed) { return {float(packed >> 16) / 16.f, float(packed & 0xFFFFu) / 16.f}; }

bool trace(const Heightfield& hf, vec3 origin, vec3 dir, vec2& hit_texel) {
    const Field F = build_field(hf);
    const RayDir R = make_ray_dir(F, dir);
    double c, r;
    if (!walk(F, R, to_texel(F, origin), c, r)) return false;
    hit_texel = vec2(float(c), float(r));
    return true;
}

bool trace_brute_force(const Heightfield& hf, vec3 origin, vec3 dir, vec2& hit_texel) {
    const int W = hf.width, H = hf.height;
    const double s = double(hf.texel_size);
    if (W <= 0 || H <= 0 || hf.h.size() < size_t(W) * size_t(H) || !(s > 0)) return false;
    const int Wc = hf.periodic ? W : W - 1, Hc = hf.periodic ? H : H - 1;
    if (Wc <= 0 || Hc <= 0) return false;
    double d[3] = {double(dir.x), -double(dir.y), double(dir.z)};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0) || !std::isfinite(len)) return false;
    for (double& v : d) v /= len;
    const double o[3] = {double(origin.x) / s - 0.5, double(H) - 0.5 - double(origin.y) / s, double(origin.z) / s};
    if (!std::isfinite(o[0]) || !std::isfinite(o[1]) || !std::isfinite(o[2])) return false;
    auto hd = [&](int x, int y) { return double(hf.h[size_t(y % H) * size_t(W) + size_t(x % W)]) / s; };
    double gmin = kInf, gmax = -kInf;
    for (float v : hf.h) {
        gmin = std::min(gmin, double(v) / s);
        gmax = std::max(gmax, double(v) / s);
    }
    // Reach: the periodic cap, and where the ray leaves the global height range for good.
    const double hl = std::sqrt(d[0] * d[0] + d[1] * d[1]);
    const double tcap = hf.periodic && hl > 0 ? kPeriodicReach * double(W + H) / hl : kInf;
    double tend = tcap;
    if (d[2] > 0) tend = std::min(tend, std::max(0.0, (gmax - o[2]) / d[2]) + 1);
    if (d[2] < 0) tend = std::min(tend, std::max(0.0, (gmin - o[2]) / d[2]) + 1);
    if (!std::isfinite(tend)) tend = 4.0 * (W + H);  // non-periodic horizontal ray: the domain bounds it anyway

    double best = kInf;
    // Möller-Trumbore, two-sided, double; barycentric bounds slightly inclusive.
    auto tri = [&](const double* a, const double* b, const double* c) {
        const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
        const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
        if (std::abs(det) < 1e-300) return;
        const double inv = 1.0 / det;
        const double tv[3] = {o[0] - a[0], o[1] - a[1], o[2] - a[2]};
        const double u = (tv[0] * p[0] + tv[1] * p[1] + tv[2] * p[2]) * inv;
        if (u < -1e-12 || u > 1 + 1e-12) return;
        const double q[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2], tv[0] * e1[1] - tv[1] * e1[0]};
        const double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
        if (v < -1e-12 || u + v > 1 + 1e-12) return;
        const double tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
        if (tt > kTMin && tt <= tcap && tt < best) best = tt;
    };
    auto tile = [&](int a, int b) {
        const double ox = double(a) * W, oy = double(b) * H;
        for (int y = 0; y < Hc; ++y)
            for (int x = 0; x < Wc; ++x) {
                const double p00[3] = {ox + x, oy + y, hd(x, y)}, p10[3] = {ox + x + 1, oy + y, hd(x + 1, y)};
                const double p01[3] = {ox + x, oy + y + 1, hd(x, y + 1)}, p11[3] = {ox + x + 1, oy + y + 1, hd(x + 1, y + 1)};
                tri(p00, p10, p11);
                tri(p00, p11, p01);
            }
    };
    if (!hf.periodic) {
        tile(0, 0);
    } else {
        // Every copy of the tile whose rectangle (grown by a texel) the ray's horizontal path
        // [0, tend] touches.
        const double c1 = o[0] + tend * d[0], r1 = o[1] + tend * d[1];
        const int a0 = int(std::floor(std::min(o[0], c1) / W)) - 1, a1 = int(std::floor(std::max(o[0], c1) / W)) + 1;
        const int b0 = int(std::floor(std::min(o[1], r1) / H)) - 1, b1 = int(std::floor(std::max(o[1], r1) / H)) + 1;
        for (int b = b0; b <= b1; ++b)
            for (int a = a0; a <= a1; ++a) {
                double t0 = 0, t1 = tend;
                auto slab = [&](double p, double dd, double lo, double hi) {
                    if (dd == 0) return p >= lo && p <= hi;
                    double u = (lo - p) / dd, v = (hi - p) / dd;
                    if (u > v) std::swap(u, v);
                    t0 = std::max(t0, u);
                    t1 = std::min(t1, v);
                    return t0 <= t1;
                };
                if (slab(o[0], d[0], double(a) * W - 1, double(a + 1) * W + 1) && slab(o[1], d[1], double(b) * H - 1, double(b + 1) * H + 1)) tile(a, b);
            }
    }
    if (!(best < kInf)) return false;
    double c = o[0] + best * d[0], r = o[1] + best * d[1];
    if (hf.periodic) {
        c = wrap(c, W);
        r = wrap(r, H);
    }
    hit_texel = vec2(float(c), float(r));
    return true;
}

Visibility compute_visibility(const Heightfield& hf, const DirectionSet& dirs, const VisibilityProgress& progress) {
    Visibility vis;
    vis.width = hf.width;
    vis.height = hf.height;
    vis.count = dirs.size();
    const int W = hf.width, H = hf.height, N = dirs.size();
    if (W <= 0 || H <= 0 || N <= 0) {
        if (progress) progress(1.0);
        return vis;
    }
    if (hf.h.size() != size_t(W) * size_t(H))
        throw std::invalid_argument("microgeom visibility: heightfield has " + std::to_string(hf.h.size()) + " heights for " +
                                    std::to_string(W) + "x" + std::to_string(H) + " texels");
    vis.hit = hits_filled(size_t(N) * size_t(W) * size_t(H), Visibility::kNoHit);
    const Field F = build_field(hf);

    // Per texel: normal and lifted origin (texel space), computed once.
    std::vector<vec3> normal(size_t(W) * size_t(H));
    std::vector<Origin> origin(normal.size());
    mesolab::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < W; ++x) {
                const size_t k = size_t(y) * size_t(W) + size_t(x);
                normal[k] = hf.normal(x, y);
                origin[k] = to_texel(F, hf.position(x, y) + (kLift * hf.texel_size) * normal[k]);
            }
    });
    std::vector<RayDir> rd(static_cast<size_t>(N));
    for (int i = 0; i < N; ++i) rd[size_t(i)] = make_ray_dir(F, dirs.d[size_t(i)]);

    // Tasks: (direction, block of rows); batches of directions between progress calls, so that
    // progress runs on the calling thread only and an exception from it simply propagates.
    const int rows_per_task = std::max(1, std::min(H, 4096 / std::max(1, W)));
    const int blocks = (H + rows_per_task - 1) / rows_per_task;
    const int batches = std::min(N, 16);
    if (progress) progress(0.0);
    for (int b = 0; b < batches; ++b) {
        const int d0 = int(long(N) * b / batches), d1 = int(long(N) * (b + 1) / batches);
        mesolab::parallel_for(tbb::blocked_range<int>(0, (d1 - d0) * blocks), [&](const tbb::blocked_range<int>& tasks) {
            for (int task = tasks.begin(); task < tasks.end(); ++task) {
                const int i = d0 + task / blocks, y0 = (task % blocks) * rows_per_task, y1 = std::min(H, y0 + rows_per_task);
                const vec3 d = dirs.d[size_t(i)];
                const RayDir& R = rd[size_t(i)];
                uint32_t* out = vis.hit.data() + size_t(i) * size_t(W) * size_t(H);
                for (int y = y0; y < y1; ++y)
                    for (int x = 0; x < W; ++x) {
                        const size_t k = size_t(y) * size_t(W) + size_t(x);
                        if (!(glm::dot(d, normal[k]) > 0.f)) {
                            out[k] = Visibility::kBelow;
                            continue;
                        }
                        double c, r;
                        out[k] = walk(F, R, origin[k], c, r) ? pack_hit(F, c, r) : Visibility::kNoHit;
                    }
            }
        });
        if (progress) progress(double(d1) / double(N));
    }
    return vis;
}

HitArray hits_filled(size_t n, uint32_t value) {
    HitArray h;
    h.resize(n);  // uninitialised (UninitAllocator)
    constexpr size_t kBlock = size_t(1) << 20;  // 4 MB per task
    mesolab::parallel_for(size_t(0), (n + kBlock - 1) / kBlock, [&](size_t b) {
        std::fill(h.begin() + std::ptrdiff_t(b * kBlock), h.begin() + std::ptrdiff_t(std::min(n, (b + 1) * kBlock)), value);
    });
    return h;
}
}  // namespace mesolab::microgeom
