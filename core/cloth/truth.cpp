// Technique cloth: its truth (truth.h): the stitch's tile, the fabric instanced over the garment,
// and the yarn's material for the path tracer.
#include "core/cloth/stages.h"
#include "core/parallel.h"
#include "core/cloth/technique.h"
#include "core/cloth/truth.h"
#include "core/error.h"
#include "core/render.h"
#include "core/scene_stages.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mesolab::cloth {

TruthFabric truth_stitch_tile(const StitchParams& p) {
    const StitchMesh sm = build_stitch_mesh(make_stitch(p), kTruthStitchResolution);
    const TriMesh& m = sm.mesh;
    TruthFabric t;
    std::vector<int> remap(m.position.size(), -1);
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const uint32_t* i = &m.index[3 * f];
        const vec3 c = (m.position[i[0]] + m.position[i[1]] + m.position[i[2]]) / 3.f;
        if (c.x < 0.f || c.y < 0.f || c.x >= sm.tile.x || c.y >= sm.tile.y) continue;
        for (int k = 0; k < 3; ++k) {
            int& r = remap[i[k]];
            if (r < 0) {
                r = int(t.mesh.position.size());
                t.mesh.position.push_back(m.position[i[k]]);
                if (!m.normal.empty()) t.mesh.normal.push_back(m.normal[i[k]]);
                t.color.push_back(sm.color[i[k]]);
            }
            t.mesh.index.push_back(uint32_t(r));
        }
    }
    // z about the middle of the skeletons; the tile's period in uv (x, y).
    const float z_mid = 0.5f * (sm.lo.z + sm.hi.z);
    for (vec3& q : t.mesh.position) {
        q.z -= z_mid;
        t.half_thickness = std::max(t.half_thickness, std::fabs(q.z));
    }
    t.tile = sm.tile;
    t.mesh.uv.assign(t.mesh.position.size(), vec2(0.f));
    for (size_t v = 0; v < t.mesh.position.size(); ++v) t.mesh.uv[v] = vec2(t.mesh.position[v]) / sm.tile;
    return t;
}

namespace {
// Where a uv lies on a mesh: the triangle (of a uniform bucket grid over uv) whose barycentrics are
// least negative, so that points just outside the uv square extrapolate the nearest triangle.
class UvLocator {
public:
    explicit UvLocator(const TriMesh& m) : m_(m) {
        cells_.resize(size_t(kN) * kN);
        for (size_t f = 0; f < m.triangle_count(); ++f) {
            vec2 lo(1e30f), hi(-1e30f);
            for (int k = 0; k < 3; ++k) lo = glm::min(lo, m.uv[m.index[3 * f + k]]), hi = glm::max(hi, m.uv[m.index[3 * f + k]]);
            const ivec2 a = cell(lo), b = cell(hi);
            for (int y = a.y; y <= b.y; ++y)
                for (int x = a.x; x <= b.x; ++x) cells_[size_t(y) * kN + size_t(x)].push_back(uint32_t(f));
        }
    }
    // Triangle and barycentrics (w0, w1, w2) of uv; -1 when the mesh has no triangle near it.
    int locate(vec2 uv, vec3& w) const {
        const ivec2 c = cell(uv);
        float best = -std::numeric_limits<float>::infinity();
        int tri = -1;
        for (int r = 0; r <= 2 && tri < 0; ++r)  // the cell, then its rings, until a triangle is found
            for (int y = std::max(0, c.y - r); y <= std::min(kN - 1, c.y + r); ++y)
                for (int x = std::max(0, c.x - r); x <= std::min(kN - 1, c.x + r); ++x)
                    for (uint32_t f : cells_[size_t(y) * kN + size_t(x)]) {
                        const vec2 a = m_.uv[m_.index[3 * f]], b = m_.uv[m_.index[3 * f + 1]], d = m_.uv[m_.index[3 * f + 2]];
                        const float det = (b.x - a.x) * (d.y - a.y) - (d.x - a.x) * (b.y - a.y);
                        if (std::fabs(det) < 1e-20f) continue;
                        const float w1 = ((uv.x - a.x) * (d.y - a.y) - (d.x - a.x) * (uv.y - a.y)) / det;
                        const float w2 = ((b.x - a.x) * (uv.y - a.y) - (uv.x - a.x) * (b.y - a.y)) / det;
                        const float w0 = 1.f - w1 - w2, least = std::min({w0, w1, w2});
                        if (least > best) best = least, tri = int(f), w = vec3(w0, w1, w2);
                    }
        return tri;
    }

private:
    static constexpr int kN = 128;
    static ivec2 cell(vec2 uv) { return glm::clamp(ivec2(glm::floor(uv * float(kN))), ivec2(0), ivec2(kN - 1)); }
    const TriMesh& m_;
    std::vector<std::vector<uint32_t>> cells_;
};
}  // namespace

TruthFabric truth_fabric(const TruthFabric& tile, const TriMesh& base, int repeat) {
    if (base.uv.empty() || base.normal.empty()) throw std::logic_error("cloth truth: the garment has no uv or normals");
    double area_w = 0.0, area_uv = 0.0;
    for (size_t f = 0; f < base.triangle_count(); ++f) {
        const uint32_t a = base.index[3 * f], b = base.index[3 * f + 1], c = base.index[3 * f + 2];
        area_w += 0.5 * double(glm::length(glm::cross(base.position[b] - base.position[a], base.position[c] - base.position[a])));
        const vec2 e1 = base.uv[b] - base.uv[a], e2 = base.uv[c] - base.uv[a];
        area_uv += 0.5 * std::fabs(double(e1.x) * e2.y - double(e1.y) * e2.x);
    }
    const vec2 tile_size = tile.tile;
    const float s = float(std::sqrt(area_w / std::max(area_uv, 1e-30)) / double(repeat) / std::sqrt(double(tile_size.x) * tile_size.y));
    const UvLocator where(base);
    const size_t nv = tile.mesh.position.size(), nt = tile.mesh.index.size();
    const size_t copies = size_t(repeat) * size_t(repeat);
    TruthFabric out;
    out.mesh.position.resize(nv * copies);
    out.mesh.normal.resize(tile.mesh.normal.empty() ? 0 : nv * copies);
    out.mesh.uv.resize(nv * copies);
    out.mesh.index.resize(nt * copies);
    out.color.resize(nv * copies);
    out.half_thickness = tile.half_thickness * s;
    mesolab::parallel_for(size_t(0), copies, [&](size_t c) {
        const int i = int(c % size_t(repeat)), j = int(c / size_t(repeat));
        for (size_t v = 0; v < nv; ++v) {
            const vec2 uv = (vec2(float(i), float(j)) + tile.mesh.uv[v]) / float(repeat);
            vec3 w(1.f, 0.f, 0.f);
            const int f = where.locate(uv, w);
            vec3 P(0.f), N(0.f, 0.f, 1.f), T(1.f, 0.f, 0.f);
            if (f >= 0) {
                const uint32_t a = base.index[3 * size_t(f)], b = base.index[3 * size_t(f) + 1], d = base.index[3 * size_t(f) + 2];
                P = w.x * base.position[a] + w.y * base.position[b] + w.z * base.position[d];
                N = glm::normalize(w.x * base.normal[a] + w.y * base.normal[b] + w.z * base.normal[d]);
                if (!base.tangent.empty()) T = w.x * base.tangent[a] + w.y * base.tangent[b] + w.z * base.tangent[d];
                T -= N * glm::dot(N, T);
                T = glm::dot(T, T) > 1e-12f ? glm::normalize(T) : glm::normalize(glm::cross(std::fabs(N.x) < 0.9f ? vec3(1, 0, 0) : vec3(0, 1, 0), N));
            }
            const vec3 B = glm::cross(N, T);
            const size_t o = c * nv + v;
            out.mesh.position[o] = P + N * (tile.mesh.position[v].z * s);
            if (!tile.mesh.normal.empty()) {
                const vec3 n = tile.mesh.normal[v];
                out.mesh.normal[o] = glm::normalize(T * n.x + B * n.y + N * n.z);
            }
            out.mesh.uv[o] = uv;
            out.color[o] = tile.color[v];
        }
        for (size_t k = 0; k < nt; ++k) out.mesh.index[c * nt + k] = uint32_t(c * nv) + tile.mesh.index[k];
    });
    return out;
}

namespace {
// The yarn: Lambertian with its vertices' colour (as the acquisition lights it).
class YarnMaterial final : public TruthMaterial {
public:
    explicit YarnMaterial(std::shared_ptr<const TruthFabric> fabric) : fabric_(std::move(fabric)) {}
    vec3 albedo(const TruthHit& h) const {
        const TriMesh& m = fabric_->mesh;
        const uint32_t* i = &m.index[3 * size_t(h.triangle)];
        return (1.f - h.bary.x - h.bary.y) * fabric_->color[i[0]] + h.bary.x * fabric_->color[i[1]] + h.bary.y * fabric_->color[i[2]];
    }
    vec3 f(const TruthHit& h, vec3, vec3) const override { return albedo(h) * kInvPi; }
    bool pixel_filter() const override { return true; }  // stitches finer than a pixel: the real-time mip levels filter them

private:
    std::shared_ptr<const TruthFabric> fabric_;
};
}  // namespace

TruthObject truth_object(const Scene& s, const Evaluation& ev, int object) {
    const auto fabric = ev.get(stages::truth_fabric, object);
    TruthObject t;
    if (!fabric) return t;
    t.mesh = std::shared_ptr<const TriMesh>(fabric, &fabric->mesh);
    t.to_world = object_to_world(s.objects.at(size_t(object)));
    t.material = std::make_shared<YarnMaterial>(fabric);
    return t;
}

float truth_lift(const Scene&, const Evaluation& ev, int object) {
    const auto fabric = ev.get(stages::truth_fabric, object);
    return fabric ? 1.5f * fabric->half_thickness : 0.f;
}

std::optional<TruthDecl> ClothTechnique::truth() const {
    return TruthDecl{.params = {},
                     .stages = {stages::truth_stitch, stages::truth_fabric},
                     .object = truth_object,
                     .lift = truth_lift};
}
}  // namespace mesolab::cloth
