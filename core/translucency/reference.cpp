// The reference radiosity (see reference.h).
#include "core/translucency/reference.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>

namespace mesolab::translucency {

vec3 reference_self_weight(const Profile& dipole, const RdTable& Rd, float area) {
    return vec3(dipole.reflectance_within(std::sqrt(double(texel_disk_r2(area))))) - Rd.at_r2(texel_disk_r2(area)) * area;
}

std::vector<vec3> reference_radiosity(const Atlas& atlas, const std::vector<vec3>& x, const Profile& dipole, double mm_per_unit,
                                      const std::vector<vec3>& E) {
    const float s2 = float(mm_per_unit * mm_per_unit);
    // Sources: lit inner texels, with their power E A (mm²).
    struct Source {
        vec3 x, power;
        float r2_min;  // ρ² of its disk (local.h)
    };
    std::vector<Source> src;
    vec3 lo(INFINITY), hi(-INFINITY);
    for (size_t t = 0; t < E.size(); ++t) {
        if (atlas.texel_kind[t] != Atlas::kInner) continue;
        lo = glm::min(lo, x[t]), hi = glm::max(hi, x[t]);
        if (E[t] != vec3(0.f)) src.push_back({x[t], E[t] * (atlas.texel_area[t] * s2), texel_disk_r2(atlas.texel_area[t] * s2)});
    }
    std::vector<vec3> B(E.size(), vec3(0.f));
    if (src.empty()) return B;
    const RdTable Rd(dipole, std::max(1e-6, double(glm::length(hi - lo))) * 1.0001);
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, E.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            if (atlas.texel_kind[t] != Atlas::kInner) continue;
            const vec3 xt = x[t];
            vec3 sum(0.f);
            for (const Source& s : src) {
                const vec3 d = s.x - xt;
                sum += Rd.at_r2(std::max(glm::dot(d, d), s.r2_min)) * s.power;
            }
            // The texel itself: its disk instead of R_d(ρ) A_t.
            sum += reference_self_weight(dipole, Rd, atlas.texel_area[t] * s2) * E[t];
            B[t] = sum;
        }
    });
    return B;
}
}  // namespace mesolab::translucency
