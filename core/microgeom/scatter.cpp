#include "core/microgeom/scatter.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace mesolab::microgeom {

// [SECTION] Look-ups
namespace {
// Nearest texel of a packed hit (secondary bounces).
size_t nearest_texel(uint32_t packed, int w, int h) {
    const vec2 t = Visibility::decode(packed);
    const int x = std::clamp(int(std::lround(t.x)) % w, 0, w - 1), y = std::clamp(int(std::lround(t.y)) % h, 0, h - 1);
    return size_t(y) * size_t(w) + size_t(x);
}
}  // namespace

// [SECTION] Shadows and masking
float visibility_fraction(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, int x, int y, vec3 w) {
    if (glm::dot(hf.normal(x, y), w) <= 0.f) return 0.f;
    vec3 bary;
    const auto& tri = dirs.triangles[size_t(dirs.locate(w, bary))];
    float v = 0.f;
    for (int k = 0; k < 3; ++k) v += bary[k] * (vis.at(tri[size_t(k)], x, y) == Visibility::kNoHit ? 1.f : 0.f);
    return v;
}

float visibility_fraction(const Heightfield& hf, const Visibility& vis, const std::array<int, 3>& tri, vec3 bary, int x, int y, vec3 w) {
    if (glm::dot(hf.normal(x, y), w) <= 0.f) return 0.f;
    float v = 0.f;
    for (int k = 0; k < 3; ++k) v += bary[k] * (vis.at(tri[size_t(k)], x, y) == Visibility::kNoHit ? 1.f : 0.f);
    return v;
}

std::vector<float> visibility_texture(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, vec3 w) {
    std::vector<float> out(size_t(hf.width) * size_t(hf.height));
    vec3 bary;
    const auto& tri = dirs.triangles[size_t(dirs.locate(w, bary))];
    mesolab::parallel_for(0, hf.height, [&](int y) {
        for (int x = 0; x < hf.width; ++x) {
            float v = 0.f;
            if (glm::dot(hf.normal(x, y), w) > 0.f)
                for (int k = 0; k < 3; ++k) v += bary[k] * (vis.at(tri[size_t(k)], x, y) == Visibility::kNoHit ? 1.f : 0.f);
            out[hf.index(x, y)] = v;
        }
    });
    return out;
}

// [SECTION] Dependent-test scattering
std::vector<std::vector<int>> scatter_subsets(const ScatterSettings& s, int N) {
    std::mt19937 rng(s.seed);
    std::vector<std::vector<int>> out(size_t(std::clamp(s.depth, 0, 8) + 1));
    for (std::vector<int>& J : out) {
        if (s.all_directions || s.paths >= N) {
            J.resize(size_t(N));
            for (int j = 0; j < N; ++j) J[size_t(j)] = j;
        } else {
            for (int m = 0; m < s.paths; ++m) J.push_back(int(rng() % uint32_t(N)));
        }
    }
    return out;
}

ScatterResult scatter(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const ScatterSettings& s,
                      const std::function<void(double)>& progress) {
    const int W = hf.width, H = hf.height, N = dirs.size();
    const size_t T = size_t(W) * size_t(H);
    ScatterResult out;
    out.width = W;
    out.height = H;
    out.E_indirect.assign(T, vec3(0.f));

    // Normals once (the quadrature weights need them per texel and direction).
    std::vector<vec3> n(T);
    mesolab::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) n[hf.index(x, y)] = hf.normal(x, y);
    });

    // Direct light with exact shadows.
    const bool has_light = s.light_E.x > 0.f || s.light_E.y > 0.f || s.light_E.z > 0.f;
    out.shadow = !(has_light && s.shadows) ? std::vector<float>(T, 1.f)
                 : s.ellipses             ? ellipse_visibility_texture(*s.ellipses, hf, s.light_dir)
                                          : visibility_texture(hf, dirs, vis, s.light_dir);
    out.direct.assign(T, vec3(0.f));
    mesolab::parallel_for(tbb::blocked_range<size_t>(0, T, 16384), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t p = r.begin(); p < r.end(); ++p) {
            const float cos_l = std::max(0.f, glm::dot(n[p], s.light_dir));
            if (cos_l <= 0.f) out.shadow[p] = 0.f;
            if (has_light) out.direct[p] = hf.albedo[p] * kInvPi * s.light_E * cos_l * out.shadow[p];
        }
    });

    // Environment radiance per direction (constant across texels: the dependent tests).
    std::vector<vec3> L_env(size_t(N), vec3(0.f));
    if (s.env)
        for (int j = 0; j < N; ++j) L_env[size_t(j)] = s.env->radiance(dirs.d[size_t(j)]);

    // Gather: E(p) = pi * sum_j w_j(p) L_in,j(p). `primary` selects bilinear hit look-ups.
    const Importance* bent = s.importance && !s.importance->empty() ? s.importance : nullptr;
    auto gather = [&](const std::vector<vec3>* L_prev, const std::vector<int>& J, bool primary) {
        std::vector<vec3> E(T, vec3(0.f));
        mesolab::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                const size_t p = hf.index(x, y);
                vec3 sum(0.f);
                float wsum = 0.f;
                for (int j : J) {
                    const float w = bent ? bent->weight(p, j) : glm::dot(n[p], dirs.d[size_t(j)]) * dirs.solid_angle[size_t(j)];
                    if (w <= 0.f) continue;
                    wsum += w;
                    const uint32_t hit = vis.at(j, x, y);
                    if (hit == Visibility::kNoHit) {
                        sum += w * L_env[size_t(j)];
                    } else if (hit != Visibility::kBelow && L_prev) {
                        if (primary) {
                            const vec2 t = Visibility::decode(hit);
                            sum += w * sample_bilinear(*L_prev, W, H, hf.periodic, t.x, t.y);
                        } else {
                            sum += w * (*L_prev)[nearest_texel(hit, W, H)];
                        }
                    }
                }
                E[p] = wsum > 0.f ? kPi * sum / wsum : vec3(0.f);
            }
        });
        return E;
    };

    // E^0: the environment alone; L^k = L_d + rho/pi E^k; E^k gathers L^{k-1}. Depth K keeps
    // E^K: light that reflected at most K times inside the heightfield before reaching p.
    // Only the final gather (at the viewer's texel) looks hits up bilinearly.
    const int K = std::clamp(s.depth, 0, 8);
    if (s.gatherer) s.gatherer->begin(hf, dirs, vis, bent, L_env);
    auto run_gather = [&](const std::vector<vec3>* L_prev, const std::vector<int>& J, bool primary) {
        return s.gatherer ? s.gatherer->gather(L_prev, J, primary) : gather(L_prev, J, primary);
    };
    const std::vector<std::vector<int>> J = scatter_subsets(s, N);
    if (s.gatherer) {
        out.E_indirect = s.gatherer->bounces(out.direct, hf.albedo, s.env != nullptr, J, K, progress);
        return out;
    }
    // Without an environment E^0 is 0 (the light-driven solves): the gather is skipped.
    std::vector<vec3> E = s.env ? run_gather(nullptr, J[0], K == 0) : std::vector<vec3>(T, vec3(0.f));
    for (int k = 1; k <= K; ++k) {
        std::vector<vec3> L(T);
        for (size_t p = 0; p < T; ++p) L[p] = out.direct[p] + hf.albedo[p] * kInvPi * E[p];
        E = run_gather(&L, J[size_t(k)], k == K);
        if (progress) progress(double(k) / double(K));
    }
    out.E_indirect = std::move(E);
    return out;
}

std::vector<vec3> Gatherer::bounces(const std::vector<vec3>& direct, const std::vector<vec3>& albedo, bool env, const std::vector<std::vector<int>>& J,
                                    int K, const std::function<void(double)>& progress) {
    const size_t T = direct.size();
    std::vector<vec3> E = env ? gather(nullptr, J[0], K == 0) : std::vector<vec3>(T, vec3(0.f));
    for (int k = 1; k <= K; ++k) {
        std::vector<vec3> L(T);
        for (size_t p = 0; p < T; ++p) L[p] = direct[p] + albedo[p] * kInvPi * E[p];
        E = gather(&L, J[size_t(k)], k == K);
        if (progress) progress(double(k) / double(K));
    }
    return E;
}

// [SECTION] Scattering tabulated over light directions (non-planar bases)
namespace {
constexpr int kDirectionBlock = 8;  // directions solved in parallel between progress calls
}  // namespace

vec3 DirectionalScatter::irradiance(const DirectionSet& dirs, vec3 l, float c, float r) const {
    vec3 bary;
    const auto& tri = dirs.triangles[size_t(dirs.locate(l, bary))];
    return irradiance(tri, bary, c, r);
}

vec3 DirectionalScatter::irradiance(const std::array<int, 3>& tri, vec3 bary, float c, float r) const {
    const size_t T = size_t(width) * size_t(height);
    vec3 sum(0.f);
    for (int k = 0; k < 3; ++k)
        if (tri[size_t(k)] < count) sum += bary[k] * sample_bilinear(E.data() + size_t(tri[size_t(k)]) * T, width, height, true, c, r);
    return sum;
}

int directions_above_horizon(const DirectionSet& dirs) {
    int m = 0;
    while (m < dirs.size() && dirs.d[size_t(m)].z > 0.f) ++m;
    for (int j = m; j < dirs.size(); ++j)
        if (dirs.d[size_t(j)].z > 0.f) throw std::logic_error("microgeom: the directions above the horizon are not the first of the set");
    return m;
}

DirectionalScatter scatter_directions(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const ScatterSettings& s,
                                      const std::function<void(double)>& progress) {
    DirectionalScatter out;
    out.width = hf.width;
    out.height = hf.height;
    out.count = directions_above_horizon(dirs);
    const size_t T = size_t(hf.width) * size_t(hf.height);
    out.E.assign(size_t(out.count) * T, vec3(0.f));
    auto solve = [&](int j) {
        ScatterSettings st = s;
        st.light_dir = dirs.d[size_t(j)];
        st.light_E = vec3(1.f);
        st.env = nullptr;
        const ScatterResult r = scatter(hf, dirs, vis, st);
        std::copy(r.E_indirect.begin(), r.E_indirect.end(), out.E.begin() + std::ptrdiff_t(size_t(j) * T));
    };
    if (progress) progress(0.0);
    const int block = s.gatherer ? 1 : kDirectionBlock;
    for (int j0 = 0; j0 < out.count; j0 += block) {
        const int j1 = std::min(out.count, j0 + block);
        if (s.gatherer) {
            solve(j0);
        } else {
            mesolab::parallel_for(j0, j1, [&](int j) { solve(j); });
        }
        if (progress) progress(double(j1) / double(out.count));
    }
    return out;
}
}  // namespace mesolab::microgeom
