// The texture atlas of Lensch et al. 2002, §5.1 (see atlas.h).
#include "core/translucency/atlas.h"
#include "core/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <numeric>
#include <unordered_map>

namespace mesolab::translucency {

namespace {
using dvec2 = glm::dvec2;
using dvec3 = glm::dvec3;

struct Face {
    dvec3 n{0.0};
    double area = 0.0;
    bool valid = false;
};

uint64_t edge_key(uint32_t a, uint32_t b) { return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a; }

double cross2(dvec2 a, dvec2 b) { return a.x * b.y - a.y * b.x; }

// Do two 2D triangles overlap in their interiors (separating axis test; touching is no overlap)?
bool triangles_overlap(const dvec2 a[3], const dvec2 b[3], double eps) {
    for (int pass = 0; pass < 2; ++pass) {
        const dvec2* t = pass == 0 ? a : b;
        for (int e = 0; e < 3; ++e) {
            const dvec2 d = t[(e + 1) % 3] - t[e];
            const dvec2 axis(-d.y, d.x);
            const double len = std::sqrt(glm::dot(axis, axis));
            if (!(len > 0.0)) continue;
            double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
            for (int k = 0; k < 3; ++k) {
                const double pa = glm::dot(a[k], axis) / len, pb = glm::dot(b[k], axis) / len;
                amin = std::min(amin, pa), amax = std::max(amax, pa), bmin = std::min(bmin, pb), bmax = std::max(bmax, pb);
            }
            if (amax <= bmin + eps || bmax <= amin + eps) return false;
        }
    }
    return true;
}

// Convex hull (Andrew's monotone chain), counter-clockwise.
std::vector<dvec2> convex_hull(std::vector<dvec2> p) {
    std::sort(p.begin(), p.end(), [](dvec2 a, dvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    p.erase(std::unique(p.begin(), p.end()), p.end());
    if (p.size() < 3) return p;
    std::vector<dvec2> h(2 * p.size());
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        while (k >= 2 && cross2(h[k - 1] - h[k - 2], p[i] - h[k - 2]) <= 0.0) --k;
        h[k++] = p[i];
    }
    for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross2(h[k - 1] - h[k - 2], p[i] - h[k - 2]) <= 0.0) --k;
        h[k++] = p[i];
    }
    h.resize(k - 1);
    return h;
}

// Unit axis u of the minimum-area rectangle around a hull (rotating calipers: one side on a hull edge).
dvec2 min_area_axis(const std::vector<dvec2>& hull) {
    dvec2 best(1.0, 0.0);
    double best_area = INFINITY;
    for (size_t i = 0; i < hull.size(); ++i) {
        dvec2 d = hull[(i + 1) % hull.size()] - hull[i];
        const double len = std::sqrt(glm::dot(d, d));
        if (!(len > 0.0)) continue;
        d /= len;
        const dvec2 n(-d.y, d.x);
        double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
        for (const dvec2& q : hull) {
            u0 = std::min(u0, glm::dot(q, d)), u1 = std::max(u1, glm::dot(q, d));
            v0 = std::min(v0, glm::dot(q, n)), v1 = std::max(v1, glm::dot(q, n));
        }
        const double area = (u1 - u0) * (v1 - v0);
        if (area < best_area - 1e-12 * std::abs(best_area)) best_area = area, best = d;
    }
    return best;
}

// Orthonormal in-plane axes for a normal.
void plane_axes(dvec3 n, dvec3& u, dvec3& v) {
    const dvec3 a = std::abs(n.x) < 0.9 ? dvec3(1, 0, 0) : dvec3(0, 1, 0);
    u = glm::normalize(glm::cross(a, n));
    v = glm::cross(n, u);
}

struct ChunkBuild {
    std::vector<uint32_t> faces;
    dvec3 n{0.0}, u{0.0}, v{0.0}, origin{0.0};
    dvec2 size{0.0};  // rectangle, scene units
};

// Barycentrics of p in the 2D triangle (a, b, c); false when degenerate.
bool barycentric(dvec2 p, dvec2 a, dvec2 b, dvec2 c, dvec3& w) {
    const double d = cross2(b - a, c - a);
    if (!(std::abs(d) > 0.0)) return false;
    w.y = cross2(p - a, c - a) / d;
    w.z = cross2(b - a, p - a) / d;
    w.x = 1.0 - w.y - w.z;
    return true;
}

// Shelf packing of padded rectangles (w, h) into a square of `size`; offsets of each, or false.
bool shelf_pack(const std::vector<ivec2>& rects, int size, std::vector<ivec2>& at) {
    std::vector<size_t> order(rects.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return rects[a].y > rects[b].y; });
    at.assign(rects.size(), ivec2(0));
    int x = 0, y = 0, shelf = 0;
    for (size_t i : order) {
        const ivec2 r = rects[i];
        if (r.x > size) return false;
        if (x + r.x > size) y += shelf, x = 0, shelf = 0;
        if (y + r.y > size) return false;
        at[i] = ivec2(x, y);
        x += r.x;
        shelf = std::max(shelf, r.y);
    }
    return true;
}
}  // namespace

Atlas build_atlas(const std::vector<vec3>& position, const std::vector<uint32_t>& index, const AtlasParams& p) {
    if (p.size < 16 || p.size > 4096) throw InputError("translucency.atlas_size: " + std::to_string(p.size) + " must be in [16, 4096]");
    if (!(p.chunk_angle > 0.f && p.chunk_angle < 90.f))
        throw InputError("translucency.chunk_angle: " + std::to_string(p.chunk_angle) + " must be in (0, 90) degrees");
    if (p.border < 1 || 4 * p.border >= p.size)
        throw InputError("translucency.kernel: a border of " + std::to_string(p.border) + " texels does not fit an atlas of " + std::to_string(p.size) +
                         " (translucency.atlas_size)");
    const size_t F = index.size() / 3;
    Atlas A;
    A.size = p.size;
    A.border = p.border;

    // Triangle normals and areas; degenerate triangles are skipped.
    std::vector<Face> face(F);
    double total_area = 0.0;
    for (size_t f = 0; f < F; ++f) {
        const uint32_t i0 = index[3 * f], i1 = index[3 * f + 1], i2 = index[3 * f + 2];
        if (i0 >= position.size() || i1 >= position.size() || i2 >= position.size() || i0 == i1 || i1 == i2 || i0 == i2) {
            ++A.skipped_degenerate;
            continue;
        }
        const dvec3 a(position[i0]), b(position[i1]), c(position[i2]);
        const dvec3 n = glm::cross(b - a, c - a);
        const double len = std::sqrt(glm::dot(n, n));
        const double scale = std::max({glm::dot(b - a, b - a), glm::dot(c - a, c - a), glm::dot(c - b, c - b)});
        if (!std::isfinite(len) || !(len > 1e-12 * scale) || !std::isfinite(scale)) {
            ++A.skipped_degenerate;
            continue;
        }
        face[f] = {n / len, 0.5 * len, true};
        total_area += 0.5 * len;
    }
    if (!(total_area > 0.0)) throw InputError("translucency: the mesh has no triangle with an area (" + std::to_string(A.skipped_degenerate) + " degenerate)");

    // Adjacency over shared edges.
    std::unordered_map<uint64_t, std::vector<uint32_t>> edges;
    edges.reserve(F * 2);
    for (size_t f = 0; f < F; ++f)
        if (face[f].valid)
            for (int e = 0; e < 3; ++e) edges[edge_key(index[3 * f + e], index[3 * f + (e + 1) % 3])].push_back(uint32_t(f));
    for (const auto& [k, fs] : edges) A.non_manifold_edges += fs.size() > 2 ? 1 : 0;
    const auto neighbours = [&](uint32_t f, auto&& visit) {
        for (int e = 0; e < 3; ++e) {
            const uint32_t a = index[3 * f + e], b = index[3 * f + (e + 1) % 3];
            for (uint32_t g : edges[edge_key(a, b)])
                if (g != f) visit(g, a, b);
        }
    };

    // [SECTION] Chunks: grow, then drop what folds over
    const double cos_max = std::cos(double(p.chunk_angle) * 3.14159265358979323846 / 180.0);
    std::vector<uint32_t> seeds;
    for (size_t f = 0; f < F; ++f)
        if (face[f].valid) seeds.push_back(uint32_t(f));
    std::stable_sort(seeds.begin(), seeds.end(), [&](uint32_t a, uint32_t b) { return face[a].area > face[b].area; });
    std::vector<int32_t> owner(F, -1);
    std::vector<int32_t> refused(F, -1);  // the chunk that dropped a triangle (it never re-enters it)
    std::vector<ChunkBuild> chunks;
    const auto project = [&](const ChunkBuild& c, uint32_t vi) {
        const dvec3 q = dvec3(position[vi]) - c.origin;
        return dvec2(glm::dot(q, c.u), glm::dot(q, c.v));
    };
    // Triangles dropped from a chunk may come after their turn as seeds: repeat until all are placed.
    for (size_t si = 0, unplaced = seeds.size(); unplaced > 0; si = (si + 1) % seeds.size()) {
        const uint32_t seed = seeds[si];
        if (owner[seed] >= 0) continue;
        const int32_t id = int32_t(chunks.size());
        ChunkBuild c;
        dvec3 sum = face[seed].n * face[seed].area;
        owner[seed] = id;
        c.faces.push_back(seed);
        std::deque<uint32_t> queue{seed};
        while (!queue.empty()) {
            const uint32_t f = queue.front();
            queue.pop_front();
            neighbours(f, [&](uint32_t g, uint32_t, uint32_t) {
                if (owner[g] >= 0 || refused[g] == id) return;
                if (glm::dot(face[g].n, glm::normalize(sum)) < cos_max) return;
                owner[g] = id;
                c.faces.push_back(g);
                sum += face[g].n * face[g].area;
                queue.push_back(g);
            });
        }
        // Project along the final average normal; drop triangles that overlap earlier ones (or
        // flip), until none does.
        for (;;) {
            c.n = glm::normalize(sum);
            plane_axes(c.n, c.u, c.v);
            c.origin = dvec3(0.0);
            dvec2 lo(INFINITY), hi(-INFINITY);
            std::vector<std::array<dvec2, 3>> tri(c.faces.size());
            for (size_t k = 0; k < c.faces.size(); ++k)
                for (int j = 0; j < 3; ++j) {
                    tri[k][size_t(j)] = project(c, index[3 * c.faces[k] + uint32_t(j)]);
                    lo = glm::min(lo, tri[k][size_t(j)]), hi = glm::max(hi, tri[k][size_t(j)]);
                }
            const double diam = std::max(hi.x - lo.x, hi.y - lo.y), eps = 1e-9 * diam;
            // Uniform grid of about one triangle per cell.
            const int G = std::clamp(int(std::sqrt(double(c.faces.size()))), 1, 512);
            const dvec2 cell = glm::max((hi - lo) / double(G), dvec2(1e-300));
            std::vector<std::vector<uint32_t>> grid(size_t(G) * size_t(G));
            std::vector<char> drop(c.faces.size(), 0);
            bool dropped = false;
            // The triangle nearest the average stays (so the chunk never empties); it goes first.
            size_t keep_k = 0;
            for (size_t k = 1; k < c.faces.size(); ++k)
                if (glm::dot(face[c.faces[k]].n, c.n) > glm::dot(face[c.faces[keep_k]].n, c.n)) keep_k = k;
            std::swap(c.faces[0], c.faces[keep_k]);
            std::swap(tri[0], tri[keep_k]);
            for (size_t k = 0; k < c.faces.size(); ++k) {
                if (k > 0 && glm::dot(face[c.faces[k]].n, c.n) < cos_max) {  // the angle holds for the final average too
                    drop[k] = 1, dropped = true;
                    continue;
                }
                dvec2 tlo = glm::min(tri[k][0], glm::min(tri[k][1], tri[k][2])), thi = glm::max(tri[k][0], glm::max(tri[k][1], tri[k][2]));
                const ivec2 g0 = glm::clamp(ivec2((tlo - lo) / cell), ivec2(0), ivec2(G - 1)), g1 = glm::clamp(ivec2((thi - lo) / cell), ivec2(0), ivec2(G - 1));
                bool hit = false;
                for (int gy = g0.y; gy <= g1.y && !hit; ++gy)
                    for (int gx = g0.x; gx <= g1.x && !hit; ++gx)
                        for (uint32_t o : grid[size_t(gy) * size_t(G) + size_t(gx)])
                            if (triangles_overlap(tri[k].data(), tri[o].data(), eps)) {
                                hit = true;
                                break;
                            }
                if (hit) {
                    drop[k] = 1, dropped = true;
                    continue;
                }
                for (int gy = g0.y; gy <= g1.y; ++gy)
                    for (int gx = g0.x; gx <= g1.x; ++gx) grid[size_t(gy) * size_t(G) + size_t(gx)].push_back(uint32_t(k));
            }
            if (!dropped) break;
            std::vector<uint32_t> keep;
            sum = dvec3(0.0);
            for (size_t k = 0; k < c.faces.size(); ++k) {
                const uint32_t f = c.faces[k];
                if (drop[k]) {
                    owner[f] = -1, refused[f] = id;
                } else {
                    keep.push_back(f);
                    sum += face[f].n * face[f].area;
                }
            }
            c.faces = std::move(keep);  // k = 0 is never dropped
        }
        unplaced = 0;
        for (uint32_t f : seeds) unplaced += owner[f] < 0 ? 1 : 0;
        // Minimum-area rectangle: rotate the axes onto it, origin at its corner.
        std::vector<dvec2> pts;
        for (uint32_t f : c.faces)
            for (int j = 0; j < 3; ++j) pts.push_back(project(c, index[3 * f + uint32_t(j)]));
        const dvec2 d = min_area_axis(convex_hull(pts));
        const dvec3 u = c.u * d.x + c.v * d.y, v = glm::cross(c.n, u);
        c.u = u, c.v = v;
        dvec2 lo(INFINITY), hi(-INFINITY);
        for (uint32_t f : c.faces)
            for (int j = 0; j < 3; ++j) {
                const dvec2 q = project(c, index[3 * f + uint32_t(j)]);
                lo = glm::min(lo, q), hi = glm::max(hi, q);
            }
        c.origin = c.u * lo.x + c.v * lo.y;  // project() subtracts origin: now the rectangle starts at (0, 0)
        c.size = hi - lo;
        chunks.push_back(std::move(c));
    }

    // [SECTION] Packing: the largest global scale that fits
    const int B = p.border, N = p.size;
    const auto rects_at = [&](double s) {
        std::vector<ivec2> r(chunks.size());
        for (size_t i = 0; i < chunks.size(); ++i)
            r[i] = ivec2(std::max(1, int(std::ceil(chunks[i].size.x * s))) + 2 * B, std::max(1, int(std::ceil(chunks[i].size.y * s))) + 2 * B);
        return r;
    };
    std::vector<ivec2> at;
    if (!shelf_pack(rects_at(0.0), N, at))
        throw InputError("translucency.atlas_size: " + std::to_string(N) + " texels a side cannot hold the " + std::to_string(chunks.size()) +
                         " chunks with their borders of " + std::to_string(B) +
                         " texels; raise translucency.atlas_size or translucency.chunk_angle, or lower translucency.kernel");
    double lo = 0.0, hi = 1.0;
    while (shelf_pack(rects_at(hi), N, at) && hi < 1e30) lo = hi, hi *= 2.0;
    for (int it = 0; it < 60 && hi - lo > 1e-7 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (shelf_pack(rects_at(mid), N, at) ? lo : hi) = mid;
    }
    const double s = lo;
    const std::vector<ivec2> rects = rects_at(s);
    shelf_pack(rects, N, at);
    A.scale = float(s);

    // [SECTION] Texels
    const size_t T = size_t(N) * size_t(N);
    A.texel_chunk.assign(T, -1);
    A.texel_face.assign(T, -1);
    A.texel_bary.assign(T, vec3(0.f));
    A.texel_kind.assign(T, Atlas::kEmpty);
    A.texel_area.assign(T, 0.f);
    A.corner_uv.assign(index.size(), vec2(std::numeric_limits<float>::quiet_NaN()));
    A.face_chunk.assign(F, -1);
    const double texel_area = 1.0 / (s * s);
    size_t inner = 0;
    for (size_t ci = 0; ci < chunks.size(); ++ci) {
        const ChunkBuild& c = chunks[ci];
        AtlasChunk out;
        out.faces = c.faces;
        out.normal = vec3(c.n), out.origin = vec3(c.origin), out.axis_u = vec3(c.u), out.axis_v = vec3(c.v);
        out.offset = at[ci] + ivec2(B);
        out.extent = rects[ci] - ivec2(2 * B);
        const dvec2 off(out.offset);
        const auto atlas_xy = [&](uint32_t vi) { return off + project(c, vi) * s; };
        // Inner texels: the chunk triangle covering the centre (half-open: centres on a shared
        // edge go to one side only).
        for (uint32_t f : c.faces) {
            A.face_chunk[f] = int32_t(ci);
            dvec2 q[3];
            for (int j = 0; j < 3; ++j) {
                q[j] = atlas_xy(index[3 * f + uint32_t(j)]);
                A.corner_uv[3 * f + uint32_t(j)] = vec2(q[j]);
            }
            const bool ccw = cross2(q[1] - q[0], q[2] - q[0]) > 0.0;
            const dvec2 tlo = glm::min(q[0], glm::min(q[1], q[2])), thi = glm::max(q[0], glm::max(q[1], q[2]));
            const int x0 = std::max(0, int(std::floor(tlo.x - 0.5))), x1 = std::min(N - 1, int(std::ceil(thi.x - 0.5)));
            const int y0 = std::max(0, int(std::floor(tlo.y - 0.5))), y1 = std::min(N - 1, int(std::ceil(thi.y - 0.5)));
            const double area_f = texel_area / std::max(1e-6, glm::dot(face[f].n, c.n));
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x) {
                    const dvec2 pc(x + 0.5, y + 0.5);
                    bool in = true;
                    for (int e = 0; e < 3 && in; ++e) {
                        const dvec2 a = q[e], b = q[(e + 1) % 3];
                        double w = cross2(b - a, pc - a);
                        if (!ccw) w = -w;
                        // Top-left rule on the edge's direction (as seen counter-clockwise).
                        const dvec2 d = ccw ? b - a : a - b;
                        const bool top_left = d.y < 0.0 || (d.y == 0.0 && d.x > 0.0);
                        in = w > 0.0 || (w == 0.0 && top_left);
                    }
                    if (!in) continue;
                    const size_t t = A.texel(x, y);
                    if (A.texel_kind[t] == Atlas::kInner) continue;  // never: chunks do not overlap
                    dvec3 w(1.0 / 3.0);
                    barycentric(pc, q[0], q[1], q[2], w);
                    A.texel_chunk[t] = int32_t(ci), A.texel_face[t] = int32_t(f), A.texel_bary[t] = vec3(w);
                    A.texel_kind[t] = Atlas::kInner, A.texel_area[t] = float(area_f);
                    ++inner;
                }
        }
        // Border texels: within B texels (Chebyshev) of an inner texel of this chunk.
        const ivec2 r0 = at[ci], r1 = at[ci] + rects[ci];  // padded rectangle [r0, r1)
        const int W = r1.x - r0.x, H = r1.y - r0.y;
        std::vector<int> dist(size_t(W) * size_t(H), -1);  // Chebyshev distance to the chunk, via BFS
        std::deque<ivec2> bfs;
        for (int y = r0.y; y < r1.y; ++y)
            for (int x = r0.x; x < r1.x; ++x)
                if (A.texel_chunk[A.texel(x, y)] == int32_t(ci)) dist[size_t(y - r0.y) * size_t(W) + size_t(x - r0.x)] = 0, bfs.push_back({x, y});
        std::vector<ivec2> border;
        std::vector<ivec2> nearest(size_t(W) * size_t(H), ivec2(-1));
        for (const ivec2& q : bfs) nearest[size_t(q.y - r0.y) * size_t(W) + size_t(q.x - r0.x)] = q;
        while (!bfs.empty()) {
            const ivec2 q = bfs.front();
            bfs.pop_front();
            const size_t qi = size_t(q.y - r0.y) * size_t(W) + size_t(q.x - r0.x);
            if (dist[qi] >= B) continue;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const ivec2 n = q + ivec2(dx, dy);
                    if (n.x < r0.x || n.y < r0.y || n.x >= r1.x || n.y >= r1.y) continue;
                    const size_t ni = size_t(n.y - r0.y) * size_t(W) + size_t(n.x - r0.x);
                    if (dist[ni] >= 0) continue;
                    dist[ni] = dist[qi] + 1, nearest[ni] = nearest[qi];
                    border.push_back(n);
                    bfs.push_back(n);
                }
        }
        // Unfold the neighbouring triangles about the chunk's edges into its plane, ring by ring.
        std::unordered_map<uint32_t, std::array<dvec2, 3>> placed;  // face -> atlas positions of its corners
        std::unordered_map<uint32_t, std::array<dvec2, 2>> origin;  // unfolded face -> the chunk edge it was reached across
        for (uint32_t f : c.faces) placed[f] = {atlas_xy(index[3 * f]), atlas_xy(index[3 * f + 1]), atlas_xy(index[3 * f + 2])};
        std::deque<uint32_t> ring(c.faces.begin(), c.faces.end());
        std::vector<uint32_t> order;  // unfolded triangles, nearest ring first
        std::unordered_map<uint32_t, char> in_chunk;
        for (uint32_t f : c.faces) in_chunk[f] = 1;
        const dvec2 plo = dvec2(r0), phi = dvec2(r1);
        size_t budget = 64 * c.faces.size() + 4096;
        while (!ring.empty() && budget-- > 0) {
            const uint32_t f = ring.front();
            ring.pop_front();
            const std::array<dvec2, 3> qf = placed[f];
            neighbours(f, [&](uint32_t g, uint32_t a, uint32_t b) {
                if (placed.count(g)) return;
                int ja = -1, jb = -1, jc = -1, fa = -1, fb = -1;
                for (int j = 0; j < 3; ++j) {
                    const uint32_t vg = index[3 * g + uint32_t(j)], vf = index[3 * f + uint32_t(j)];
                    if (vg == a) ja = j; else if (vg == b) jb = j; else jc = j;
                    if (vf == a) fa = j; else if (vf == b) fb = j;
                }
                if (ja < 0 || jb < 0 || jc < 0 || fa < 0 || fb < 0) return;
                const int fc = 3 - fa - fb;
                const dvec3 A3(position[a]), B3(position[b]), C3(position[index[3 * g + uint32_t(jc)]]);
                const dvec3 e3 = B3 - A3;
                const double e3len2 = glm::dot(e3, e3);
                if (!(e3len2 > 0.0)) return;
                const double t = glm::dot(C3 - A3, e3) / e3len2;
                const double h3 = glm::length(C3 - (A3 + t * e3));
                const dvec2 a2 = qf[size_t(fa)], b2 = qf[size_t(fb)], e2 = b2 - a2;
                const double e2len = glm::length(e2);
                if (!(e2len > 0.0)) return;
                dvec2 perp(-e2.y / e2len, e2.x / e2len);
                if (glm::dot(perp, qf[size_t(fc)] - a2) > 0.0) perp = -perp;  // the side away from f
                const dvec2 c2 = a2 + t * e2 + perp * (h3 * e2len / std::sqrt(e3len2));
                std::array<dvec2, 3> qg;
                qg[size_t(ja)] = a2, qg[size_t(jb)] = b2, qg[size_t(jc)] = c2;
                placed[g] = qg;
                order.push_back(g);
                const auto from = origin.find(f);
                const std::array<dvec2, 2> edge = from == origin.end() ? std::array<dvec2, 2>{a2, b2} : from->second;
                origin[g] = edge;
                // Expand only within the border's reach of that edge (a chain of unfolded
                // triangles may otherwise come back over the chunk from far away on the surface).
                double near = INFINITY;
                const dvec2 ed = edge[1] - edge[0];
                for (const dvec2& v : qg) {
                    const double t = std::clamp(glm::dot(v - edge[0], ed) / std::max(1e-300, glm::dot(ed, ed)), 0.0, 1.0);
                    near = std::min(near, glm::length(v - (edge[0] + t * ed)));
                }
                if (near > double(B) + 1.0) return;
                const dvec2 glo = glm::min(qg[0], glm::min(qg[1], qg[2])), ghi = glm::max(qg[0], glm::max(qg[1], qg[2]));
                if (ghi.x < plo.x || ghi.y < plo.y || glo.x > phi.x || glo.y > phi.y) return;  // beyond the border: stop here
                ring.push_back(g);
            });
        }
        // Border texels take the first unfolded triangle (nearest ring) that covers their centre.
        std::vector<std::pair<uint32_t, std::array<dvec2, 3>>> unfolded;
        for (uint32_t g : order) unfolded.push_back({g, placed[g]});
        std::vector<int32_t> cover(size_t(W) * size_t(H), -1);
        std::vector<dvec3> cover_w(size_t(W) * size_t(H));
        for (const auto& [g, q] : unfolded) {
            const dvec2 tlo = glm::min(q[0], glm::min(q[1], q[2])), thi = glm::max(q[0], glm::max(q[1], q[2]));
            const int x0 = std::max(r0.x, int(std::floor(tlo.x - 0.5))), x1 = std::min(r1.x - 1, int(std::ceil(thi.x - 0.5)));
            const int y0 = std::max(r0.y, int(std::floor(tlo.y - 0.5))), y1 = std::min(r1.y - 1, int(std::ceil(thi.y - 0.5)));
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x) {
                    const size_t li = size_t(y - r0.y) * size_t(W) + size_t(x - r0.x);
                    if (cover[li] >= 0 || dist[li] <= 0) continue;
                    dvec3 w(0.0);
                    if (!barycentric(dvec2(x + 0.5, y + 0.5), q[0], q[1], q[2], w)) continue;
                    if (w.x < -1e-9 || w.y < -1e-9 || w.z < -1e-9) continue;
                    cover[li] = int32_t(g), cover_w[li] = w;
                }
        }
        for (const ivec2& q : border) {
            const size_t li = size_t(q.y - r0.y) * size_t(W) + size_t(q.x - r0.x), t = A.texel(q.x, q.y);
            A.texel_chunk[t] = int32_t(ci);
            A.texel_area[t] = float(texel_area);
            if (cover[li] >= 0) {
                A.texel_face[t] = cover[li], A.texel_bary[t] = vec3(cover_w[li]), A.texel_kind[t] = Atlas::kBorder;
                ++A.unfolded_border_texels;
            } else {
                const size_t src = A.texel(nearest[li].x, nearest[li].y);
                A.texel_face[t] = A.texel_face[src], A.texel_bary[t] = A.texel_bary[src], A.texel_kind[t] = Atlas::kClamped;
                ++A.clamped_border_texels;
            }
        }
        A.chunks.push_back(std::move(out));
    }
    A.fill_ratio = double(inner) / double(T);
    if (A.skipped_degenerate > 0) A.warnings.push_back(std::to_string(A.skipped_degenerate) + " degenerate triangles skipped");
    if (A.non_manifold_edges > 0) A.warnings.push_back(std::to_string(A.non_manifold_edges) + " non-manifold edges (three or more triangles)");
    return A;
}

vec3 texel_position(const Atlas& a, const std::vector<vec3>& position, const std::vector<uint32_t>& index, size_t t) {
    const int32_t f = a.texel_face[t];
    if (f < 0) return vec3(0.f);
    const vec3 w = a.texel_bary[t];
    return w.x * position[index[3 * size_t(f)]] + w.y * position[index[3 * size_t(f) + 1]] + w.z * position[index[3 * size_t(f) + 2]];
}
}  // namespace mesolab::translucency
