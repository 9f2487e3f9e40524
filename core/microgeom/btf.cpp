#include "core/microgeom/btf.h"
#include "core/parallel.h"
#include "core/error.h"
#include "core/microgeom/scatter.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace mesolab::microgeom {

// [SECTION] Grid
std::vector<vec3> btf_directions(int n_theta, int n_phi) {
    std::vector<vec3> d;
    for (int i = 0; i < n_theta; ++i)
        for (int j = 0; j < n_phi; ++j) {
            const float theta = (float(i) + 0.5f) / float(n_theta) * 0.5f * kPi, phi = float(j) / float(n_phi) * 2.f * kPi;
            d.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        }
    return d;
}

// [SECTION] Mosaic
Image btf_mosaic(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& s,
                 const std::vector<vec3>& lights, const std::vector<vec3>& views, const std::function<void(double)>& progress) {
    const size_t W = size_t(hf.width), H = size_t(hf.height);
    if (lights.empty() || views.empty()) throw InputError("grid: the BTF needs at least one light and one view direction");
    if (W * views.size() > 16384 || H * lights.size() > 16384)
        throw InputError("grid: a " + std::to_string(views.size()) + " x " + std::to_string(lights.size()) + " grid of " + std::to_string(W) + "x" +
                         std::to_string(H) + " images exceeds 16384 pixels per side; use a smaller grid or heightfield");
    Image out(int(W * views.size()), int(H * lights.size()), 3, 0.f);
    // Masking per view, once.
    std::vector<std::vector<float>> mask(views.size());
    mesolab::parallel_for(size_t(0), views.size(), [&](size_t k) {
        mask[k] = s.scatter.ellipses ? ellipse_visibility_texture(*s.scatter.ellipses, hf, views[k]) : visibility_texture(hf, dirs, vis, views[k]);
    });
    // Light images in batches: on s.lights where set (the GPU), else scatter() in parallel.
    const size_t batch = s.lights ? size_t(std::max(1, s.lights->batch())) : 4;
    for (size_t l0 = 0; l0 < lights.size(); l0 += batch) {
        const size_t bn = std::min(batch, lights.size() - l0);
        std::vector<std::vector<vec3>> L(bn);
        std::vector<std::vector<float>> shadow(bn);
        if (s.lights) {
            s.lights->solve(std::vector<vec3>(lights.begin() + std::ptrdiff_t(l0), lights.begin() + std::ptrdiff_t(l0 + bn)), L, shadow);
        } else {
            mesolab::parallel_for(size_t(0), bn, [&](size_t k) {
                ScatterSettings st = s.scatter;
                st.light_dir = lights[l0 + k];
                st.light_E = vec3(1.f);
                st.env = nullptr;
                ScatterResult sr = scatter(hf, dirs, vis, st);
                L[k].resize(W * H);
                for (size_t t = 0; t < W * H; ++t) L[k][t] = sr.direct[t] + hf.albedo[t] * kInvPi * sr.E_indirect[t];
                shadow[k] = std::move(sr.shadow);
            });
        }
        mesolab::parallel_for(size_t(0), bn * views.size(), [&](size_t kv) {
            const size_t k = kv / views.size(), vi = kv % views.size(), li = l0 + k;
            const vec3 l = lights[li], v = views[vi];
            const vec3 h = glm::normalize(l + v);
            for (size_t y = 0; y < H; ++y)
                for (size_t x = 0; x < W; ++x) {
                    const size_t t = y * W + x;
                    vec3 Lt = L[k][t];
                    if (s.phong) {
                        const vec3 n = hf.normal(int(x), int(y));
                        const float cos_l = std::max(0.f, glm::dot(n, l));
                        Lt += s.ks * (s.shininess + 8.f) / (8.f * kPi) * std::pow(std::max(0.f, glm::dot(n, h)), s.shininess) * cos_l * shadow[k][t];
                    }
                    Lt *= mask[vi][t];
                    float* q = out.at(int(vi * W + x), int(li * H + y));
                    q[0] = Lt.x, q[1] = Lt.y, q[2] = Lt.z;
                }
        });
        if (progress) progress(double(l0 + bn) / double(lights.size()));
    }
    return out;
}
}  // namespace mesolab::microgeom
