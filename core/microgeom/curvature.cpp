#include "core/microgeom/curvature.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>

namespace mesolab::microgeom {

Bending Bending::from_degrees(float across_u_deg, float across_v_deg, int width, int height) {
    return {radians(across_u_deg) / float(std::max(1, width)), radians(across_v_deg) / float(std::max(1, height))};
}

// [SECTION] Bent directions
vec3 bent_direction(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b, int x, int y, int j) {
    const vec3 d = dirs.d[size_t(j)];
    const uint32_t hit = vis.at(j, x, y);
    if (b.zero() || hit == Visibility::kNoHit || hit == Visibility::kBelow) return d;
    // Horizontal offset to the hit in texels (local x = +column, local y = -row), nearest image.
    const vec2 t = Visibility::decode(hit);
    float dx = t.x - float(x), dy = -(t.y - float(y));
    if (hf.periodic) {
        dx -= float(hf.width) * std::round(dx / float(hf.width));
        dy -= float(hf.height) * std::round(dy / float(hf.height));
    }
    // The hit point relative to p along the ray (t_len texels), lowered by the paraboloid.
    const float horiz = std::sqrt(d.x * d.x + d.y * d.y);
    const float len = horiz > 1e-6f ? std::sqrt(dx * dx + dy * dy) / horiz : 0.f;
    vec3 q = d * len;
    q.z -= 0.5f * (b.ku * dx * dx + b.kv * dy * dy);
    const float l2 = glm::dot(q, q);
    return l2 > 1e-20f ? q / std::sqrt(l2) : d;
}

// [SECTION] Fan-area importance
Importance compute_importance(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                              const std::function<void(double)>& progress) {
    Importance imp;
    imp.width = hf.width;
    imp.height = hf.height;
    imp.count = dirs.size();
    if (b.zero()) return imp;
    const size_t T = size_t(hf.width) * size_t(hf.height), N = size_t(dirs.size());
    imp.w.assign(T * N, 1.f);
    imp.folded.assign(T, 0);
    // Fan areas of the unbent set, once.
    std::vector<float> fan0(N, 0.f);
    for (size_t j = 0; j < N; ++j)
        for (int t : dirs.fan[j]) {
            const auto& v = dirs.triangles[size_t(t)];
            fan0[j] += spherical_triangle_area(dirs.d[size_t(v[0])], dirs.d[size_t(v[1])], dirs.d[size_t(v[2])]);
        }
    const int rows_per_batch = std::max(1, hf.height / 8);
    for (int y0 = 0; y0 < hf.height; y0 += rows_per_batch) {
        const int y1 = std::min(hf.height, y0 + rows_per_batch);
        tbb::parallel_for(y0, y1, [&](int y) {
            std::vector<vec3> bent(N);
            std::vector<float> tri_area(dirs.triangles.size());
            for (int x = 0; x < hf.width; ++x) {
                const size_t p = hf.index(x, y);
                for (size_t j = 0; j < N; ++j) bent[j] = bent_direction(hf, dirs, vis, b, x, y, int(j));
                bool folded = false;
                for (size_t t = 0; t < dirs.triangles.size(); ++t) {
                    const auto& v = dirs.triangles[t];
                    const vec3 a = bent[size_t(v[0])], bb = bent[size_t(v[1])], c = bent[size_t(v[2])];
                    // Orientation flip = the triangle turned over (counter-clockwise seen from outside before).
                    const float orient = glm::dot(a, glm::cross(bb, c));
                    folded |= orient <= 0.f;
                    tri_area[t] = orient <= 0.f ? 0.f : spherical_triangle_area(a, bb, c);
                }
                for (size_t j = 0; j < N; ++j) {
                    float area = 0.f;
                    for (int t : dirs.fan[j]) area += tri_area[size_t(t)];
                    imp.w[p * N + j] = fan0[j] > 0.f ? area / fan0[j] : 1.f;
                }
                imp.folded[p] = folded ? 1 : 0;
            }
        });
        if (progress) progress(double(y1) / double(hf.height));
    }
    imp.folded_count = size_t(std::count(imp.folded.begin(), imp.folded.end(), uint8_t(1)));
    return imp;
}
}  // namespace mesolab::microgeom
