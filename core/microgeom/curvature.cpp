#include "core/microgeom/curvature.h"
#include "core/parallel.h"

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

// [SECTION] Fan-area importance and gather weights
Importance compute_importance(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, Bending b,
                              const std::function<void(double)>& progress) {
    Importance imp = Importance::sized(hf.width, hf.height, dirs.size());
    if (b.zero()) return imp;
    const size_t N = size_t(dirs.size()), M = dirs.triangles.size();
    imp.allocate();
    // Unbent triangle areas, once.
    std::vector<float> area0(M);
    for (size_t t = 0; t < M; ++t) {
        const auto& v = dirs.triangles[t];
        area0[t] = spherical_triangle_area(dirs.d[size_t(v[0])], dirs.d[size_t(v[1])], dirs.d[size_t(v[2])]);
    }
    const int rows_per_batch = std::max(1, hf.height / 8);
    for (int y0 = 0; y0 < hf.height; y0 += rows_per_batch) {
        const int y1 = std::min(hf.height, y0 + rows_per_batch);
        mesolab::parallel_for(y0, y1, [&](int y) {
            std::vector<vec3> bent(N);
            std::vector<uint8_t> is_hit(N);
            std::vector<float> tri_area(M);
            std::vector<uint8_t> tri_ok(M);
            for (int x = 0; x < hf.width; ++x) {
                const size_t p = hf.index(x, y);
                const vec3 n = hf.normal(x, y);
                for (size_t j = 0; j < N; ++j) {
                    const uint32_t hit = vis.at(int(j), x, y);
                    is_hit[j] = hit != Visibility::kNoHit && hit != Visibility::kBelow;
                    bent[j] = bent_direction(hf, dirs, vis, b, x, y, int(j));
                }
                // Triangles: orientation (folding) and, between three hits, the bent area.
                bool folded = false;
                for (size_t t = 0; t < M; ++t) {
                    const auto& v = dirs.triangles[t];
                    const vec3 a = bent[size_t(v[0])], bb = bent[size_t(v[1])], c = bent[size_t(v[2])];
                    // Orientation flip = the triangle turned over (counter-clockwise seen from outside before).
                    const float orient = glm::dot(a, glm::cross(bb, c));
                    folded |= orient <= 0.f;
                    tri_ok[t] = orient > 0.f && is_hit[size_t(v[0])] && is_hit[size_t(v[1])] && is_hit[size_t(v[2])];
                    tri_area[t] = tri_ok[t] ? spherical_triangle_area(a, bb, c) : 0.f;
                }
                // Importance: bent / unbent area of the fan's hit-only triangles (1 where there are none).
                float* I = &imp.I[p * N];
                for (size_t j = 0; j < N; ++j) {
                    if (!is_hit[j]) continue;
                    float a1 = 0.f, a0 = 0.f;
                    for (int t : dirs.fan[j])
                        if (tri_ok[size_t(t)]) a1 += tri_area[size_t(t)], a0 += area0[size_t(t)];
                    I[j] = a0 > 0.f ? std::max(a1 / a0, 1e-6f) : 1.f;
                }
                // Gather weights: bent hits, then the environment takes what is left of W0.
                float* w = &imp.w[p * N];
                double W0 = 0, H = 0, F = 0;
                for (size_t j = 0; j < N; ++j) {
                    const float omega = dirs.solid_angle[j];
                    W0 += double(std::max(0.f, glm::dot(n, dirs.d[j])) * omega);
                    if (is_hit[j]) {
                        w[j] = std::max(0.f, glm::dot(n, bent[j])) * omega * I[j];
                        H += double(w[j]);
                    } else {
                        w[j] = std::max(0.f, glm::dot(n, dirs.d[j])) * omega;
                        F += double(w[j]);
                    }
                }
                const double hit_scale = H > W0 || F <= 0.0 ? (H > 0.0 ? W0 / H : 0.0) : 1.0;
                const double env_scale = F > 0.0 ? std::max(0.0, W0 - H * hit_scale) / F : 0.0;
                const double total = H * hit_scale + F * env_scale;
                for (size_t j = 0; j < N; ++j)
                    w[j] = total > 0.0 ? float(double(w[j]) * (is_hit[j] ? hit_scale : env_scale) / total) : 0.f;
                imp.folded[p] = folded ? 1 : 0;
            }
        });
        if (progress) progress(double(y1) / double(hf.height));
    }
    imp.folded_count = size_t(std::count(imp.folded.begin(), imp.folded.end(), uint8_t(1)));
    return imp;
}
}  // namespace mesolab::microgeom
