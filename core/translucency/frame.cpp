// Technique translucency: the atlas stage's extras, the gather table, ρ and the per-frame CPU passes (see translucency.h).
#include "core/translucency/translucency.h"
#include "core/sampling.h"
#include "core/basic/basic.h"
#include "core/error.h"
#include "core/image.h"
#include "core/raster.h"

#include <glm/gtc/matrix_transform.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>
#include <utility>

namespace mesolab::translucency {

// [SECTION] Atlas stage: texel geometry, fill sources, the drawn mesh
AtlasStage make_atlas_stage(const PreparedMesh& mesh, const AtlasParams& p) {
    AtlasStage s;
    s.atlas = build_atlas(mesh.position, mesh.index, p);
    const Atlas& a = s.atlas;
    const size_t N = size_t(a.size) * size_t(a.size);
    s.texel_position.assign(N, vec3(0.f));
    s.texel_normal.assign(N, vec3(0.f));
    s.fill.assign(N, -1);
    for (size_t t = 0; t < N; ++t)
        if (a.texel_face[t] >= 0) s.nonempty.push_back(int32_t(t));
    tbb::parallel_for(size_t(0), s.nonempty.size(), [&](size_t k) {
        const size_t t = size_t(s.nonempty[k]);
        const size_t f = size_t(a.texel_face[t]);
        const vec3 w = a.texel_bary[t];
        const uint32_t i0 = mesh.index[3 * f], i1 = mesh.index[3 * f + 1], i2 = mesh.index[3 * f + 2];
        s.texel_position[t] = w.x * mesh.position[i0] + w.y * mesh.position[i1] + w.z * mesh.position[i2];
        vec3 n = mesh.corner_normal.empty() ? w.x * mesh.normal[i0] + w.y * mesh.normal[i1] + w.z * mesh.normal[i2]
                                            : w.x * mesh.corner_normal[3 * f] + w.y * mesh.corner_normal[3 * f + 1] + w.z * mesh.corner_normal[3 * f + 2];
        if (!(glm::length(n) > 1e-12f)) n = glm::cross(mesh.position[i1] - mesh.position[i0], mesh.position[i2] - mesh.position[i0]);
        s.texel_normal[t] = glm::length(n) > 0.f ? glm::normalize(n) : vec3(0.f, 0.f, 1.f);
    });
    // Fill sources: inner texels show themselves; the others the nearest inner texel of their chunk
    // (breadth first over the chunk's texels), or, in a chunk too small to hold one, the inner
    // texel nearest on the surface (3D).
    {
        std::vector<int32_t> queue;
        for (size_t t = 0; t < N; ++t)
            if (a.texel_kind[t] == Atlas::kInner) s.fill[t] = int32_t(t), queue.push_back(int32_t(t));
        for (size_t head = 0; head < queue.size(); ++head) {
            const int t = queue[head];
            const int x = t % a.size, y = t / a.size;
            const int nb[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
            for (const auto& d : nb) {
                const int qx = x + d[0], qy = y + d[1];
                if (qx < 0 || qy < 0 || qx >= a.size || qy >= a.size) continue;
                const size_t q = a.texel(qx, qy);
                if (s.fill[q] >= 0 || a.texel_face[q] < 0 || a.texel_chunk[q] != a.texel_chunk[size_t(t)]) continue;
                s.fill[q] = s.fill[size_t(t)];
                queue.push_back(int32_t(q));
            }
        }
        std::vector<int32_t> orphans;
        for (int32_t t : s.nonempty)
            if (s.fill[size_t(t)] < 0) orphans.push_back(t);
        if (!orphans.empty() && !queue.empty()) {
            // A uniform grid over the inner texels' positions.
            vec3 lo(INFINITY), hi(-INFINITY);
            for (int32_t t : queue) lo = glm::min(lo, s.texel_position[size_t(t)]), hi = glm::max(hi, s.texel_position[size_t(t)]);
            const int G = 32;
            const vec3 cell = glm::max((hi - lo) / float(G), vec3(1e-12f));
            auto cell_of = [&](vec3 p) { return glm::clamp(glm::ivec3(glm::floor((p - lo) / cell)), glm::ivec3(0), glm::ivec3(G - 1)); };
            std::vector<std::vector<int32_t>> grid(size_t(G) * G * G);
            for (int32_t t : queue) {
                const glm::ivec3 c = cell_of(s.texel_position[size_t(t)]);
                grid[(size_t(c.z) * G + size_t(c.y)) * G + size_t(c.x)].push_back(t);
            }
            const float min_cell = std::min({cell.x, cell.y, cell.z});
            tbb::parallel_for(size_t(0), orphans.size(), [&](size_t k) {
                const size_t t = size_t(orphans[k]);
                const vec3 p = s.texel_position[t];
                const glm::ivec3 c = cell_of(p);
                int best = -1;
                float best_d = INFINITY;
                for (int r = 0; r < G; ++r) {
                    if (best >= 0 && float(r - 1) * min_cell > std::sqrt(best_d)) break;
                    for (int z = std::max(0, c.z - r); z <= std::min(G - 1, c.z + r); ++z)
                        for (int y = std::max(0, c.y - r); y <= std::min(G - 1, c.y + r); ++y)
                            for (int x = std::max(0, c.x - r); x <= std::min(G - 1, c.x + r); ++x) {
                                if (std::max({std::abs(x - c.x), std::abs(y - c.y), std::abs(z - c.z)}) != r) continue;
                                for (int32_t q : grid[(size_t(z) * G + size_t(y)) * G + size_t(x)]) {
                                    const vec3 d = s.texel_position[size_t(q)] - p;
                                    const float dd = glm::dot(d, d);
                                    if (dd < best_d) best_d = dd, best = q;
                                }
                            }
                }
                s.fill[t] = best;
            });
        }
    }
    // Illumination sources: a border texel's point lies on a triangle of another chunk (or of
    // its own, clamped); that chunk's texel under the point, or the nearest of its inner texels
    // within one texel, holds the same surface.
    {
        std::vector<int32_t> source(s.nonempty.size(), -1);
        tbb::parallel_for(size_t(0), s.nonempty.size(), [&](size_t k) {
            const size_t t = size_t(s.nonempty[k]);
            if (a.texel_kind[t] == Atlas::kInner) return;
            const size_t f = size_t(a.texel_face[t]);
            const int chunk = a.face_chunk[f];
            if (chunk < 0) return;
            const vec3 w = a.texel_bary[t];
            const vec2 u = w.x * a.corner_uv[3 * f] + w.y * a.corner_uv[3 * f + 1] + w.z * a.corner_uv[3 * f + 2];
            if (!std::isfinite(u.x) || !std::isfinite(u.y)) return;
            const int cx = int(std::floor(u.x)), cy = int(std::floor(u.y));
            float best_d = INFINITY;
            for (int y = cy - 1; y <= cy + 1; ++y)
                for (int x = cx - 1; x <= cx + 1; ++x) {
                    if (x < 0 || y < 0 || x >= a.size || y >= a.size) continue;
                    const size_t q = a.texel(x, y);
                    if (a.texel_kind[q] != Atlas::kInner || a.texel_chunk[q] != chunk) continue;
                    const vec2 d = vec2(float(x) + 0.5f, float(y) + 0.5f) - u;
                    const float dd = glm::dot(d, d);
                    if (dd <= 1.f && dd < best_d) best_d = dd, source[k] = int32_t(q);
                }
        });
        for (size_t k = 0; k < s.nonempty.size(); ++k)
            if (source[k] >= 0) s.copy.push_back(ivec2(s.nonempty[k], source[k]));
            else s.lit.push_back(s.nonempty[k]);
    }
    // The drawn mesh: a vertex per mesh vertex and atlas position (corners inside a chunk share
    // theirs; chunk borders split), so that rasterising it transforms each vertex about once.
    auto m = std::make_shared<TriMesh>();
    const float inv = 1.f / float(a.size);
    std::unordered_map<uint64_t, uint32_t> made;
    for (size_t f = 0; f < mesh.triangle_count(); ++f) {
        if (a.face_chunk[f] < 0) continue;
        for (int j = 0; j < 3; ++j) {
            const uint32_t v = mesh.index[3 * f + size_t(j)];
            const vec2 c = a.corner_uv[3 * f + size_t(j)];
            const vec3 n = mesh.corner_normal.empty() ? mesh.normal[v] : mesh.corner_normal[3 * f + size_t(j)];
            const uint64_t key = uint64_t(v) << 32 | uint64_t(uint32_t(a.face_chunk[f]));
            auto [it, fresh] = made.try_emplace(key, uint32_t(m->position.size()));
            if (!fresh && (m->uv[it->second] != vec2(c.x * inv, 1.f - c.y * inv) || m->normal[it->second] != n))
                fresh = true, it->second = uint32_t(m->position.size());
            if (fresh) {
                m->position.push_back(mesh.position[v]);
                m->normal.push_back(n);
                m->tangent.push_back(vec3(0.f));
                m->uv.push_back(vec2(c.x * inv, 1.f - c.y * inv));
            }
            m->index.push_back(it->second);
        }
    }
    m->has_uv = true;
    s.display = std::move(m);
    return s;
}

// [SECTION] Gather table
Gather make_gather(const Atlas& a, const std::vector<uint32_t>& index, const std::vector<float>& vertex_area, double mm_per_unit,
                   const BlendWeights* blend, const LocalKernels* kernels) {
    Gather g;
    g.n = int(vertex_area.size());
    g.direct = blend && kernels;
    g.start.assign(size_t(g.n) + 1, 0);
    const size_t N = a.texel_kind.size();
    for (size_t t = 0; t < N; ++t) {
        if (a.texel_kind[t] != Atlas::kInner) continue;
        const size_t f = size_t(a.texel_face[t]);
        for (int j = 0; j < 3; ++j) ++g.start[index[3 * f + size_t(j)] + 1];
    }
    for (int v = 0; v < g.n; ++v) g.start[size_t(v) + 1] += g.start[size_t(v)];
    g.texel.resize(size_t(g.start.back()));
    g.w.resize(g.texel.size());
    std::vector<int32_t> next(g.start.begin(), g.start.end() - 1);
    const double s2 = mm_per_unit * mm_per_unit;


    for (size_t t = 0; t < N; ++t) {
        if (a.texel_kind[t] != Atlas::kInner) continue;
        const size_t f = size_t(a.texel_face[t]);
        const vec3 w = a.texel_bary[t];
        const double area = double(a.texel_area[t]) * s2;
        for (int j = 0; j < 3; ++j) {
            const uint32_t v = index[3 * f + size_t(j)];
            const size_t e = size_t(next[v]++);
            g.texel[e] = int32_t(t);
            const float proj = float(area * 3.0 / double(vertex_area[v]) * double(w[j]));  // project_to_vertices
            vec3 c(0.f);
            if (g.direct) c = blend->c[size_t(kernels->slot[t])][size_t(j)];
            g.w[e] = vec4(proj, c);
        }
    }
    return g;
}

VertexValues gather_vertices(const Gather& g, const std::vector<vec3>& E) {
    VertexValues out;
    out.E.assign(size_t(g.n), vec3(0.f));
    out.direct.assign(size_t(g.n), vec3(0.f));
    tbb::parallel_for(tbb::blocked_range<int>(0, g.n, 256), [&](const tbb::blocked_range<int>& r) {
        for (int v = r.begin(); v != r.end(); ++v) {
            vec3 e(0.f), d(0.f);
            for (int k = g.start[size_t(v)]; k < g.start[size_t(v) + 1]; ++k) {
                const vec3 Et = E[size_t(g.texel[size_t(k)])];
                const vec4 w = g.w[size_t(k)];
                e += w.x * Et;
                d += vec3(w.y, w.z, w.w) * Et;
            }
            out.E[size_t(v)] = e;
            out.direct[size_t(v)] = d;
        }
    });
    return out;
}

// [SECTION] ρ: albedo map and veins
namespace {
uint32_t hash3(int x, int y, int z) {
    uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ uint32_t(z) * 0xcb1ab31fu;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    h *= 0x297a2d39u;
    h ^= h >> 15;
    return h;
}
float value_noise(vec3 p) {
    const vec3 f = glm::floor(p);
    const vec3 t = p - f;
    const vec3 s = t * t * (3.f - 2.f * t);
    const int x = int(f.x), y = int(f.y), z = int(f.z);
    float v[8];
    for (int k = 0; k < 8; ++k) v[k] = float(hash3(x + (k & 1), y + ((k >> 1) & 1), z + (k >> 2)) >> 8) * (1.f / 16777216.f);
    const float a = glm::mix(glm::mix(v[0], v[1], s.x), glm::mix(v[2], v[3], s.x), s.y);
    const float b = glm::mix(glm::mix(v[4], v[5], s.x), glm::mix(v[6], v[7], s.x), s.y);
    return glm::mix(a, b, s.z);
}
}  // namespace

float vein(vec3 x_mm, double scale_mm) {
    const vec3 p = x_mm / float(scale_mm);
    float fbm = 0.f, amp = 0.5f;
    vec3 q = p;
    for (int o = 0; o < 5; ++o, amp *= 0.5f, q *= 2.03f) fbm += amp * value_noise(q + vec3(17.f * float(o)));
    const float t = p.x + 0.6f * p.y + 3.f * fbm;
    return std::pow(1.f - std::abs(std::sin(kPi * t)), 8.f);
}

std::vector<vec3> texel_albedo(const Scene& scene, const Settings& s, const PreparedMesh& mesh, const AtlasStage& a) {
    std::vector<vec3> rho(a.texel_position.size(), vec3(1.f));
    std::optional<Image> img;
    if (!s.albedo_map.empty()) {
        const std::string path = scene.resolve(s.albedo_map);
        if (mesh.corner_uv.empty())
            throw InputError("translucency.albedo_map: " + path + " needs texture coordinates, and the object's mesh has none (use translucency.veins, or a mesh with uv)");
        img = read_image(path, true, true);
    }
    tbb::parallel_for(size_t(0), a.nonempty.size(), [&](size_t k) {
        const size_t t = size_t(a.nonempty[k]);
        vec3 r(1.f);
        if (img) {
            const size_t f = size_t(a.atlas.texel_face[t]);
            const vec3 w = a.atlas.texel_bary[t];
            const vec2 uv = w.x * mesh.corner_uv[3 * f] + w.y * mesh.corner_uv[3 * f + 1] + w.z * mesh.corner_uv[3 * f + 2];
            r = basic::sample_albedo(*img, uv);
        }
        if (s.veins > 0.f) r *= glm::mix(vec3(1.f), s.vein_color, s.veins * vein(a.texel_position[t] * float(s.mm_per_unit), s.vein_scale));
        rho[t] = r;
    });
    return fill_texels(a, rho);
}

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
    tbb::parallel_for(tbb::blocked_range<size_t>(0, world.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
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
    tbb::parallel_for(tbb::blocked_range<size_t>(0, world.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
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
    tbb::parallel_for(tbb::blocked_range<size_t>(0, T, 1024), [&](const tbb::blocked_range<size_t>& r) {
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
    tbb::parallel_for(0, bands, [&](int band) {
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

// [SECTION] Illumination
std::vector<vec3> illuminate(const AtlasStage& a, const mat4& model, const Lighting& L, double eta, const std::vector<ShadowMap>& shadows) {
    std::vector<vec3> E(a.texel_position.size(), vec3(0.f));
    const mat3 normal_matrix = glm::transpose(glm::inverse(mat3(model)));
    const float env_t = float(diffuse_transmittance(eta));  // entering from outside: the lights' T averaged over the hemisphere
    // Schlick's transmittance (fresnel_transmittance) in single precision: c is in (0, 1] here.
    const float r0 = float((eta - 1.0) / (eta + 1.0) * ((eta - 1.0) / (eta + 1.0)));
    const auto transmittance = [&](float c) {
        if (eta == 1.0) return 1.f;
        const float m = 1.f - std::min(c, 1.f), m2 = m * m;
        return std::clamp(1.f - (r0 + (1.f - r0) * m2 * m2 * m), 0.f, 1.f);
    };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, a.lit.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const size_t t = size_t(a.lit[k]);
            const vec3 p = vec3(model * vec4(a.texel_position[t], 1.f));
            const vec3 n = glm::normalize(normal_matrix * a.texel_normal[t]);
            vec3 e(0.f);
            for (size_t i = 0; i < L.lights.size(); ++i) {
                vec3 wi, El;
                L.lights[i].sample(p, wi, El);
                const float c = glm::dot(n, wi);
                if (c <= 0.f) continue;
                const float v = i < shadows.size() ? shadows[i].visibility(p) : 1.f;
                e += El * (c * transmittance(c) * v);
            }
            e += L.env_irradiance(n) * env_t;
            E[t] = e;
        }
    });
    // Border texels whose surface another chunk holds take its value.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, a.copy.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) E[size_t(a.copy[k].x)] = E[size_t(a.copy[k].y)];
    });
    return E;
}

// [SECTION] Combine and look-ups
std::vector<vec3> fill_texels(const AtlasStage& a, const std::vector<vec3>& v) {
    std::vector<vec3> out(v.size(), vec3(0.f));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, v.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) out[t] = a.fill[t] >= 0 ? v[size_t(a.fill[t])] : v[t];
    });
    return out;
}

Maps combine(const AtlasStage& a, const std::vector<uint32_t>& index, const std::vector<vec3>& E, const std::vector<vec3>& local,
             const std::vector<vec3>& Bv) {
    const Atlas& at = a.atlas;
    Maps m;
    m.texel.resize(E.size());
    // Texels shown as themselves (the inner ones, and any without a fill source): their
    // irradiance, local part and the vertex values interpolated at their point. Empty texels get 0
    // (no irradiance, no local part, no triangle).
    tbb::parallel_for(tbb::blocked_range<size_t>(0, E.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            if (at.texel_face[t] < 0) {
                m.texel[t] = MapTexel(vec3(0.f), vec3(0.f), vec3(0.f));
                continue;
            }
            if (a.fill[t] >= 0 && size_t(a.fill[t]) != t) continue;
            const size_t f = size_t(at.texel_face[t]);
            const vec3 w = at.texel_bary[t];
            const vec3 g = w.x * Bv[index[3 * f]] + w.y * Bv[index[3 * f + 1]] + w.z * Bv[index[3 * f + 2]];
            m.texel[t] = MapTexel(E[t], local[t], g);
        }
    });
    // The others take their fill source's record.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, a.nonempty.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const size_t t = size_t(a.nonempty[k]);
            if (a.fill[t] >= 0 && size_t(a.fill[t]) != t) m.texel[t] = m.texel[size_t(a.fill[t])];
        }
    });
    return m;
}

TexelTap::TexelTap(int size, vec2 uv) {
    // Row 0 at v = 1, clamped to the edge.
    const BilinearTaps t(uv.x * float(size) - 0.5f, (1.f - uv.y) * float(size) - 0.5f, size, size, Edge::Clamp, Edge::Clamp);
    ax = t.ax, ay = t.ay;
    const size_t n = size_t(size);
    i00 = size_t(t.y0) * n + size_t(t.x0), i10 = size_t(t.y0) * n + size_t(t.x1);
    i01 = size_t(t.y1) * n + size_t(t.x0), i11 = size_t(t.y1) * n + size_t(t.x1);
}

vec3 sample_texels(const std::vector<vec3>& map, int size, vec2 uv) { return TexelTap(size, uv)(map); }
}  // namespace mesolab::translucency
