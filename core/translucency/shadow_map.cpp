// Technique translucency: shadow maps of the lights over the object, for the illumination map (see translucency.h).
#include "core/translucency/translucency.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "core/basic/basic.h"
#include "core/error.h"
#include "core/image.h"
#include "core/raster.h"

#include <glm/gtc/matrix_transform.hpp>
#include <tbb/blocked_range.h>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>
#include <utility>

namespace mesolab::translucency {

// [SECTION] Shadow maps
ShadowMap shadow_frame(const Light& l, vec3 centre, float radius, int res) {
    ShadowMap m;
    m.res = res;
    m.point = l.point;
    radius = std::max(radius, 1e-6f);
    mat4 view, proj;
    if (!l.point) {
        m.dir = -glm::normalize(l.direction);
        m.origin = centre - m.dir * (1.01f * radius);
        const vec3 up = std::abs(m.dir.z) < 0.9f ? vec3(0.f, 0.f, 1.f) : vec3(1.f, 0.f, 0.f);
        view = glm::lookAt(m.origin, centre, up);
        proj = glm::ortho(-radius, radius, -radius, radius, 0.f, 2.03f * radius);
        m.bias = 2.f * (2.f * radius / float(res));
        m.valid = true;
    } else {
        m.origin = l.position;
        const vec3 d = centre - l.position;
        const float dist = glm::length(d);
        if (!(dist > 1.01f * radius)) return m;  // inside the bounds: no shadow map
        const vec3 dir = d / dist;
        const vec3 up = std::abs(dir.z) < 0.9f ? vec3(0.f, 0.f, 1.f) : vec3(1.f, 0.f, 0.f);
        const float half = std::asin(std::min(1.f, radius / dist)) * 1.02f;
        view = glm::lookAt(l.position, centre, up);
        proj = glm::perspective(2.f * half, 1.f, std::max(dist - 1.01f * radius, 1e-4f * dist), dist + 1.01f * radius);
        m.bias = 2.f * (2.f * dist * std::tan(half) / float(res));
        m.valid = true;
    }
    m.view_proj = proj * view;
    return m;
}

float ShadowMap::visibility(vec3 p) const {
    if (!valid || depth.empty()) return 1.f;
    const vec4 c = view_proj * vec4(p, 1.f);
    if (!(c.w > 0.f)) return 1.f;
    const float nx = c.x / c.w, ny = c.y / c.w;
    if (!(std::abs(nx) <= 1.f && std::abs(ny) <= 1.f)) return 1.f;
    const int x = std::clamp(int(std::floor((nx * 0.5f + 0.5f) * float(res))), 0, res - 1);
    const int y = std::clamp(int(std::floor((0.5f - 0.5f * ny) * float(res))), 0, res - 1);
    return distance(p) - bias <= depth[size_t(y) * size_t(res) + size_t(x)] ? 1.f : 0.f;
}

// Distances only, rasterised the way GL does (pixel centres, a LESS test; edges shared by two
// triangles can go either way, which only moves silhouettes by a texel). Each triangle is set up
// once (its barycentrics and depth as affine functions of the pixel centre), binned by bands of
// rows, and the bands are filled in parallel.
ShadowMap make_shadow_map(const TriMesh& display, const mat4& model, const Light& l, int res) {
    if (display.position.empty()) return ShadowMap{};
    std::vector<vec3> world(display.position.size());
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, world.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) world[i] = vec3(model * vec4(display.position[i], 1.f));
    });
    Bounds b{vec3(INFINITY), vec3(-INFINITY)};
    for (const vec3& p : world) b.lo = glm::min(b.lo, p), b.hi = glm::max(b.hi, p);
    const vec3 centre = 0.5f * (b.lo + b.hi);
    ShadowMap m = shadow_frame(l, centre, 0.5f * glm::length(b.hi - b.lo), res);
    if (!m.valid) return m;
    m.depth.assign(size_t(res) * size_t(res), std::numeric_limits<float>::infinity());
    // Window position (x right, y down from the top row), 1/w and the distance over w, per vertex.
    struct V {
        vec2 p;
        float inv_w, d_over_w;
        bool ok;
    };
    std::vector<V> v(world.size());
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, world.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const vec4 c = m.view_proj * vec4(world[i], 1.f);
            V& o = v[i];
            o.ok = c.w > 1e-12f;
            if (!o.ok) continue;
            o.inv_w = 1.f / c.w;
            o.p = vec2((c.x * o.inv_w * 0.5f + 0.5f) * float(res), (0.5f - 0.5f * c.y * o.inv_w) * float(res));
            o.d_over_w = m.distance(world[i]) * o.inv_w;
        }
    });
    // Per triangle: w_k(x, y) = e[k].x + x e[k].y + y e[k].z at pixel centre (x, y) (w_2 = 1 − w_0 − w_1
    // as an affine function too), 1/w and d/w likewise (d = d/w ÷ 1/w; a directional light's 1/w is 1),
    // and the pixel rows and columns it can cover.
    struct Tri {
        vec3 e[3], iw, dw;
        int x0, x1, y0, y1;  // y0 > y1: nothing to draw
    };
    const size_t T = display.index.size() / 3;
    std::vector<Tri> tri(T);
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, T, 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t f = r.begin(); f != r.end(); ++f) {
            Tri& t = tri[f];
            t.y0 = 1, t.y1 = 0;
            const V& a = v[display.index[3 * f]];
            const V& bb = v[display.index[3 * f + 1]];
            const V& c = v[display.index[3 * f + 2]];
            if (!a.ok || !bb.ok || !c.ok) continue;
            const float area = (bb.p.x - a.p.x) * (c.p.y - a.p.y) - (bb.p.y - a.p.y) * (c.p.x - a.p.x);
            if (!(std::abs(area) > 1e-12f)) continue;
            t.y0 = std::max(0, int(std::ceil(std::min({a.p.y, bb.p.y, c.p.y}) - 0.5f)));
            t.y1 = std::min(res - 1, int(std::floor(std::max({a.p.y, bb.p.y, c.p.y}) - 0.5f)));
            t.x0 = std::max(0, int(std::ceil(std::min({a.p.x, bb.p.x, c.p.x}) - 0.5f)));
            t.x1 = std::min(res - 1, int(std::floor(std::max({a.p.x, bb.p.x, c.p.x}) - 0.5f)));
            if (t.x0 > t.x1) t.y0 = 1, t.y1 = 0;
            const float inv_area = 1.f / area;
            // w_0 = ((b − p) × (c − p)) / area, w_1 = ((c − p) × (a − p)) / area.
            const auto edge = [&](vec2 p, vec2 q) {
                return vec3((p.x * q.y - p.y * q.x) * inv_area, (p.y - q.y) * inv_area, (q.x - p.x) * inv_area);
            };
            t.e[0] = edge(bb.p, c.p);
            t.e[1] = edge(c.p, a.p);
            t.e[2] = vec3(1.f, 0.f, 0.f) - t.e[0] - t.e[1];
            t.iw = c.inv_w * t.e[2] + a.inv_w * t.e[0] + bb.inv_w * t.e[1];
            t.dw = c.d_over_w * t.e[2] + a.d_over_w * t.e[0] + bb.d_over_w * t.e[1];
        }
    });
    const int bands = std::max(1, std::min(64, res / 16));
    const int band_h = (res + bands - 1) / bands;
    // Copies of the records per band, so that each band reads its triangles in sequence.
    std::vector<std::vector<Tri>> binned(static_cast<size_t>(bands));
    for (const Tri& t : tri)
        for (int k = t.y0 / band_h; t.y0 <= t.y1 && k <= t.y1 / band_h; ++k) binned[size_t(k)].push_back(t);
    const bool perspective = m.point;
    typedef float f4 __attribute__((vector_size(16)));
    typedef int32_t i4 __attribute__((vector_size(16)));
    mesolab::parallel_for(0, bands, [&](int band) {
        const int y_lo = band * band_h, y_hi = std::min(res, y_lo + band_h);
        for (const Tri& t : binned[size_t(band)]) {
            const int y0 = std::max(y_lo, t.y0), y1 = std::min(y_hi - 1, t.y1);
            // Four pixels at a time across the triangle's columns (the last block shifted left to
            // stay inside the row): every pixel tested exactly, the depth kept where it is nearer.
            const float px = float(t.x0) + 0.5f;
            const int span = t.x1 - t.x0;
            for (int y = y0; y <= y1; ++y) {
                const float py = float(y) + 0.5f;
                const float w0r = t.e[0].x + px * t.e[0].y + py * t.e[0].z, w1r = t.e[1].x + px * t.e[1].y + py * t.e[1].z;
                const float w2r = t.e[2].x + px * t.e[2].y + py * t.e[2].z;
                const float iwr = t.iw.x + px * t.iw.y + py * t.iw.z, dwr = t.dw.x + px * t.dw.y + py * t.dw.z;
                float* row = m.depth.data() + size_t(y) * size_t(res);
                for (int s0 = 0; s0 <= span; s0 += 4) {
                    const int xb = std::min(t.x0 + s0, res - 4);
                    const f4 s = f4{0.f, 1.f, 2.f, 3.f} + float(xb - t.x0);
                    const f4 w0 = w0r + s * t.e[0].y, w1 = w1r + s * t.e[1].y, w2 = w2r + s * t.e[2].y;
                    const f4 dw = dwr + s * t.dw.y;
                    const f4 d = perspective ? dw / (iwr + s * t.iw.y) : dw;
                    f4 old;
                    std::memcpy(&old, row + xb, sizeof old);
                    const i4 in = (w0 >= 0.f) & (w1 >= 0.f) & (w2 >= 0.f) & (s >= 0.f) & (s <= float(span)) & (d < old);
                    const f4 out = in ? d : old;
                    std::memcpy(row + xb, &out, sizeof out);
                }
            }
        }
    });
    return m;
}
}  // namespace mesolab::translucency
