#pragma once
// The energy harness the translucency tests share: a closed mesh lit through the technique's own
// illumination step, its radiosity computed by the technique's stages and frame steps on the CPU
// (local kernels, vertex factors, blending, the gather table), and Σ B A / Σ E A over the atlas's
// inner texels (area-weighted) against the brute-force reference on the same atlas.
#include "core/mesh.h"
#include "core/render.h"
#include "core/translucency/reference.h"
#include "core/translucency/translucency.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace mesolab::translucency::test {

struct Shape {
    std::vector<vec3> position;
    std::vector<uint32_t> index;
};

inline Light point_light(vec3 p) {
    Light l;
    l.point = true;
    l.position = p;
    l.radiance = vec3(1.f);
    return l;
}

inline Light directional_light(vec3 direction) {
    Light l;
    l.direction = glm::normalize(direction);
    l.radiance = vec3(1.f);
    return l;
}

struct EnergySettings {
    std::string material = "skin1";
    int atlas = 192, kernel = 7;
    float threshold = 3e-5f;
    bool unblended = true;  // also the unblended sum (kernels, factors alone)
    bool rmse = true;       // the blended RMSE and lowest value against the reference
    bool burley = false;    // Christensen and Burley's profile (lensch-burley) instead of the dipole
};

struct Energy {
    dvec3 blended{0.0}, unblended{0.0}, kernels{0.0}, factors{0.0}, reference{0.0};  // Σ B A / Σ E A
    double lowest = 0.0;                            // most negative blended radiosity / the reference's mean
    dvec3 rmse{0.0};                                // blended against the reference, over its mean
    bool lit = false;                               // some inner texel has irradiance
    dvec3 ratio() const { return blended / reference; }
};

// Every vertex kept, the atlas and K of `s`, the factors' threshold: the technique's stages and
// frame steps on the CPU, blended (and, with s.unblended, not).
inline Energy energy(const Shape& shape, double mm, const Light& light, const EnergySettings& s = {}) {
    const PreparedMesh m = prepare_mesh(shape.position, shape.index, 0);
    const AtlasStage a = make_atlas_stage(m, {s.atlas, (s.kernel - 1) / 2 + 1, 30.f});
    const Medium medium = measured_material(s.material).medium;
    const std::unique_ptr<Profile> profile = s.burley ? std::unique_ptr<Profile>(std::make_unique<BurleyProfile>(medium)) : std::make_unique<Dipole>(medium);
    const Profile& d = *profile;
    Lighting L;
    L.lights = {light};
    L.env_lighting = false;
    const std::vector<ShadowMap> shadows = {make_shadow_map(*a.display, mat4(1.f), light, 512)};
    const std::vector<vec3> E = illuminate(a, mat4(1.f), L, medium.eta, shadows);
    const std::vector<float> A = vertex_areas(m.position, m.index, mm);
    Energy r;
    dvec3 in(0.0);
    for (size_t t = 0; t < E.size(); ++t)
        if (a.atlas.texel_kind[t] == Atlas::kInner) in += dvec3(E[t]) * double(a.atlas.texel_area[t]);
    r.lit = in.x > 0.0 && in.y > 0.0 && in.z > 0.0;
    if (!r.lit) return r;
    auto ratio = [&](const std::vector<vec3>& B) {
        dvec3 out(0.0);
        for (size_t t = 0; t < B.size(); ++t)
            if (a.atlas.texel_kind[t] == Atlas::kInner) out += dvec3(B[t]) * double(a.atlas.texel_area[t]);
        return out / in;
    };
    std::vector<vec3> blended;
    for (const bool blend : {true, false}) {
        if (!blend && !s.unblended) continue;
        LocalKernels K = build_local_kernels(a.atlas, m.position, m.index, d, mm, s.kernel);
        const VertexFactors F = build_vertex_factors(m.position, m.index, d, {mm, s.threshold, blend});
        std::unique_ptr<BlendWeights> w;
        if (blend) w = std::make_unique<BlendWeights>(fit_blending(a.atlas, m.position, m.index, d, mm, F, K));
        const VertexValues v = gather_vertices(make_gather(a.atlas, m.index, A, mm, w.get(), blend ? &K : nullptr), E);
        std::vector<vec3> Bv = F.multiply(v.E);
        for (size_t i = 0; i < Bv.size(); ++i) Bv[i] += v.direct[i];
        const std::vector<vec3> local = convolve_local(K, E), global = interpolate_to_texels(a.atlas, m.index, Bv);
        std::vector<vec3> B(local.size());
        for (size_t t = 0; t < B.size(); ++t) B[t] = local[t] + global[t];
        if (blend) {
            r.blended = ratio(B);
            blended = std::move(B);
        } else {
            r.unblended = ratio(B), r.kernels = ratio(local), r.factors = ratio(global);
        }
    }
    const std::vector<vec3> ref = reference_radiosity(a.atlas, texel_positions_mm(a.atlas, m.position, m.index, mm), d, mm, E);
    r.reference = ratio(ref);
    if (!s.rmse) return r;
    dvec3 sum(0.0), se(0.0);
    double lowest = 0.0;
    size_t n = 0;
    for (size_t t = 0; t < ref.size(); ++t)
        if (a.atlas.texel_kind[t] == Atlas::kInner) {
            ++n;
            for (int c = 0; c < 3; ++c) {
                sum[c] += double(ref[t][c]), se[c] += std::pow(double(blended[t][c] - ref[t][c]), 2.0);
                lowest = std::min(lowest, double(blended[t][c]));
            }
        }
    r.lowest = lowest / ((sum.x + sum.y + sum.z) / (3.0 * double(n)));
    for (int c = 0; c < 3; ++c) r.rmse[c] = std::sqrt(se[c] / double(n)) / (sum[c] / double(n));
    return r;
}
}  // namespace mesolab::translucency::test
