#include "core/microgeom/lod.h"
#include "core/microgeom/scatter.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>

namespace mesolab::microgeom {

// [SECTION] Tessellation rate
int displacement_resolution(const std::string& type, int base_resolution, int field_width, int field_height, float tiling, int cap, bool* capped) {
    // Segments along u; the sphere has half as many along v (mesh.h), so it needs twice the rate,
    // and so does the teapot (its atlas has 8 patch cells along u, 4 along v, resolution/8 segments per patch side).
    const double along_u = double(field_width) * tiling, along_v = double(field_height) * tiling;
    const bool half_along_v = type == "sphere" || type == "teapot";
    double need = std::max(along_u, half_along_v ? 2.0 * along_v : along_v);
    need = std::ceil(need);
    if (capped) *capped = need > cap;
    return int(std::clamp(need, double(base_resolution), double(std::max(cap, base_resolution))));
}

// [SECTION] Displacement
TriMesh displace(const TriMesh& base, const Heightfield& hf, float tiling) {
    TriMesh m = base;
    const size_t nv = m.vertex_count();
    // World length per uv unit at each vertex: sqrt(sum world area / sum uv area) of its triangles.
    std::vector<double> area_w(nv, 0.0), area_uv(nv, 0.0);
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const uint32_t a = m.index[3 * t], b = m.index[3 * t + 1], c = m.index[3 * t + 2];
        const double aw = 0.5 * double(glm::length(glm::cross(m.position[b] - m.position[a], m.position[c] - m.position[a])));
        const vec2 e1 = m.uv[b] - m.uv[a], e2 = m.uv[c] - m.uv[a];
        const double auv = 0.5 * std::fabs(double(e1.x) * e2.y - double(e1.y) * e2.x);
        for (uint32_t v : {a, b, c}) area_w[v] += aw, area_uv[v] += auv;
    }
    double mean = 0.0;
    for (float h : hf.h) mean += h;
    mean /= double(std::max<size_t>(1, hf.h.size()));
    const float inv_s = 1.f / hf.texel_size;
    tbb::parallel_for(size_t(0), nv, [&](size_t v) {
        const vec2 uv = m.uv[v];
        const float c = uv.x * float(hf.width) * tiling - 0.5f, r = (1.f - uv.y) * float(hf.height) * tiling - 0.5f;
        const float h = sample_bilinear(hf.h, hf.width, hf.height, true, c, r);
        const double per_uv = area_uv[v] > 0.0 ? std::sqrt(area_w[v] / area_uv[v]) : 0.0;
        const float texel = float(per_uv / (double(hf.width) * tiling));
        m.position[v] += m.normal[v] * ((h - float(mean)) * inv_s * texel);
    });
    return m;
}
}  // namespace mesolab::microgeom
