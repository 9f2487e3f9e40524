// Technique cloth: the BRDF pyramid packed as the GPU pass reads it (cloth.h, PackedPyramid).
#include "core/cloth/cloth.h"

#include <algorithm>

namespace mesolab::cloth {

// [SECTION] The pyramid for the GPU
PackedPyramid pack_pyramid(const BrdfPyramid& p) {
    PackedPyramid out;
    out.res = p.res;
    size_t lobes = 0, dirs = 0, count = 0;
    for (const auto& level : p.level)
        for (const ClothBrdf& b : level) lobes = std::max(lobes, b.sheen ? size_t(1) : b.L.lobes.size()), dirs = std::max(dirs, b.table.v.size()), ++count;
    out.stride = int(5 + 4 * lobes + 2 * dirs);
    out.lobes = int(lobes), out.dirs = int(dirs);
    out.data.assign(count * size_t(out.stride), vec4(0.f));
    size_t e = 0;
    for (size_t k = 0; k < p.level.size(); ++k) {
        out.level_first.push_back(int(e));
        for (size_t i = 0; i < p.level[k].size(); ++i, ++e) {
            const ClothBrdf& b = p.level[k][i];
            const glm::dmat3& F = p.frame[k][i];
            vec4* r = &out.data[e * size_t(out.stride)];
            r[0] = vec4(vec3(b.L.kd), b.sheen ? -1.f : float(b.L.lobes.size()));
            // glm is column-major: row j of F is (F[0][j], F[1][j], F[2][j]).
            for (int j = 0; j < 3; ++j) r[1 + j] = vec4(float(F[0][j]), float(F[1][j]), float(F[2][j]), 0.f);
            r[1].w = float(b.table.v.size());
            constexpr double kFloatMax = 3.0e38;
            r[4] = vec4(vec3(glm::min(b.f_max, dvec3(kFloatMax))), 0.f);
            vec4* q = r + 5;
            if (b.sheen) *q = vec4(vec3(b.sheen->S), float(b.sheen->r));  // the sheen in the first lobe's place
            for (const LafortuneLobe& l : b.L.lobes) {
                *q++ = vec4(vec3(l.Cx), 0.f);
                *q++ = vec4(vec3(l.Cy), 0.f);
                *q++ = vec4(vec3(l.Cz), 0.f);
                *q++ = vec4(vec3(l.n), 0.f);
            }
            q = r + 5 + 4 * lobes;
            for (size_t d = 0; d < b.table.v.size(); ++d) {
                *q++ = vec4(vec3(b.table.v[d]), 0.f);
                *q++ = vec4(b.table.T[d]);
            }
        }
    }
    // The shared views: the top entry's directions taken back to the pattern frame, checked on every entry.
    if (dirs > 0 && !p.level.empty()) {
        const ClothBrdf& top = p.level.back()[0];
        const glm::dmat3 Ft = glm::transpose(p.frame.back()[0]);
        std::vector<dvec3> views;
        for (const dvec3& v : top.table.v) views.push_back(Ft * v);
        bool shared = views.size() == dirs;
        for (size_t k = 0; k < p.level.size() && shared; ++k)
            for (size_t i = 0; i < p.level[k].size() && shared; ++i) {
                const auto& tv = p.level[k][i].table.v;
                shared = tv.size() == views.size();
                for (size_t d = 0; d < tv.size() && shared; ++d) shared = glm::length(p.frame[k][i] * views[d] - tv[d]) < 1e-6;
            }
        if (shared)
            for (const dvec3& v : views) out.shared_views.push_back(vec4(vec3(v), 0.f));
    }
    return out;
}
}  // namespace mesolab::cloth
