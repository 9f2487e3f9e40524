#include "core/raster.h"
#include "core/parallel.h"
#include "core/profile.h"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace mesolab {

// [SECTION] Rasteriser constants and per-stage data
namespace {

constexpr int kSubPixelBits = 8;               // window positions snap to 1/256 pixel, as GPUs do
constexpr int64_t kSubPixel = int64_t(1) << kSubPixelBits;
constexpr int64_t kHalfPixel = kSubPixel / 2;  // pixel centres are at (x+0.5, y+0.5)
constexpr int kTileW = 128, kTileH = 32;  // wide tiles: long runs of G-buffer writes
constexpr int kMaxImageSize = 1 << 16;
constexpr float kMinClipW = 1e-6f;  // w > epsilon after clipping, whatever the projection
// Window coordinates stay within +-2^20 pixels (guard band), so fixed-point coordinates fit in
// 29 bits and edge functions (products of two differences) in 60 bits of an int64_t.
constexpr double kGuardBandPixels = double(1 << 20);
constexpr size_t kSetupChunk = 1024;  // source triangles per setup task

// Vertex stage output: world-space attributes of one vertex (together, for locality).
struct VertexAttributes {
    vec3 position, normal, tangent;
    vec2 uv;
};

// Vertex stage output of one draw item.
struct ShadedVertices {
    std::vector<vec4> clip;
    std::vector<VertexAttributes> attr;
};

// A clip-space polygon vertex: its position and its barycentric coordinates in the source
// triangle (attributes are affine in clip space, so clipping interpolates these linearly).
struct ClipVertex {
    vec4 clip;
    vec3 bary;
};

// A triangle ready for scan conversion, counter-clockwise in GL window space (y up).
struct ScreenTriangle {
    std::array<int32_t, 3> x, y;      // window position in 1/kSubPixel pixels
    std::array<float, 3> z;           // window depth in [0,1]
    std::array<float, 3> inv_w;       // 1 / clip w, for perspective-correct interpolation
    vec2 lambda_dx{0.f}, lambda_dy{0.f};  // change of (lambda_1, lambda_2) over one pixel in x and in y
    std::array<vec3, 3> bary;         // barycentrics of each vertex in the source triangle
    std::array<uint32_t, 3> src;      // source vertex indices (bary refers to these)
    int64_t area2 = 0;                // twice the signed area in fixed-point units, > 0
    double inv_area2 = 0.0;
    int px0 = 0, px1 = -1, py0 = 0, py1 = -1;  // covered pixel bounds, inclusive, in the viewport
    uint32_t item = 0;                // draw item
    bool clipped = false;             // false: bary is the identity (vertex k is src[k])
};

int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Edge function of the directed edge a->b at p: twice the signed area of (a, b, p); positive
// when p is to the left (inside a counter-clockwise triangle in y-up window space).
int64_t edge_function(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t px, int64_t py) {
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// Top-left fill rule in GL's y-up window space, for a counter-clockwise triangle: a top edge is
// horizontal with the interior below it (it runs towards -x); a left edge runs downwards.
bool is_top_left(int64_t ax, int64_t ay, int64_t bx, int64_t by) {
    return (ay == by && bx < ax) || by < ay;
}

bool is_finite(vec4 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w); }

// Unit v, or 0 when v is zero or not finite.
inline vec3 normalize_or_zero(vec3 v) {
    const float len2 = glm::dot(v, v);
    return (len2 > 0.f && len2 <= std::numeric_limits<float>::max()) ? v * (1.f / std::sqrt(len2)) : vec3(0.f);
}
}  // namespace

// [SECTION] Vertex stage
namespace {

void shade_vertices(const DrawItem& item, const RasterCamera& cam, ShadedVertices& sv) {
    const TriMesh& m = *item.mesh;
    const size_t n = m.vertex_count();
    const bool has_normal = m.normal.size() == n, has_tangent = m.tangent.size() == n, has_uv = m.uv.size() == n;
    const mat4 clip_from_object = cam.proj * cam.view * item.model;
    const mat3 model3(item.model);
    const mat3 normal_matrix = glm::transpose(glm::inverse(model3));

    sv.clip.resize(n);
    sv.attr.resize(n);
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const vec4 p(m.position[i], 1.f);
            const vec2 uv = has_uv ? m.uv[i] : vec2(0.f);
            sv.clip[i] = cam.texture_space ? vec4(uv * 2.f - 1.f, 0.f, 1.f) : clip_from_object * p;
            VertexAttributes& a = sv.attr[i];
            a.position = vec3(item.model * p);
            a.normal = has_normal ? normalize_or_zero(normal_matrix * m.normal[i]) : vec3(0.f);
            a.tangent = has_tangent ? normalize_or_zero(model3 * m.tangent[i]) : vec3(0.f);
            a.uv = uv;
        }
    });
}
}  // namespace

// [SECTION] Clipping and triangle setup
namespace {

// Clip planes as signed distances (inside >= 0): w > epsilon, near and far (-w <= z <= w) as in
// GL, and a guard band |x|, |y| <= g w that keeps fixed-point window coordinates in range.
constexpr int kClipPlanes = 7;

inline float plane_distance(int plane, vec4 c, float g) {
    switch (plane) {
        case 0: return c.w - kMinClipW;
        case 1: return c.z + c.w;
        case 2: return c.w - c.z;
        case 3: return g * c.w - c.x;
        case 4: return g * c.w + c.x;
        case 5: return g * c.w - c.y;
        default: return g * c.w + c.y;
    }
}

// Lexicographic order on clip positions: an edge shared by two triangles is intersected from the
// same end in both, so both get bit-identical new vertices and no crack opens along it.
bool clip_less(vec4 a, vec4 b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    if (a.z != b.z) return a.z < b.z;
    return a.w < b.w;
}

ClipVertex intersect(const ClipVertex& a, float da, const ClipVertex& b, float db) {
    if (clip_less(b.clip, a.clip)) return intersect(b, db, a, da);
    const float t = da / (da - db);
    return {a.clip + (b.clip - a.clip) * t, a.bary + (b.bary - a.bary) * t};
}

// Sutherland-Hodgman against every plane some vertex lies outside. At most 3 + kClipPlanes
// vertices come out.
int clip_polygon(std::array<ClipVertex, 3 + kClipPlanes>& poly, int n, float g) {
    std::array<ClipVertex, 3 + kClipPlanes> out;
    std::array<float, 3 + kClipPlanes> d;
    for (int plane = 0; plane < kClipPlanes && n >= 3; ++plane) {
        bool any_outside = false;
        for (int i = 0; i < n; ++i) {
            d[size_t(i)] = plane_distance(plane, poly[size_t(i)].clip, g);
            any_outside |= !(d[size_t(i)] >= 0.f);
        }
        if (!any_outside) continue;
        int m = 0;
        for (int i = 0; i < n; ++i) {
            const int j = (i + 1) % n;
            const float di = d[size_t(i)], dj = d[size_t(j)];
            if (di >= 0.f) out[size_t(m++)] = poly[size_t(i)];
            if ((di >= 0.f) != (dj >= 0.f)) out[size_t(m++)] = intersect(poly[size_t(i)], di, poly[size_t(j)], dj);
        }
        poly = out;
        n = m;
    }
    return n;
}

// Viewport transform and snapping of three clipped vertices; false when the triangle has zero
// area or covers no pixel centre's bounding box.
bool setup_triangle(const ClipVertex& c0, const ClipVertex& c1, const ClipVertex& c2, int width, int height,
                    ScreenTriangle& t) {
    const std::array<const ClipVertex*, 3> c{&c0, &c1, &c2};
    const float half_w = 0.5f * float(width), half_h = 0.5f * float(height);
    for (size_t k = 0; k < 3; ++k) {
        const vec4 p = c[k]->clip;
        const float inv_w = 1.f / p.w;
        const float xw = (p.x * inv_w + 1.f) * half_w, yw = (p.y * inv_w + 1.f) * half_h;
        t.x[k] = int32_t(std::llrint(double(xw) * double(kSubPixel)));
        t.y[k] = int32_t(std::llrint(double(yw) * double(kSubPixel)));
        t.z[k] = std::clamp((p.z * inv_w + 1.f) * 0.5f, 0.f, 1.f);
        t.inv_w[k] = inv_w;
        t.bary[k] = c[k]->bary;
    }
    t.area2 = edge_function(t.x[0], t.y[0], t.x[1], t.y[1], t.x[2], t.y[2]);
    if (t.area2 == 0) return false;
    if (t.area2 < 0) {  // no culling: make it counter-clockwise
        std::swap(t.x[1], t.x[2]);
        std::swap(t.y[1], t.y[2]);
        std::swap(t.z[1], t.z[2]);
        std::swap(t.inv_w[1], t.inv_w[2]);
        std::swap(t.bary[1], t.bary[2]);
        std::swap(t.src[1], t.src[2]);
        t.area2 = -t.area2;
    }
    t.inv_area2 = 1.0 / double(t.area2);
    // Screen-space barycentrics are the edge functions (scan_triangle) over twice the area.
    const double s = double(kSubPixel) * t.inv_area2;
    t.lambda_dx = vec2(float(-(double(t.y[0]) - double(t.y[2])) * s), float(-(double(t.y[1]) - double(t.y[0])) * s));
    t.lambda_dy = vec2(float((double(t.x[0]) - double(t.x[2])) * s), float((double(t.x[1]) - double(t.x[0])) * s));
    const int64_t x_lo = std::min({t.x[0], t.x[1], t.x[2]}), x_hi = std::max({t.x[0], t.x[1], t.x[2]});
    const int64_t y_lo = std::min({t.y[0], t.y[1], t.y[2]}), y_hi = std::max({t.y[0], t.y[1], t.y[2]});
    // Pixels whose centre lies in the bounding box: x*256 + 128 in [x_lo, x_hi].
    t.px0 = int(std::max<int64_t>(0, floor_div(x_lo - kHalfPixel + kSubPixel - 1, kSubPixel)));
    t.px1 = int(std::min<int64_t>(width - 1, floor_div(x_hi - kHalfPixel, kSubPixel)));
    t.py0 = int(std::max<int64_t>(0, floor_div(y_lo - kHalfPixel + kSubPixel - 1, kSubPixel)));
    t.py1 = int(std::min<int64_t>(height - 1, floor_div(y_hi - kHalfPixel, kSubPixel)));
    return t.px0 <= t.px1 && t.py0 <= t.py1;
}

// Clip and set up source triangles [begin, end) of one item, appending in source order.
void setup_triangles(const TriMesh& m, const ShadedVertices& sv, uint32_t item, size_t begin, size_t end,
                     int width, int height, float g, std::vector<ScreenTriangle>& out) {
    for (size_t tri = begin; tri < end; ++tri) {
        const std::array<uint32_t, 3> src{m.index[3 * tri], m.index[3 * tri + 1], m.index[3 * tri + 2]};
        const std::array<vec4, 3> p{sv.clip[src[0]], sv.clip[src[1]], sv.clip[src[2]]};
        if (!is_finite(p[0]) || !is_finite(p[1]) || !is_finite(p[2])) continue;
        // Trivial reject: all three vertices outside one frustum plane (w, near, far, or the
        // viewport's own x/y planes); trivial accept: inside all clip planes.
        bool rejected = false, inside = true;
        for (int plane = 0; plane < 3; ++plane) {
            const float d0 = plane_distance(plane, p[0], g), d1 = plane_distance(plane, p[1], g),
                        d2 = plane_distance(plane, p[2], g);
            rejected |= d0 < 0.f && d1 < 0.f && d2 < 0.f;
            inside &= d0 >= 0.f && d1 >= 0.f && d2 >= 0.f;
        }
        for (int plane = 3; plane < kClipPlanes; ++plane) {
            rejected |= plane_distance(plane, p[0], 1.f) < 0.f && plane_distance(plane, p[1], 1.f) < 0.f &&
                        plane_distance(plane, p[2], 1.f) < 0.f;
            inside &= plane_distance(plane, p[0], g) >= 0.f && plane_distance(plane, p[1], g) >= 0.f &&
                      plane_distance(plane, p[2], g) >= 0.f;
        }
        if (rejected) continue;

        std::array<ClipVertex, 3 + kClipPlanes> poly;
        poly[0] = {p[0], vec3(1.f, 0.f, 0.f)};
        poly[1] = {p[1], vec3(0.f, 1.f, 0.f)};
        poly[2] = {p[2], vec3(0.f, 0.f, 1.f)};
        const int n = inside ? 3 : clip_polygon(poly, 3, g);
        for (int k = 1; k + 1 < n; ++k) {  // fan
            ScreenTriangle t;
            t.src = src;
            if (!setup_triangle(poly[0], poly[size_t(k)], poly[size_t(k + 1)], width, height, t)) continue;
            t.item = item;
            t.clipped = !inside;
            out.push_back(t);
        }
    }
}
}  // namespace

// [SECTION] Scan conversion and G-buffer resolve
namespace {

// Visibility buffers of one tile (row stride kTileW): depth, the visible triangle and its
// screen-space barycentrics (lambda_1, lambda_2) at the pixel centre.
struct TileBuffers {
    std::vector<float> depth;
    std::vector<int32_t> tri_id;
    std::vector<vec2> lambda;
    TileBuffers() : depth(size_t(kTileW) * kTileH), tri_id(depth.size()), lambda(depth.size()) {}
};

// Scan-convert `t` inside the pixel rectangle [x0,x1]x[y0,y1] (GL window coordinates) of the
// tile with origin (tx, ty), with a LESS depth test. The covered span of each row comes from
// the exact integer edge functions (stepped incrementally), so no pixel is tested twice.
void scan_triangle(const ScreenTriangle& t, int32_t id, int x0, int x1, int y0, int y1, int tx, int ty,
                   TileBuffers& buf) {
    std::array<int64_t, 3> e_row, step_x, step_y, bias;
    const int64_t sx0 = int64_t(x0) * kSubPixel + kHalfPixel, sy0 = int64_t(y0) * kSubPixel + kHalfPixel;
    for (size_t k = 0; k < 3; ++k) {
        const size_t a = (k + 1) % 3, b = (k + 2) % 3;  // edge opposite vertex k
        e_row[k] = edge_function(t.x[a], t.y[a], t.x[b], t.y[b], sx0, sy0);
        step_x[k] = -(int64_t(t.y[b]) - t.y[a]) * kSubPixel;
        step_y[k] = (int64_t(t.x[b]) - t.x[a]) * kSubPixel;
        bias[k] = is_top_left(t.x[a], t.y[a], t.x[b], t.y[b]) ? 0 : -1;
        e_row[k] += bias[k];  // covered iff every biased edge function is >= 0
    }
    const double dz1 = double(t.z[1]) - double(t.z[0]), dz2 = double(t.z[2]) - double(t.z[0]);
    const int64_t last = x1 - x0;
    for (int y = y0; y <= y1; ++y, e_row[0] += step_y[0], e_row[1] += step_y[1], e_row[2] += step_y[2]) {
        // Covered span [n_lo, n_hi] of this row (n = x - x0): each edge function is affine in n,
        // so every edge bounds n from one side; exact integer arithmetic.
        int64_t n_lo = 0, n_hi = last;
        for (size_t k = 0; k < 3; ++k) {
            const int64_t e = e_row[k], s = step_x[k];
            if (s > 0) {
                if (e < 0) n_lo = std::max(n_lo, (-e + s - 1) / s);
            } else if (s < 0) {
                if (e < 0) n_hi = -1;
                else if (e + s * last < 0) n_hi = std::min(n_hi, e / -s);
            } else if (e < 0) {
                n_hi = -1;
            }
        }
        if (n_lo > n_hi) continue;
        const size_t row = size_t(y - ty) * kTileW;
        float* depth_row = buf.depth.data() + row;
        int64_t e1 = e_row[1] + step_x[1] * n_lo - bias[1], e2 = e_row[2] + step_x[2] * n_lo - bias[2];
        for (int64_t n = n_lo; n <= n_hi; ++n, e1 += step_x[1], e2 += step_x[2]) {
            // Window depth, linear in screen space.
            const double l1 = double(e1) * t.inv_area2, l2 = double(e2) * t.inv_area2;
            const float z = float(double(t.z[0]) + l1 * dz1 + l2 * dz2);
            const size_t p = size_t(x0 + n - tx);
            if (z < depth_row[p]) {
                depth_row[p] = z;
                buf.tri_id[row + p] = id;
                buf.lambda[row + p] = vec2(float(l1), float(l2));
            }
        }
    }
}

// Perspective-correct barycentrics (weights of t.src) from screen-space ones (lambda_1, lambda_2).
inline vec3 source_barycentrics(const ScreenTriangle& t, vec2 lambda) {
    const vec3 w((1.f - lambda.x - lambda.y) * t.inv_w[0], lambda.x * t.inv_w[1], lambda.y * t.inv_w[2]);
    const float inv_sum = 1.f / (w.x + w.y + w.z);
    if (!t.clipped) return w * inv_sum;
    return (t.bary[0] * w.x + t.bary[1] * w.y + t.bary[2] * w.z) * inv_sum;
}
}  // namespace

// [SECTION] Scratch memory
namespace {

// Buffers of one rasterize() call, kept between calls (re-allocating megabytes per frame costs
// page faults). A pool rather than thread_local storage: a TBB thread waiting inside one call
// may run a task of another call.
struct Scratch {
    std::vector<ShadedVertices> shaded;
    std::vector<std::vector<ScreenTriangle>> chunk_triangles;
    std::vector<const ScreenTriangle*> tris;  // all set-up triangles in submission order
    std::vector<uint32_t> bin_start, bins, bin_fill;
};

class ScratchLease {
public:
    ScratchLease() {
        std::lock_guard<std::mutex> lock(mutex_);
        if (pool_.empty()) scratch_ = std::make_unique<Scratch>();
        else {
            scratch_ = std::move(pool_.back());
            pool_.pop_back();
        }
    }
    ~ScratchLease() {
        std::lock_guard<std::mutex> lock(mutex_);
        if (pool_.size() < 4) pool_.push_back(std::move(scratch_));
    }
    ScratchLease(const ScratchLease&) = delete;
    ScratchLease& operator=(const ScratchLease&) = delete;
    Scratch& operator*() { return *scratch_; }

private:
    std::unique_ptr<Scratch> scratch_;
    static inline std::mutex mutex_;
    static inline std::vector<std::unique_ptr<Scratch>> pool_;
};
}  // namespace

// [SECTION] rasterize()
void rasterize(const std::vector<DrawItem>& items, const RasterCamera& cam, GBuffer& out) {
    if (cam.width > kMaxImageSize || cam.height > kMaxImageSize)
        throw std::invalid_argument("rasterize: image larger than 65536 pixels on a side");
    const int width = std::max(cam.width, 0), height = std::max(cam.height, 0);
    const size_t n_pixels = size_t(width) * size_t(height);
    out.width = width;
    out.height = height;
    out.depth.resize(n_pixels);
    out.object.resize(n_pixels);
    out.primitive.resize(n_pixels);
    out.position.resize(n_pixels);
    out.normal.resize(n_pixels);
    out.tangent.resize(n_pixels);
    out.uv.resize(n_pixels);
    const bool derivatives = std::any_of(items.begin(), items.end(), [](const DrawItem& i) { return i.uv_derivatives; });
    out.uv_dx.resize(derivatives ? n_pixels : 0);
    out.uv_dy.resize(derivatives ? n_pixels : 0);
    if (n_pixels == 0) return;

    // Vertex stage, then clipping and setup in chunks of source triangles (kept in submission
    // order, which the LESS test needs to resolve equal depths like GL).
    const float guard = float(kGuardBandPixels / double(std::max(width, height)));
    ScratchLease lease;
    Scratch& scratch = *lease;
    std::vector<ShadedVertices>& shaded = scratch.shaded;
    if (shaded.size() < items.size()) shaded.resize(items.size());
    struct Chunk {
        uint32_t item;
        size_t begin, end;
    };
    std::vector<Chunk> chunks;
    std::optional<ProfileScope> phase;
    phase.emplace("vertices");
    for (size_t i = 0; i < items.size(); ++i) {
        const TriMesh* m = items[i].mesh;
        if (!m || m->triangle_count() == 0) continue;
        for (uint32_t v : m->index)
            if (v >= m->vertex_count()) throw std::invalid_argument("rasterize: mesh index out of range");
        shade_vertices(items[i], cam, shaded[i]);
        for (size_t b = 0; b < m->triangle_count(); b += kSetupChunk)
            chunks.push_back({uint32_t(i), b, std::min(b + kSetupChunk, m->triangle_count())});
    }
    phase.reset();
    phase.emplace("setup");
    std::vector<std::vector<ScreenTriangle>>& chunk_triangles = scratch.chunk_triangles;
    if (chunk_triangles.size() < chunks.size()) chunk_triangles.resize(chunks.size());
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, chunks.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t c = r.begin(); c != r.end(); ++c) {
            const Chunk& ch = chunks[c];
            chunk_triangles[c].clear();
            chunk_triangles[c].reserve(ch.end - ch.begin);
            setup_triangles(*items[ch.item].mesh, shaded[ch.item], ch.item, ch.begin, ch.end, width, height, guard,
                            chunk_triangles[c]);
        }
    });
    std::vector<const ScreenTriangle*>& tris = scratch.tris;
    tris.clear();
    for (size_t c = 0; c < chunks.size(); ++c)
        for (const ScreenTriangle& t : chunk_triangles[c]) tris.push_back(&t);
    if (tris.size() > size_t(INT32_MAX)) throw std::length_error("rasterize: too many triangles");

    phase.reset();
    phase.emplace("bin");
    // Bin triangles into tiles (counting sort; every bin stays in submission order).
    const int tiles_x = (width + kTileW - 1) / kTileW, tiles_y = (height + kTileH - 1) / kTileH;
    const size_t n_tiles = size_t(tiles_x) * size_t(tiles_y);
    std::vector<uint32_t>& bin_start = scratch.bin_start;
    bin_start.assign(n_tiles + 1, 0);
    auto for_each_tile = [&](const ScreenTriangle& t, auto&& f) {
        for (int ty = t.py0 / kTileH; ty <= t.py1 / kTileH; ++ty)
            for (int tx = t.px0 / kTileW; tx <= t.px1 / kTileW; ++tx) f(size_t(ty) * size_t(tiles_x) + size_t(tx));
    };
    for (const ScreenTriangle* t : tris) for_each_tile(*t, [&](size_t tile) { ++bin_start[tile + 1]; });
    for (size_t i = 0; i < n_tiles; ++i) bin_start[i + 1] += bin_start[i];
    std::vector<uint32_t>& bins = scratch.bins;
    bins.resize(bin_start.back());
    std::vector<uint32_t>& fill = scratch.bin_fill;
    fill.assign(bin_start.begin(), bin_start.end() - 1);
    for (size_t i = 0; i < tris.size(); ++i) for_each_tile(*tris[i], [&](size_t tile) { bins[fill[tile]++] = uint32_t(i); });

    phase.reset();
    phase.emplace("tiles");
    // Tiles in parallel: depth-tested visibility (nearest triangle per pixel), then the
    // attributes of the visible triangle, once per pixel. Every pixel of `out` is written.
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, n_tiles, 1), [&](const tbb::blocked_range<size_t>& r) {
        TileBuffers buf;
        for (size_t tile = r.begin(); tile != r.end(); ++tile) {
            const int tx = int(tile % size_t(tiles_x)) * kTileW, ty = int(tile / size_t(tiles_x)) * kTileH;
            const int tx1 = std::min(tx + kTileW, width) - 1, ty1 = std::min(ty + kTileH, height) - 1;
            std::fill(buf.depth.begin(), buf.depth.end(), 1.f);
            std::fill(buf.tri_id.begin(), buf.tri_id.end(), -1);
            for (uint32_t b = bin_start[tile]; b < bin_start[tile + 1]; ++b) {
                const ScreenTriangle& t = *tris[bins[b]];
                const int x0 = std::max(t.px0, tx), x1 = std::min(t.px1, tx1);
                const int y0 = std::max(t.py0, ty), y1 = std::min(t.py1, ty1);
                if (x0 <= x1 && y0 <= y1) scan_triangle(t, int32_t(bins[b]), x0, x1, y0, y1, tx, ty, buf);
            }
            const size_t span = size_t(tx1 - tx + 1);
            for (int y = ty; y <= ty1; ++y) {
                const size_t local_row = size_t(y - ty) * kTileW;
                const size_t o_row = out.index(tx, height - 1 - y);  // image row 0 is the top
                std::copy_n(buf.depth.begin() + std::ptrdiff_t(local_row), span, out.depth.begin() + std::ptrdiff_t(o_row));
                for (size_t x = 0; x < span; ++x) {
                    const size_t local = local_row + x, o = o_row + x;
                    const int32_t id = buf.tri_id[local];
                    out.primitive[o] = id;
                    if (id < 0) {
                        out.object[o] = -1;
                        out.position[o] = vec3(0.f);
                        out.normal[o] = vec3(0.f);
                        out.tangent[o] = vec3(0.f);
                        out.uv[o] = vec2(0.f);
                        if (derivatives) out.uv_dx[o] = out.uv_dy[o] = vec2(0.f);
                        continue;
                    }
                    const ScreenTriangle& t = *tris[size_t(id)];
                    const vec3 beta = source_barycentrics(t, buf.lambda[local]);
                    const VertexAttributes* attr = shaded[t.item].attr.data();
                    const VertexAttributes &a = attr[t.src[0]], &b = attr[t.src[1]], &c = attr[t.src[2]];
                    out.object[o] = items[t.item].object_id;
                    out.position[o] = a.position * beta.x + b.position * beta.y + c.position * beta.z;
                    out.normal[o] = normalize_or_zero(a.normal * beta.x + b.normal * beta.y + c.normal * beta.z);
                    out.tangent[o] = normalize_or_zero(a.tangent * beta.x + b.tangent * beta.y + c.tangent * beta.z);
                    out.uv[o] = a.uv * beta.x + b.uv * beta.y + c.uv * beta.z;
                    if (!derivatives) continue;
                    if (!items[t.item].uv_derivatives) {
                        out.uv_dx[o] = out.uv_dy[o] = vec2(0.f);
                        continue;
                    }
                    // The quad's other pixel in the row and in the column, on this triangle:
                    // screen-space barycentrics step by their per-pixel change.
                    auto uv_at = [&](vec2 lambda) {
                        const vec3 w = source_barycentrics(t, lambda);
                        return a.uv * w.x + b.uv * w.y + c.uv * w.z;
                    };
                    const vec2 l = buf.lambda[local], uv = out.uv[o];
                    out.uv_dx[o] = ((tx + int(x)) & 1) ? uv - uv_at(l - t.lambda_dx) : uv_at(l + t.lambda_dx) - uv;  // odd: the right column
                    out.uv_dy[o] = (y & 1) ? uv - uv_at(l - t.lambda_dy) : uv_at(l + t.lambda_dy) - uv;              // odd: the upper row
                }
            }
        }
    });
}
}  // namespace mesolab
