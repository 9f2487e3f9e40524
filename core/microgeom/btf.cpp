#include "core/microgeom/btf.h"
#include "core/error.h"
#include "core/microgeom/scatter.h"

#include <tbb/parallel_for.h>
#include <cmath>

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
    tbb::parallel_for(size_t(0), views.size(), [&](size_t k) {
        mask[k] = s.scatter.ellipses ? ellipse_visibility_texture(*s.scatter.ellipses, hf, views[k]) : visibility_texture(hf, dirs, vis, views[k]);
    });
    for (size_t li = 0; li < lights.size(); ++li) {
        const vec3 l = lights[li];
        ScatterSettings st = s.scatter;
        st.light_dir = l;
        st.light_E = vec3(1.f);
        st.env = nullptr;
        const ScatterResult sr = scatter(hf, dirs, vis, st);
        tbb::parallel_for(size_t(0), views.size(), [&](size_t vi) {
            const vec3 v = views[vi];
            const vec3 h = glm::normalize(l + v);
            for (size_t y = 0; y < H; ++y)
                for (size_t x = 0; x < W; ++x) {
                    const size_t t = y * W + x;
                    vec3 L = sr.direct[t] + hf.albedo[t] * kInvPi * sr.E_indirect[t];
                    if (s.phong) {
                        const vec3 n = hf.normal(int(x), int(y));
                        const float cos_l = std::max(0.f, glm::dot(n, l));
                        L += s.ks * (s.shininess + 8.f) / (8.f * kPi) * std::pow(std::max(0.f, glm::dot(n, h)), s.shininess) * cos_l * sr.shadow[t];
                    }
                    L *= mask[vi][t];
                    float* q = out.at(int(vi * W + x), int(li * H + y));
                    q[0] = L.x, q[1] = L.y, q[2] = L.z;
                }
        });
        if (progress) progress(double(li + 1) / double(lights.size()));
    }
    return out;
}
}  // namespace mesolab::microgeom
