#include "core/microgeom/ellipse.h"
#include "core/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

namespace mesolab::microgeom {

namespace {

// [SECTION] Per-texel fit
constexpr float kMinRadius = 0.01f;     // radii never shrink below this (keeps q finite)
constexpr float kMinAspect = 0.02f;     // b / a, and its inverse, stay within [kMinAspect, 1/kMinAspect]
constexpr int kMaxEvaluations = 120;    // pattern-search budget per texel
constexpr int kRefinements = 4;         // step halvings before the search stops

// Quality of one candidate: correctly classified points, then the margin (projected units).
struct Score {
    int correct = -1;
    float margin = -1.f;
    bool better_than(const Score& o) const { return correct != o.correct ? correct > o.correct : margin > o.margin + 1e-6f; }
};

// Candidate shape: centre, angle, log(b / a); the radius a follows from the sweep.
struct Shape {
    float cx = 0.f, cy = 0.f, angle = 0.f, log_rho = 0.f;
};

class Fitter {
public:
    Fitter(const std::vector<vec2>& points, float edge) : P_(&points), edge_(edge), keys_(points.size()) {}
    explicit Fitter(float edge) : edge_(edge) {}

    // Fits the ellipse for other projected points (a texel of a bent base, §5); lit as below.
    Ellipse fit(const std::vector<vec2>& points, const std::vector<uint8_t>& lit) {
        P_ = &points;
        keys_.resize(points.size());
        return fit(lit);
    }

    // Fits the ellipse for the lit flags of the projected points.
    Ellipse fit(const std::vector<uint8_t>& lit) {
        lit_ = lit.data();
        const int n = int(P_->size());
        int n_lit = 0;
        vec2 mean(0.f);
        for (int i = 0; i < n; ++i)
            if (lit_[i]) {
                ++n_lit;
                mean += (*P_)[size_t(i)];
            }
        if (n_lit == 0) return kEmptyEllipse;
        if (n_lit == n) return Ellipse{vec2(0.f), 0.f, 1.f + edge_, 1.f + edge_};
        mean /= float(n_lit);

        // Covariance start (§4): axes from the eigenvectors of the lit points' covariance.
        float sxx = 0.f, sxy = 0.f, syy = 0.f;
        for (int i = 0; i < n; ++i)
            if (lit_[i]) {
                const vec2 d = (*P_)[size_t(i)] - mean;
                sxx += d.x * d.x;
                sxy += d.x * d.y;
                syy += d.y * d.y;
            }
        sxx /= float(n_lit);
        sxy /= float(n_lit);
        syy /= float(n_lit);
        const float tr = 0.5f * (sxx + syy), det = sxx * syy - sxy * sxy;
        const float disc = std::sqrt(std::max(0.f, tr * tr - det));
        const float l1 = tr + disc, l2 = std::max(0.f, tr - disc);
        const float phi0 = 0.5f * std::atan2(2.f * sxy, sxx - syy);  // major-axis direction
        const float rho0 = l1 > 0.f ? std::clamp(std::sqrt(l2 / l1), 0.1f, 1.f) : 1.f;

        Shape best{mean.x, mean.y, phi0, std::log(rho0)};
        float best_a = 0.f;
        Score best_score = evaluate(best, best_a);
        for (const Shape& s : {Shape{mean.x, mean.y, 0.f, 0.f}, Shape{0.f, 0.f, 0.f, 0.f}}) {
            float a = 0.f;
            const Score sc = evaluate(s, a);
            if (sc.better_than(best_score)) best = s, best_a = a, best_score = sc;
        }

        // Pattern search over (cx, cy, angle, log rho): best of the 8 axis moves, halve the steps
        // when none improves.
        std::array<float, 4> step{0.1f, 0.1f, 0.3f, 0.4f};
        int evaluations = 3, refinements = 0;
        while (refinements < kRefinements && evaluations + 8 <= kMaxEvaluations) {
            Shape move = best;
            float move_a = best_a;
            Score move_score = best_score;
            for (int k = 0; k < 4; ++k)
                for (float sign : {1.f, -1.f}) {
                    Shape s = best;
                    float* c[4] = {&s.cx, &s.cy, &s.angle, &s.log_rho};
                    *c[k] += sign * step[size_t(k)];
                    s.log_rho = std::clamp(s.log_rho, std::log(kMinAspect), -std::log(kMinAspect));
                    float a = 0.f;
                    const Score sc = evaluate(s, a);
                    ++evaluations;
                    if (sc.better_than(move_score)) move = s, move_a = a, move_score = sc;
                }
            if (move_score.better_than(best_score)) {
                best = move, best_a = move_a, best_score = move_score;
            } else {
                for (float& st : step) st *= 0.5f;
                ++refinements;
            }
        }

        // Nothing inside beats every ellipse tried: the empty one.
        if (best_a <= 0.f) return kEmptyEllipse;
        Ellipse e;
        e.centre = vec2(best.cx, best.cy);
        e.angle = best.angle;
        e.a = std::max(kMinRadius, best_a);
        e.b = std::max(kMinRadius, best_a * std::exp(best.log_rho));
        if (e.b > e.a) {
            std::swap(e.a, e.b);
            e.angle += 0.5f * kPi;
        }
        e.angle = std::fmod(e.angle, kPi);
        if (e.angle < 0.f) e.angle += kPi;
        return e;
    }

private:
    // Best radius a for the shape (0: nothing inside is best) and its score. Keys are the squared
    // normalised radii s^2 as float bits (non-negative floats order like their bits) with the lit
    // flag in the lowest bit, so one integer sort orders the points.
    Score evaluate(const Shape& s, float& a_out) {
        const int n = int(P_->size());
        const float ca = std::cos(s.angle), sa = std::sin(s.angle), rho = std::exp(s.log_rho), inv_rho2 = 1.f / (rho * rho);
        int n_shadowed = 0;
        for (int i = 0; i < n; ++i) {
            const float dx = (*P_)[size_t(i)].x - s.cx, dy = (*P_)[size_t(i)].y - s.cy;
            const float u = ca * dx + sa * dy, v = -sa * dx + ca * dy;
            const float s2 = u * u + v * v * inv_rho2;
            uint32_t bits;
            std::memcpy(&bits, &s2, sizeof bits);
            keys_[size_t(i)] = (bits & ~1u) | (lit_[i] ? 1u : 0u);
            n_shadowed += lit_[i] ? 0 : 1;
        }
        std::sort(keys_.begin(), keys_.end());
        auto radius = [&](int i) {
            float s2;
            const uint32_t bits = keys_[size_t(i)] & ~1u;
            std::memcpy(&s2, &bits, sizeof s2);
            return std::sqrt(s2);
        };
        // k = -1: nothing inside (margin 0, so any ellipse as good wins).
        Score best{n_shadowed, 0.f};
        float best_a = 0.f;
        int correct = n_shadowed;
        // A gap in s is at least min(rho, 1) times as wide in projected units: margin = half of that.
        const float axis_scale = std::min(rho, 1.f);
        float s_here = radius(0);
        for (int i = 0; i < n; ++i) {
            correct += (keys_[size_t(i)] & 1u) ? 1 : -1;
            float margin, a;
            if (i + 1 < n) {
                const float s_next = radius(i + 1);
                margin = 0.5f * (s_next - s_here) * axis_scale;
                a = 0.5f * (s_here + s_next);
                s_here = s_next;
            } else {
                margin = edge_;
                a = s_here + edge_ / axis_scale;
            }
            const Score sc{correct, margin};
            if (sc.better_than(best)) best = sc, best_a = a;
        }
        a_out = best_a;
        return best;
    }

    const std::vector<vec2>* P_ = nullptr;
    float edge_;
    std::vector<uint32_t> keys_;
    const uint8_t* lit_ = nullptr;
};

void check_visibility(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis) {
    const int W = hf.width, H = hf.height;
    if (vis.width != W || vis.height != H || vis.count != dirs.size() ||
        vis.hit.size() != size_t(W) * size_t(H) * size_t(std::max(0, vis.count)))
        throw std::invalid_argument("microgeom ellipses: visibility is " + std::to_string(vis.width) + "x" +
                                    std::to_string(vis.height) + " with " + std::to_string(vis.count) +
                                    " directions, expected " + std::to_string(W) + "x" + std::to_string(H) + " with " +
                                    std::to_string(dirs.size()));
}

// [SECTION] Bent points (§5)
// Projected points and lit flags of texel (x, y) on a base bent by b, in direction-index order:
// no-hit upper directions lit and unbent, every other direction shadowed at its bent direction
// (kBelow: unbent, as bent_direction returns it) if that is above the base plane. For Bending{}
// these are exactly the points and flags of the flat fit.
void bent_points(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b, int x, int y,
                 std::vector<vec2>& points, std::vector<uint8_t>& lit) {
    points.clear();
    lit.clear();
    for (int j = 0; j < dirs.size(); ++j) {
        const vec3 d = dirs.d[size_t(j)];
        if (vis.at(j, x, y) == Visibility::kNoHit) {
            if (d.z > 0.f) points.push_back(vec2(d)), lit.push_back(1);
            continue;
        }
        const vec3 w = bent_direction(hf, dirs, vis, b, x, y, j);
        if (w.z > 0.f) points.push_back(vec2(w)), lit.push_back(0);
    }
}

// One map per bending, all in one pass over the texels, in parallel over rows (deterministic:
// every texel is fitted on its own).
std::vector<EllipseMap> fit_bent_maps(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis,
                                      const std::vector<Bending>& bends, const std::function<void(double)>& progress) {
    check_visibility(hf, dirs, vis);
    const int W = hf.width, H = hf.height;
    std::vector<EllipseMap> maps(bends.size());
    for (EllipseMap& m : maps) {
        m.width = W;
        m.height = H;
        m.edge = ellipse_edge(dirs.size());
        m.e.assign(size_t(std::max(0, W)) * size_t(std::max(0, H)), kEmptyEllipse);
    }
    if (progress) progress(0.0);
    if (maps.empty() || maps[0].e.empty()) {
        if (progress) progress(1.0);
        return maps;
    }
    const float edge = maps[0].edge;
    const int batches = std::min(H, 16);
    for (int batch = 0; batch < batches; ++batch) {
        const int y0 = int(long(H) * batch / batches), y1 = int(long(H) * (batch + 1) / batches);
        mesolab::parallel_for(tbb::blocked_range<int>(y0, y1), [&](const tbb::blocked_range<int>& rows) {
            Fitter fitter(edge);
            std::vector<vec2> points;
            std::vector<uint8_t> lit;
            points.reserve(size_t(dirs.size()));
            lit.reserve(size_t(dirs.size()));
            for (int y = rows.begin(); y < rows.end(); ++y)
                for (int x = 0; x < W; ++x)
                    for (size_t k = 0; k < bends.size(); ++k) {
                        bent_points(hf, dirs, vis, bends[k], x, y, points, lit);
                        maps[k].e[size_t(y) * size_t(W) + size_t(x)] = fitter.fit(points, lit);
                    }
        });
        if (progress) progress(double(y1) / double(H));
    }
    return maps;
}

// [SECTION] Quadratic-form interpolation (§5)
// Eigenvalue clamp: radii in [kMinRadius, kMaxRadius]. Fitted radii stay far below kMaxRadius
// (a <= (max |P - c| + edge) / kMinAspect, a few 10^2 at most), so only sums that are no longer
// (or barely) positive definite are affected.
constexpr double kMaxRadius = 1000.0;

// Centre and Q = R diag(1/a^2, 1/b^2) R^T.
struct QForm {
    double cx = 0, cy = 0, xx = 0, xy = 0, yy = 0;
};

QForm to_qform(const Ellipse& e) {
    const double c = std::cos(double(e.angle)), s = std::sin(double(e.angle));
    const double ia = 1.0 / (double(e.a) * double(e.a)), ib = 1.0 / (double(e.b) * double(e.b));
    return {double(e.centre.x), double(e.centre.y), c * c * ia + s * s * ib, c * s * (ia - ib), s * s * ia + c * c * ib};
}

Ellipse from_qform(const QForm& q) {
    const double m = 0.5 * (q.xx + q.yy), h = 0.5 * (q.xx - q.yy), d = std::sqrt(h * h + q.xy * q.xy);
    if (!std::isfinite(m) || !std::isfinite(d) || !std::isfinite(q.cx) || !std::isfinite(q.cy)) return kEmptyEllipse;
    const double lo = 1.0 / (kMaxRadius * kMaxRadius), hi = 1.0 / (double(kMinRadius) * double(kMinRadius));
    const double l_major = std::clamp(m - d, lo, hi), l_minor = std::clamp(m + d, lo, hi);
    // The eigenvector of the larger eigenvalue is at 0.5 atan2(2 xy, xx - yy); the major axis is
    // perpendicular to it. (Nearly) circular: angle 0.
    double angle = 0.0;
    if (d > 1e-9 * std::abs(m)) {
        angle = 0.5 * std::atan2(2.0 * q.xy, q.xx - q.yy) + 0.5 * 3.14159265358979323846;
        angle = std::fmod(angle, 3.14159265358979323846);
        if (angle < 0.0) angle += 3.14159265358979323846;
    }
    Ellipse e;
    e.centre = vec2(float(q.cx), float(q.cy));
    e.a = float(1.0 / std::sqrt(l_major));
    e.b = float(1.0 / std::sqrt(l_minor));
    e.angle = float(angle);
    if (!(e.angle < kPi) || !(e.angle >= 0.f)) e.angle = 0.f;  // float rounding up to pi
    return e;
}

bool is_empty(const Ellipse& e) {
    return e.centre.x == kEmptyEllipse.centre.x && e.centre.y == kEmptyEllipse.centre.y && e.a == kEmptyEllipse.a &&
           e.b == kEmptyEllipse.b && e.angle == kEmptyEllipse.angle;
}

// Sample coordinate along one axis: ku / step, clamped to [-1, 1]; 0 without a step.
double axis_weight(float k, float step) {
    if (step == 0.f || std::isnan(k)) return 0.0;
    return std::clamp(double(k) / double(step), -1.0, 1.0);
}
}  // namespace

// [SECTION] API
float ellipse_edge(int n) { return n > 0 ? 0.5f * std::sqrt(4.f * kPi / float(n)) : 0.f; }

EllipseMap fit_ellipses(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis,
                        const std::function<void(double)>& progress) {
    const int W = hf.width, H = hf.height;
    check_visibility(hf, dirs, vis);
    EllipseMap map;
    map.width = W;
    map.height = H;
    map.edge = ellipse_edge(dirs.size());
    map.e.assign(size_t(std::max(0, W)) * size_t(std::max(0, H)), kEmptyEllipse);
    if (progress) progress(0.0);
    if (map.e.empty()) {
        if (progress) progress(1.0);
        return map;
    }

    // The upper-hemisphere directions and their projections (the same for every texel).
    std::vector<int> up;
    std::vector<vec2> points;
    for (int i = 0; i < dirs.size(); ++i)
        if (dirs.d[size_t(i)].z > 0.f) {
            up.push_back(i);
            points.push_back(vec2(dirs.d[size_t(i)]));
        }

    // Batches of rows between progress calls (progress on the calling thread only).
    const int batches = std::min(H, 16);
    for (int batch = 0; batch < batches; ++batch) {
        const int y0 = int(long(H) * batch / batches), y1 = int(long(H) * (batch + 1) / batches);
        mesolab::parallel_for(tbb::blocked_range<int>(y0, y1), [&](const tbb::blocked_range<int>& rows) {
            Fitter fitter(points, map.edge);
            std::vector<uint8_t> lit(up.size());
            for (int y = rows.begin(); y < rows.end(); ++y)
                for (int x = 0; x < W; ++x) {
                    for (size_t j = 0; j < up.size(); ++j) lit[j] = vis.at(up[j], x, y) == Visibility::kNoHit ? 1 : 0;
                    map.e[size_t(y) * size_t(W) + size_t(x)] = fitter.fit(lit);
                }
        });
        if (progress) progress(double(y1) / double(H));
    }
    return map;
}

float ellipse_visibility(const Ellipse& e, vec3 w, float edge) {
    if (!(w.z > 0.f)) return 0.f;
    const float px = w.x - e.centre.x, py = w.y - e.centre.y;
    const float c = std::cos(e.angle), s = std::sin(e.angle);
    const float u = (c * px + s * py) / e.a, v = (-s * px + c * py) / e.b;
    const float q = u * u + v * v;
    if (!(edge > 0.f)) return q <= 1.f ? 1.f : 0.f;
    const float gu = u / e.a, gv = v / e.b;
    const float g = 2.f * std::sqrt(gu * gu + gv * gv);
    const float dist = (q - 1.f) / std::max(g, 1e-6f);
    return std::clamp(0.5f - dist / edge, 0.f, 1.f);
}

std::vector<float> ellipse_visibility_texture(const EllipseMap& map, const Heightfield& hf, vec3 w) {
    if (map.width != hf.width || map.height != hf.height || map.e.size() != size_t(hf.width) * size_t(hf.height))
        throw std::invalid_argument("microgeom ellipses: map is " + std::to_string(map.width) + "x" +
                                    std::to_string(map.height) + ", heightfield " + std::to_string(hf.width) + "x" +
                                    std::to_string(hf.height));
    std::vector<float> out(map.e.size(), 0.f);
    mesolab::parallel_for(0, hf.height, [&](int y) {
        for (int x = 0; x < hf.width; ++x)
            if (glm::dot(hf.normal(x, y), w) > 0.f) out[hf.index(x, y)] = ellipse_visibility(map.at(x, y), w, map.edge);
    });
    return out;
}

// [SECTION] Curved base (§5)
EllipseMap fit_ellipses(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                        const std::function<void(double)>& progress) {
    return std::move(fit_bent_maps(hf, dirs, vis, {b}, progress)[0]);
}

size_t CurvedEllipses::bytes() const { return flat.bytes() + u_pos.bytes() + u_neg.bytes() + v_pos.bytes() + v_neg.bytes(); }

CurvedEllipses fit_curved_ellipses(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, float bend_deg,
                                   const std::function<void(double)>& progress, const EllipseFit& fit) {
    if (!std::isfinite(bend_deg)) throw std::invalid_argument("microgeom ellipses: bend must be finite");
    CurvedEllipses c;
    c.bend_deg = std::abs(bend_deg);
    c.step_u = Bending::from_degrees(c.bend_deg, 0.f, hf.width, hf.height);
    c.step_v = Bending::from_degrees(0.f, c.bend_deg, hf.width, hf.height);
    // The fits elsewhere (the GPU) one curvature at a time, or all in one pass on the CPU.
    auto fit_all = [&](const std::vector<Bending>& bends) {
        if (!fit) return fit_bent_maps(hf, dirs, vis, bends, progress);
        std::vector<EllipseMap> out;
        for (size_t k = 0; k < bends.size(); ++k)
            out.push_back(fit(bends[k], [&](double f) { if (progress) progress((double(k) + f) / double(bends.size())); }));
        return out;
    };
    if (c.step_u.zero() && c.step_v.zero()) {
        c.flat = std::move(fit_all({Bending{}})[0]);
        c.u_pos = c.u_neg = c.v_pos = c.v_neg = c.flat;
        return c;
    }
    std::vector<EllipseMap> m = fit_all({Bending{}, c.step_u, Bending{-c.step_u.ku, 0.f}, c.step_v, Bending{0.f, -c.step_v.kv}});
    c.flat = std::move(m[0]);
    c.u_pos = std::move(m[1]);
    c.u_neg = std::move(m[2]);
    c.v_pos = std::move(m[3]);
    c.v_neg = std::move(m[4]);
    return c;
}

EllipseMap interpolate_ellipses(const CurvedEllipses& c, Bending b) {
    const size_t n = c.flat.e.size();
    for (const EllipseMap* m : {&c.flat, &c.u_pos, &c.u_neg, &c.v_pos, &c.v_neg})
        if (m->width != c.flat.width || m->height != c.flat.height || m->e.size() != n ||
            n != size_t(std::max(0, c.flat.width)) * size_t(std::max(0, c.flat.height)))
            throw std::invalid_argument("microgeom ellipses: the five curvature samples differ in size");
    const double tu = axis_weight(b.ku, c.step_u.ku), tv = axis_weight(b.kv, c.step_v.kv);
    if (tu == 0.0 && tv == 0.0) return c.flat;  // exactly the flat fit
    EllipseMap out;
    out.width = c.flat.width;
    out.height = c.flat.height;
    out.edge = c.flat.edge;
    out.e.resize(n);
    const EllipseMap& su = tu > 0.0 ? c.u_pos : c.u_neg;
    const EllipseMap& sv = tv > 0.0 ? c.v_pos : c.v_neg;
    const double wu = std::abs(tu), wv = std::abs(tv);
    // Nearest sample to (wu, wv): 0 flat, 1 u, 2 v (ties to the earlier).
    int nearest = 0;
    double best = wu * wu + wv * wv;
    if (const double du = (1.0 - wu) * (1.0 - wu) + wv * wv; du < best) nearest = 1, best = du;
    if (const double dv = wu * wu + (1.0 - wv) * (1.0 - wv); dv < best) nearest = 2;
    const int W = std::max(1, out.width);
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, n, size_t(W)), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t p = r.begin(); p < r.end(); ++p) {
            const Ellipse* s[3] = {&c.flat.e[p], &su.e[p], &sv.e[p]};
            const Ellipse* near = s[nearest];
            if (is_empty(*near)) {
                out.e[p] = kEmptyEllipse;
                continue;
            }
            for (const Ellipse*& x : s)
                if (is_empty(*x)) x = near;
            const QForm f = to_qform(*s[0]), u = to_qform(*s[1]), v = to_qform(*s[2]);
            auto mix = [&](double QForm::*m) { return f.*m + wu * (u.*m - f.*m) + wv * (v.*m - f.*m); };
            out.e[p] = from_qform({mix(&QForm::cx), mix(&QForm::cy), mix(&QForm::xx), mix(&QForm::xy), mix(&QForm::yy)});
        }
    });
    return out;
}
}  // namespace mesolab::microgeom
