#version 430
// Per-texel shadow ellipses of technique microgeom (Heidrich et al. 2000, §4) on the GPU: the
// fit of core/microgeom/ellipse.cpp (class Fitter; read ellipse.h's [SECTION] Fitting first),
// one work group per texel. Host side: ellipse_gpu.cpp.
//
// [SECTION] Method
// Per texel the points P_i (projected directions, at most kMaxPoints) and their lit flags are
// loaded into shared memory. Then, as the CPU: no lit point -> kEmptyEllipse; every point lit ->
// the circle at the origin of radius 1 + edge; otherwise the covariance start, the circle at the
// lit mean and the circle at the origin, then the pattern search over (cx, cy, angle, log rho)
// (best of the 8 axis moves, steps halved when none improves; at most kMaxEvaluations
// evaluations and kRefinements halvings). The search is sequential: invocation 0 keeps its state
// in private variables, publishes each candidate shape in shared memory and decides after the
// evaluation; a barrier separates every step, so all control flow around barriers is uniform.
//
// [SECTION] One evaluation (Fitter::evaluate), by the whole group
//  - keys: s^2 = u^2 + (v / rho)^2 as float bits with the lowest bit replaced by the lit flag
//    (non-negative floats order like their bits), padded to M = next power of two with 0xFFFFFFFF
//    (after every real key, +inf included);
//  - a bitonic sort of the M keys in shared memory;
//  - the sweep: correct_i = n_shadowed + sum_{k <= i} (lit_k ? +1 : -1) by a parallel prefix
//    sum (per-invocation chunks, then a Hillis-Steele scan of the chunk sums), the margin
//    m_i = 0.5 (s_{i+1} - s_i) min(rho, 1) (edge after the last point), and an argmax over
//    (correct, margin), first index on ties. The CPU's sequential sweep takes a later candidate
//    only for a margin larger by 1e-6; the argmax takes the largest margin, so the two differ
//    only where margins tie within 1e-6. The result competes with "nothing inside"
//    (n_shadowed, margin 0) by the CPU's rule; the radius follows as the CPU's
//    a_i = (s_i + s_{i+1}) / 2 (s_last + edge / min(rho, 1) after the last point).
// Float: the key arithmetic is `precise` (no fused multiply-adds, like the CPU's x86-64 code);
// cos, sin, exp, log and atan come from the driver and may differ from libm in the last bits, so
// a near-tie can go the other way (tests/microgeom/ellipse_gpu_test.cpp states the agreement).
//
// [SECTION] Group size and loops
// LOCAL_SIZE is set by the host (ellipse_gpu.cpp, [SECTION] Group size): a power of two from 8 to
// 512, chosen per dispatch from the point count. llvmpipe counts every loop back-edge of an
// invocation against a limit of 65535 and then leaves every loop after one pass; the host's
// loop_iterations() bounds the back-edges of the loops below, so keep the two in step when
// changing a loop here. An unfinished group leaves NaN in its output, which the host rejects.
#ifndef LOCAL_SIZE
#define LOCAL_SIZE 64
#endif
layout(local_size_x = LOCAL_SIZE, local_size_y = 1, local_size_z = 1) in;

const int L = LOCAL_SIZE;          // invocations per group (a power of two)
const int kMaxPoints = 1024;       // shared-memory capacity (the host checks the counts)
const float kMinRadius = 0.01;     // as ellipse.cpp
const float kMinAspect = 0.02;
const int kMaxEvaluations = 120;
const int kRefinements = 4;
const float kPi = 3.14159265358979323846;
const uint kPad = 0xFFFFFFFFu;

layout(std430, binding = 0) readonly buffer Points { vec2 points[]; };   // [texel * u_point_stride + i]
layout(std430, binding = 1) readonly buffer Lit { uint lit_bits[]; };    // [texel * u_lit_words + i / 32], bit i % 32
layout(std430, binding = 2) readonly buffer Counts { uint counts[]; };   // points per texel
layout(std430, binding = 3) writeonly buffer Out { float ellipses[]; };  // 5 per texel: cx, cy, angle, a, b

uniform int u_point_stride;  // 0: every texel shares the same points (flat base)
uniform int u_lit_words;     // uints of lit bits per texel
uniform float u_edge;        // EllipseMap::edge

// [SECTION] Shared state
shared vec2 s_P[kMaxPoints];
shared uint s_lit[kMaxPoints / 32];
shared uint s_key[kMaxPoints];
shared int s_part[L];               // chunk sums, then their inclusive scan
shared int s_red_correct[L];        // argmax: correct, margin, index
shared float s_red_margin[L];
shared int s_red_index[L];
shared int s_n, s_M, s_n_shadowed;
shared bool s_done;
shared vec4 s_shape;                // cx, cy, cos(angle), sin(angle)
shared vec2 s_rho;                  // 1 / rho^2, min(rho, 1)

bool is_lit(int i) { return ((s_lit[i >> 5] >> uint(i & 31)) & 1u) != 0u; }
float radius(int i) { return sqrt(uintBitsToFloat(s_key[i] & ~1u)); }

// Score::better_than of the CPU: correct first, then the margin by more than 1e-6.
bool better_than(int c, float m, int oc, float om) { return c != oc ? c > oc : m > om + 1e-6; }
// The argmax's order: correct, margin, then the lower index.
bool before(int c, float m, int i, int oc, float om, int oi) { return c != oc ? c > oc : (m != om ? m > om : i < oi); }

// [SECTION] Evaluation
// Sorts the keys of the published shape and leaves the argmax (correct, margin, index) in
// s_red_*[0]; index -1 when no point (never: n >= 2 here).
void evaluate(uint t) {
    const int n = s_n, M = s_M;
    const vec4 shape = s_shape;
    const float inv_rho2 = s_rho.x, axis_scale = s_rho.y;
    for (int i = int(t); i < M; i += L) {
        uint key = kPad;
        if (i < n) {
            precise float dx = s_P[i].x - shape.x, dy = s_P[i].y - shape.y;
            precise float u = shape.z * dx + shape.w * dy, v = -shape.w * dx + shape.z * dy;
            precise float s2 = u * u + v * v * inv_rho2;
            key = (floatBitsToUint(s2) & ~1u) | (is_lit(i) ? 1u : 0u);
        }
        s_key[i] = key;
    }
    barrier();

    // Bitonic sort, ascending: M / 2 compare-exchanges per stage.
    for (int k = 2; k <= M; k <<= 1)
        for (int j = k >> 1; j > 0; j >>= 1) {
            for (int p = int(t); p < M / 2; p += L) {
                const int i = ((p & ~(j - 1)) << 1) | (p & (j - 1)), l = i + j;
                const uint a = s_key[i], b = s_key[l];
                if ((a > b) == ((i & k) == 0)) {
                    s_key[i] = b;
                    s_key[l] = a;
                }
            }
            barrier();
        }

    // Sweep: chunk sums of +-1, their inclusive scan, then each chunk's best candidate.
    const int chunk = max(M / L, 1), first = int(t) * chunk;
    int sum = 0;
    for (int i = first; i < min(first + chunk, n); ++i) sum += (s_key[i] & 1u) != 0u ? 1 : -1;
    s_part[t] = sum;
    barrier();
    for (int offset = 1; offset < L; offset <<= 1) {
        int v = s_part[t];
        if (int(t) >= offset) v += s_part[int(t) - offset];
        barrier();
        s_part[t] = v;
        barrier();
    }
    int correct = s_n_shadowed + (t > 0u ? s_part[t - 1u] : 0);
    int best_c = -1, best_i = 0x7FFFFFFF;
    float best_m = -1.0;
    if (first < n) {
        float s_here = radius(first);
        for (int i = first; i < min(first + chunk, n); ++i) {
            correct += (s_key[i] & 1u) != 0u ? 1 : -1;
            float margin;
            if (i + 1 < n) {
                const float s_next = radius(i + 1);
                margin = 0.5 * (s_next - s_here) * axis_scale;
                s_here = s_next;
            } else {
                margin = u_edge;
            }
            if (best_c < 0 || correct > best_c || (correct == best_c && margin > best_m)) {
                best_c = correct;
                best_m = margin;
                best_i = i;
            }
        }
    }
    s_red_correct[t] = best_c;
    s_red_margin[t] = best_m;
    s_red_index[t] = best_i;
    barrier();
    for (int s = L >> 1; s > 0; s >>= 1) {
        if (int(t) < s && before(s_red_correct[t + uint(s)], s_red_margin[t + uint(s)], s_red_index[t + uint(s)],
                                 s_red_correct[t], s_red_margin[t], s_red_index[t])) {
            s_red_correct[t] = s_red_correct[t + uint(s)];
            s_red_margin[t] = s_red_margin[t + uint(s)];
            s_red_index[t] = s_red_index[t + uint(s)];
        }
        barrier();
    }
}

// [SECTION] Search state (invocation 0 only)
struct Shape {
    float cx, cy, angle, log_rho;
};
Shape g_best, g_move, g_cand;
float g_best_a, g_move_a;
int g_best_c, g_move_c;
float g_best_m, g_move_m;
float g_step[4];
int g_evaluations, g_refinements, g_stage, g_m;

void publish(Shape s) {
    g_cand = s;
    const float rho = exp(s.log_rho);
    s_shape = vec4(s.cx, s.cy, cos(s.angle), sin(s.angle));
    s_rho = vec2(1.0 / (rho * rho), min(rho, 1.0));
}

void write_ellipse(vec2 c, float angle, float a, float b) {
    const uint o = gl_WorkGroupID.x * 5u;
    ellipses[o] = c.x;
    ellipses[o + 1u] = c.y;
    ellipses[o + 2u] = angle;
    ellipses[o + 3u] = a;
    ellipses[o + 4u] = b;
    s_done = true;
}

void write_empty() { write_ellipse(vec2(2.0, 0.0), 0.0, 0.01, 0.01); }  // kEmptyEllipse

// The CPU's final ellipse from the best shape: radii clamped, a >= b, angle wrapped into [0, pi).
void finish() {
    if (g_best_a <= 0.0) {
        write_empty();
        return;
    }
    float angle = g_best.angle;
    float a = max(kMinRadius, g_best_a), b = max(kMinRadius, g_best_a * exp(g_best.log_rho));
    if (b > a) {
        const float t = a;
        a = b;
        b = t;
        angle += 0.5 * kPi;
    }
    angle = angle - kPi * trunc(angle / kPi);  // std::fmod
    if (angle < 0.0) angle += kPi;
    if (!(angle < kPi) || !(angle >= 0.0)) angle = 0.0;  // float rounding up to pi
    write_ellipse(vec2(g_best.cx, g_best.cy), angle, a, b);
}

// Move m (0..7) of the pattern search from the best shape: axis m / 2, sign + then -.
void publish_move() {
    Shape s = g_best;
    const float d = ((g_m & 1) == 0 ? 1.0 : -1.0) * g_step[g_m >> 1];
    if (g_m < 2) s.cx += d;
    else if (g_m < 4) s.cy += d;
    else if (g_m < 6) s.angle += d;
    else s.log_rho += d;
    s.log_rho = clamp(s.log_rho, log(kMinAspect), -log(kMinAspect));
    publish(s);
}

// A round of 8 moves if the budget allows, else the result.
void start_round() {
    if (g_refinements < kRefinements && g_evaluations + 8 <= kMaxEvaluations) {
        g_move = g_best;
        g_move_a = g_best_a;
        g_move_c = g_best_c;
        g_move_m = g_best_m;
        g_m = 0;
        publish_move();
    } else {
        finish();
    }
}

// Start: the special cases, else the covariance start published.
void begin_fit() {
    const int n = s_n;
    int n_lit = 0;
    vec2 mean = vec2(0.0);
    for (int i = 0; i < n; ++i)
        if (is_lit(i)) {
            ++n_lit;
            mean += s_P[i];
        }
    s_n_shadowed = n - n_lit;
    if (n_lit == 0) {
        write_empty();
        return;
    }
    if (n_lit == n) {
        write_ellipse(vec2(0.0), 0.0, 1.0 + u_edge, 1.0 + u_edge);
        return;
    }
    mean /= float(n_lit);
    float sxx = 0.0, sxy = 0.0, syy = 0.0;
    for (int i = 0; i < n; ++i)
        if (is_lit(i)) {
            const vec2 d = s_P[i] - mean;
            sxx += d.x * d.x;
            sxy += d.x * d.y;
            syy += d.y * d.y;
        }
    sxx /= float(n_lit);
    sxy /= float(n_lit);
    syy /= float(n_lit);
    const float tr = 0.5 * (sxx + syy), det = sxx * syy - sxy * sxy;
    const float disc = sqrt(max(0.0, tr * tr - det));
    const float l1 = tr + disc, l2 = max(0.0, tr - disc);
    // atan(0, 0) is undefined in GLSL; std::atan2 gives 0 (a single lit point, or a round cloud).
    const float phi0 = sxy == 0.0 && sxx == syy ? 0.0 : 0.5 * atan(2.0 * sxy, sxx - syy);
    const float rho0 = l1 > 0.0 ? clamp(sqrt(l2 / l1), 0.1, 1.0) : 1.0;
    g_step = float[4](0.1, 0.1, 0.3, 0.4);
    g_stage = 0;
    g_best = Shape(mean.x, mean.y, phi0, log(rho0));
    publish(g_best);
}

// Takes the evaluation of the published candidate (argmax in s_red_*[0]) and publishes the next
// one, or finishes.
void step_search() {
    const int n = s_n;
    int c = s_n_shadowed, i = s_red_index[0];
    float m = 0.0, a = 0.0;
    if (i >= 0 && i < n && better_than(s_red_correct[0], s_red_margin[0], c, m)) {
        c = s_red_correct[0];
        m = s_red_margin[0];
        a = i + 1 < n ? 0.5 * (radius(i) + radius(i + 1)) : radius(i) + u_edge / s_rho.y;
    }
    if (g_stage == 0) {  // the covariance start
        g_best_a = a;
        g_best_c = c;
        g_best_m = m;
        g_stage = 1;
        publish(Shape(g_best.cx, g_best.cy, 0.0, 0.0));
    } else if (g_stage < 3) {  // the circles at the mean and at the origin
        if (better_than(c, m, g_best_c, g_best_m)) {
            g_best = g_cand;
            g_best_a = a;
            g_best_c = c;
            g_best_m = m;
        }
        if (g_stage == 1) {
            g_stage = 2;
            publish(Shape(0.0, 0.0, 0.0, 0.0));
        } else {
            g_stage = 3;
            g_evaluations = 3;
            g_refinements = 0;
            start_round();
        }
    } else {  // a pattern move
        ++g_evaluations;
        if (better_than(c, m, g_move_c, g_move_m)) {
            g_move = g_cand;
            g_move_a = a;
            g_move_c = c;
            g_move_m = m;
        }
        if (++g_m < 8) {
            publish_move();
            return;
        }
        if (better_than(g_move_c, g_move_m, g_best_c, g_best_m)) {
            g_best = g_move;
            g_best_a = g_move_a;
            g_best_c = g_move_c;
            g_best_m = g_move_m;
        } else {
            for (int k = 0; k < 4; ++k) g_step[k] *= 0.5;
            ++g_refinements;
        }
        start_round();
    }
}

// [SECTION] Main: one group per texel of the batch
void main() {
    const uint t = gl_LocalInvocationID.x, texel = gl_WorkGroupID.x;
    const int n = int(counts[texel]);
    const int base = int(texel) * u_point_stride, words = (n + 31) >> 5;
    for (int i = int(t); i < n; i += L) s_P[i] = points[base + i];
    for (int w = int(t); w < words; w += L) s_lit[w] = lit_bits[int(texel) * u_lit_words + w];
    if (t == 0u) {
        s_n = n;
        int M = 2;
        while (M < n) M <<= 1;
        s_M = M;
        s_done = false;
    }
    barrier();
    if (t == 0u) {
        if (n == 0) write_empty();
        else begin_fit();
    }
    for (;;) {
        barrier();
        if (s_done) break;
        evaluate(t);  // ends with a barrier
        if (t == 0u) step_search();
    }
}
