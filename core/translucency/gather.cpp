// Technique translucency: the gather table: per vertex, the texels its irradiance and its direct radiosity come from, and the per-frame gather (see translucency.h).
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
    mesolab::parallel_for(tbb::blocked_range<int>(0, g.n, 256), [&](const tbb::blocked_range<int>& r) {
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
}  // namespace mesolab::translucency
