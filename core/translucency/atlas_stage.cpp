// Technique translucency: the atlas stage's extras: each texel's surface point and normal, where border texels take their value from, the mesh drawn in atlas space (see translucency.h).
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
    mesolab::parallel_for(size_t(0), s.nonempty.size(), [&](size_t k) {
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
            mesolab::parallel_for(size_t(0), orphans.size(), [&](size_t k) {
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
        mesolab::parallel_for(size_t(0), s.nonempty.size(), [&](size_t k) {
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
}  // namespace mesolab::translucency
