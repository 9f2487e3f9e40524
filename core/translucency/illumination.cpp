// Technique translucency: the illumination map (irradiance entering the medium per texel), the combination of the responses and the texel look-ups (see translucency.h).
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

// [SECTION] Illumination
vec3 entering_irradiance(vec3 p, vec3 n, const Lighting& L, double eta, const std::vector<ShadowMap>& shadows) {
    // Schlick's transmittance (fresnel_transmittance) in single precision: c is in (0, 1] here.
    const float r0 = float((eta - 1.0) / (eta + 1.0) * ((eta - 1.0) / (eta + 1.0)));
    const auto transmittance = [&](float c) {
        if (eta == 1.0) return 1.f;
        const float m = 1.f - std::min(c, 1.f), m2 = m * m;
        return std::clamp(1.f - (r0 + (1.f - r0) * m2 * m2 * m), 0.f, 1.f);
    };
    vec3 e(0.f);
    for (size_t i = 0; i < L.lights.size(); ++i) {
        vec3 wi, El;
        L.lights[i].sample(p, wi, El);
        const float c = glm::dot(n, wi);
        if (c <= 0.f) continue;
        const float v = i < shadows.size() ? shadows[i].visibility(p) : 1.f;
        e += El * (c * transmittance(c) * v);
    }
    // Entering from outside: the lights' T averaged over the hemisphere.
    return e + L.env_irradiance(n) * float(diffuse_transmittance(eta));
}

std::vector<vec3> illuminate(const AtlasStage& a, const mat4& model, const Lighting& L, double eta, const std::vector<ShadowMap>& shadows) {
    std::vector<vec3> E(a.texel_position.size(), vec3(0.f));
    const mat3 normal_matrix = glm::transpose(glm::inverse(mat3(model)));
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, a.lit.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const size_t t = size_t(a.lit[k]);
            E[t] = entering_irradiance(vec3(model * vec4(a.texel_position[t], 1.f)), glm::normalize(normal_matrix * a.texel_normal[t]), L, eta, shadows);
        }
    });
    // Border texels whose surface another chunk holds take its value.
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, a.copy.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) E[size_t(a.copy[k].x)] = E[size_t(a.copy[k].y)];
    });
    return E;
}

// [SECTION] Combine and look-ups
std::vector<vec3> fill_texels(const AtlasStage& a, const std::vector<vec3>& v) {
    std::vector<vec3> out(v.size(), vec3(0.f));
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, v.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
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
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, E.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
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
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, a.nonempty.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
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
