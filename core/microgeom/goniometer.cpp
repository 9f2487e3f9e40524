#include "core/microgeom/goniometer.h"
#include "core/parallel.h"

#include "core/error.h"

// Eigen (header-only, find_package(Eigen3) -> Eigen3::Eigen: a system include directory, so its
// headers stay out of our warnings).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace mesolab::microgeom {

namespace {

constexpr double kPiD = 3.14159265358979323846;
constexpr int kLightBlock = 8;    // light solves per block (parallel within, progress between)

// [SECTION] Validation
void check_inputs(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis) {
    const size_t T = size_t(hf.width) * size_t(hf.height);
    if (hf.width < 1 || hf.height < 1 || hf.h.size() != T || hf.albedo.size() != T)
        throw InputError("microgeom.heightfield: " + std::to_string(hf.width) + "x" + std::to_string(hf.height) +
                         " field with " + std::to_string(hf.h.size()) + " heights and " + std::to_string(hf.albedo.size()) + " albedos");
    if (vis.width != hf.width || vis.height != hf.height || vis.count != dirs.size() ||
        vis.hit.size() != T * size_t(std::max(vis.count, 0)))
        throw InputError("microgeom.visibility: visibility for " + std::to_string(vis.width) + "x" + std::to_string(vis.height) +
                         " texels and " + std::to_string(vis.count) + " directions does not match the " + std::to_string(hf.width) +
                         "x" + std::to_string(hf.height) + " heightfield and " + std::to_string(dirs.size()) + " directions");
}

void check_settings(const GonioSettings& g) {
    if (g.resolution < 2 || g.resolution > 64)
        throw InputError("microgeom.brdf_resolution: value " + std::to_string(g.resolution) + " is out of range [2, 64]");
    if (g.samples < 1)
        throw InputError("microgeom.brdf_samples: value " + std::to_string(g.samples) + " must be >= 1");
    if (g.sh_bands < 1 || g.sh_bands > 8)
        throw InputError("microgeom.sh_bands: value " + std::to_string(g.sh_bands) + " is out of range [1, 8]");
}

vec3 safe_normalize(vec3 w) {
    const float len = glm::length(w);
    return std::isfinite(len) && len > 0.f ? w / len : vec3(0.f);
}

// [SECTION] Per-texel quantities
// Normals once per call (every image needs them).
std::vector<vec3> normals_of(const Heightfield& hf) {
    std::vector<vec3> n(size_t(hf.width) * size_t(hf.height));
    mesolab::parallel_for(0, hf.height, [&](int y) {
        for (int x = 0; x < hf.width; ++x) n[hf.index(x, y)] = hf.normal(x, y);
    });
    return n;
}

// V(x, wo): the shadow-test data with the view direction (§6), 0 below the texel's plane.
std::vector<float> view_visibility(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g, vec3 wo) {
    return g.scatter.ellipses ? ellipse_visibility_texture(*g.scatter.ellipses, hf, wo) : visibility_texture(hf, dirs, vis, wo);
}

// m(x, wo) = V(x, wo) max(0, n.wo) / n.z.
std::vector<float> masking(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g,
                           const std::vector<vec3>& n, vec3 wo) {
    std::vector<float> m = view_visibility(hf, dirs, vis, g, wo);
    for (size_t p = 0; p < m.size(); ++p) m[p] *= std::max(0.f, glm::dot(n[p], wo)) / n[p].z;
    return m;
}

// L(x, wi) (Lambert part, view-independent) and max(0, n.wi) V(x, wi) for the lobe.
struct LightImage {
    std::vector<vec3> L;
    std::vector<float> cos_vis;  // only with phong
};

// L and, for the lobe, max(0, n.wi) V(x, wi) from the shadow texture.
LightImage light_image(const GonioSettings& g, const std::vector<vec3>& n, vec3 wi, std::vector<vec3> L,
                       const std::vector<float>& shadow) {
    LightImage out;
    out.L = std::move(L);
    if (g.phong) {
        out.cos_vis.resize(shadow.size());
        for (size_t p = 0; p < out.cos_vis.size(); ++p) out.cos_vis[p] = std::max(0.f, glm::dot(n[p], wi)) * shadow[p];
    }
    return out;
}

LightImage solve_light(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g,
                       const std::vector<vec3>& n, vec3 wi) {
    ScatterSettings s = g.scatter;
    s.light_dir = wi;
    s.light_E = vec3(1.f);
    s.env = nullptr;
    const ScatterResult r = scatter(hf, dirs, vis, s);
    std::vector<vec3> L(r.direct.size());
    for (size_t p = 0; p < L.size(); ++p) L[p] = r.direct[p] + hf.albedo[p] * kInvPi * r.E_indirect[p];
    return light_image(g, n, wi, std::move(L), r.shadow);
}

// Lights per batch: the light solver's (the GPU), or kLightBlock solved in parallel on the CPU.
int light_batch(const GonioSettings& g) { return g.lights ? std::max(1, g.lights->batch()) : kLightBlock; }

// The images of a batch of lights: on g.lights where set, else scatter() in parallel.
std::vector<LightImage> solve_lights(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g,
                                     const std::vector<vec3>& n, const std::vector<vec3>& wis) {
    std::vector<LightImage> out(wis.size());
    if (g.lights) {
        std::vector<std::vector<vec3>> L;
        std::vector<std::vector<float>> shadow;
        g.lights->solve(wis, L, shadow);
        for (size_t k = 0; k < wis.size(); ++k) out[k] = light_image(g, n, wis[k], std::move(L[k]), shadow[k]);
        return out;
    }
    mesolab::parallel_for(size_t(0), wis.size(), [&](size_t k) { out[k] = solve_light(hf, dirs, vis, g, n, wis[k]); });
    return out;
}

// rho/pi E_ind(x) under a constant white sky (radiance 1), no light.
std::vector<vec3> solve_env(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g) {
    Environment white;
    white.color = vec3(1.f);
    ScatterSettings s = g.scatter;
    s.light_E = vec3(0.f);
    s.env = &white;
    const ScatterResult r = scatter(hf, dirs, vis, s);
    std::vector<vec3> L(r.E_indirect.size());
    for (size_t p = 0; p < L.size(); ++p) L[p] = hf.albedo[p] * kInvPi * r.E_indirect[p];
    return L;
}

// Blinn-Phong radiance of texel p: ks (s + 8)/(8 pi) max(0, n.h)^s max(0, n.wi) V(x, wi).
vec3 phong_lobe(const GonioSettings& g, vec3 n, vec3 h, float cos_vis) {
    if (cos_vis <= 0.f) return vec3(0.f);
    const float nh = std::max(0.f, glm::dot(n, h));
    return g.ks * ((g.shininess + 8.f) / (8.f * kPi) * std::pow(nh, g.shininess) * cos_vis);
}

// sum_x L(x, wi, wo) m(x, wo) / sum_x m(x, wo), in double.
vec3 masked_average(const GonioSettings& g, const std::vector<vec3>& n, const LightImage& li,
                    const std::vector<float>& m, vec3 wi, vec3 wo) {
    const vec3 h = safe_normalize(wi + wo);
    double sum[3] = {0, 0, 0}, wsum = 0;
    for (size_t p = 0; p < m.size(); ++p) {
        if (m[p] <= 0.f) continue;
        vec3 L = li.L[p];
        if (g.phong) L += phong_lobe(g, n[p], h, li.cos_vis[p]);
        for (int c = 0; c < 3; ++c) sum[c] += double(L[c]) * double(m[p]);
        wsum += double(m[p]);
    }
    if (!(wsum > 0)) return vec3(0.f);
    return vec3(float(sum[0] / wsum), float(sum[1] / wsum), float(sum[2] / wsum));
}

// [SECTION] Nodes
// Node direction with theta clamped to <= theta_max (double precision).
vec3 node_dir(int i, int j, int n_theta, int n_phi, double theta_max) {
    const double theta = std::min(double(i) / double(n_theta - 1) * (kPiD / 2), theta_max);
    const double phi = double(j) / double(n_phi) * 2 * kPiD;
    return vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
}

// Distinct directions: 0 = the pole (every theta = 0 node), then 1 + (i - 1) n_phi + j.
int distinct_of(int node, int n_phi) {
    const int i = node / n_phi, j = node % n_phi;
    return i == 0 ? 0 : 1 + (i - 1) * n_phi + j;
}

// The 4 bilinear taps of a direction over the node grid (the look-up in the header).
struct Taps {
    int node[4];
    float w[4];
};

Taps taps_of(vec3 w, int n_theta, int n_phi) {
    const float t = std::clamp(std::acos(std::min(w.z, 1.f)) / (kPi / 2.f) * float(n_theta - 1), 0.f, float(n_theta - 1));
    const int i0 = std::min(int(std::floor(t)), n_theta - 2), i1 = i0 + 1;
    const float a = t - float(i0);
    float u = (w.x == 0.f && w.y == 0.f) ? 0.f : std::atan2(w.y, w.x) / (2.f * kPi);
    u -= std::floor(u);
    const float s = u * float(n_phi), jf = std::floor(s), b = s - jf;
    const int j0 = ((int(jf) % n_phi) + n_phi) % n_phi, j1 = (j0 + 1) % n_phi;
    return {{i0 * n_phi + j0, i0 * n_phi + j1, i1 * n_phi + j0, i1 * n_phi + j1},
            {(1.f - a) * (1.f - b), (1.f - a) * b, a * (1.f - b), a * b}};
}

// [SECTION] Spherical harmonics
// Associated Legendre P_l^m(x) with the Condon-Shortley phase (the standard recurrence).
double legendre(int l, int m, double x) {
    double pmm = 1;
    if (m > 0) {
        const double somx2 = std::sqrt(std::max(0.0, (1 - x) * (1 + x)));
        double fact = 1;
        for (int i = 1; i <= m; ++i) {
            pmm *= -fact * somx2;
            fact += 2;
        }
    }
    if (l == m) return pmm;
    double pmmp1 = x * (2 * m + 1) * pmm;
    if (l == m + 1) return pmmp1;
    double pll = 0;
    for (int ll = m + 2; ll <= l; ++ll) {
        pll = ((2 * ll - 1) * x * pmmp1 - (ll + m - 1) * pmm) / (ll - m);
        pmm = pmmp1;
        pmmp1 = pll;
    }
    return pll;
}

double sh_norm(int l, int m) {
    double ratio = 1;  // (l - m)! / (l + m)!
    for (int k = l - m + 1; k <= l + m; ++k) ratio /= double(k);
    return std::sqrt((2 * l + 1) / (4 * kPiD) * ratio);
}

// (count x B) matrix of Y_k(w) for the given directions.
Eigen::MatrixXd sh_rows(int bands, const std::vector<vec3>& ws) {
    const int B = bands * bands;
    Eigen::MatrixXd Y(Eigen::Index(ws.size()), B);
    std::vector<double> y(static_cast<size_t>(B));
    for (size_t r = 0; r < ws.size(); ++r) {
        real_sh(bands, ws[r], y.data());
        for (int k = 0; k < B; ++k) Y(Eigen::Index(r), k) = y[size_t(k)];
    }
    return Y;
}

// A unit direction uniform in solid angle on the upper hemisphere (z in (0, 1]).
vec3 hemisphere_sample(std::mt19937& rng) {
    const double u1 = double(rng() >> 8) * 0x1p-24, u2 = double(rng() >> 8) * 0x1p-24;
    const double z = 1 - u1, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPiD * u2;
    return vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
}

// [SECTION] Simulation: table
// T for all distinct (light, view) directions: matrix products of the light images with the
// normalised masking weights, plus the lobe where enabled. Returns [light][view] (distinct).
void simulate_table(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g,
                    const std::vector<vec3>& n, const std::vector<vec3>& lights, const std::vector<vec3>& views,
                    const Eigen::MatrixXf& Mn, std::vector<vec3>& out, const std::function<void(double)>& progress, double p0,
                    double p1) {
    const Eigen::Index T = Eigen::Index(n.size()), nl = Eigen::Index(lights.size()), nv = Eigen::Index(views.size());
    out.assign(size_t(nl * nv), vec3(0.f));
    const Eigen::Index batch = light_batch(g);
    for (Eigen::Index b0 = 0; b0 < nl; b0 += batch) {
        const Eigen::Index bn = std::min<Eigen::Index>(batch, nl - b0);
        Eigen::MatrixXf L[3] = {Eigen::MatrixXf(T, bn), Eigen::MatrixXf(T, bn), Eigen::MatrixXf(T, bn)};
        std::vector<LightImage> images =
            solve_lights(hf, dirs, vis, g, n, std::vector<vec3>(lights.begin() + b0, lights.begin() + b0 + bn));
        mesolab::parallel_for(Eigen::Index(0), bn, [&](Eigen::Index k) {
            const LightImage& li = images[size_t(k)];
            for (Eigen::Index p = 0; p < T; ++p)
                for (int c = 0; c < 3; ++c) L[c](p, k) = li.L[size_t(p)][c];
        });
        Eigen::MatrixXf R[3];
        for (int c = 0; c < 3; ++c) R[c].noalias() = L[c].transpose() * Mn;  // bn x nv
        for (Eigen::Index k = 0; k < bn; ++k)
            for (Eigen::Index v = 0; v < nv; ++v) out[size_t((b0 + k) * nv + v)] = vec3(R[0](k, v), R[1](k, v), R[2](k, v));
        if (g.phong) {
            mesolab::parallel_for(Eigen::Index(0), bn * nv, [&](Eigen::Index kv) {
                const Eigen::Index k = kv / nv, v = kv % nv;
                const vec3 wi = lights[size_t(b0 + k)], h = safe_normalize(wi + views[size_t(v)]);
                const std::vector<float>& cv = images[size_t(k)].cos_vis;
                // ks (s + 8)/(8 pi) is constant: sum the scalar max(0, n.h)^s max(0, n.wi) V m.
                double sum = 0;
                for (Eigen::Index p = 0; p < T; ++p) {
                    const float m = Mn(p, v), c = cv[size_t(p)];
                    if (m <= 0.f || c <= 0.f) continue;
                    sum += double(std::pow(std::max(0.f, glm::dot(n[size_t(p)], h)), g.shininess) * c * m);
                }
                out[size_t((b0 + k) * nv + v)] += g.ks * ((g.shininess + 8.f) / (8.f * kPi) * float(sum));
            });
        }
        if (progress) progress(p0 + (p1 - p0) * double(b0 + bn) / double(nl));
    }
}

// Normalised masking weights of the distinct view directions: column v = m(., wo_v) / sum.
Eigen::MatrixXf masking_matrix(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g,
                               const std::vector<vec3>& n, const std::vector<vec3>& views) {
    const Eigen::Index T = Eigen::Index(n.size());
    Eigen::MatrixXf Mn(T, Eigen::Index(views.size()));
    mesolab::parallel_for(size_t(0), views.size(), [&](size_t v) {
        const std::vector<float> m = masking(hf, dirs, vis, g, n, views[v]);
        double sum = 0;
        for (float x : m) sum += double(x);
        const float inv = sum > 0 ? float(1 / sum) : 0.f;
        for (Eigen::Index p = 0; p < T; ++p) Mn(p, Eigen::Index(v)) = m[size_t(p)] * inv;
    });
    return Mn;
}
}  // namespace

// [SECTION] Real spherical harmonics
void real_sh(int bands, vec3 w, double* out) {
    const double len = std::sqrt(double(w.x) * w.x + double(w.y) * w.y + double(w.z) * w.z);
    const double z = len > 0 ? std::clamp(double(w.z) / len, -1.0, 1.0) : 1.0;
    const double phi = (w.x == 0.f && w.y == 0.f) ? 0.0 : std::atan2(double(w.y), double(w.x));
    for (int l = 0; l < bands; ++l) {
        out[l * (l + 1)] = sh_norm(l, 0) * legendre(l, 0, z);
        for (int m = 1; m <= l; ++m) {
            const double k = std::sqrt(2.0) * sh_norm(l, m) * legendre(l, m, z);
            out[l * (l + 1) + m] = k * std::cos(m * phi);
            out[l * (l + 1) - m] = k * std::sin(m * phi);
        }
    }
}

// [SECTION] Look-ups
vec3 SimulatedBrdf::node_direction(int i_theta, int i_phi) const { return node_dir(i_theta, i_phi, n_theta, n_phi, kPiD / 2); }

vec3 SimulatedBrdf::eval(vec3 wi, vec3 wo) const {
    wi = safe_normalize(wi);
    wo = safe_normalize(wo);
    if (wi.z <= 0.f || wo.z <= 0.f || n_theta < 2 || n_phi < 1 || table.size() != size_t(nodes()) * size_t(nodes())) return vec3(0.f);
    const Taps a = taps_of(wi, n_theta, n_phi), b = taps_of(wo, n_theta, n_phi);
    vec3 r(0.f);
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r += a.w[i] * b.w[j] * table[size_t(a.node[i]) * size_t(nodes()) + size_t(b.node[j])];
    return r;
}

float SimulatedBrdf::eval_shadow(vec3 wi, vec3 wo) const {
    wi = safe_normalize(wi);
    wo = safe_normalize(wo);
    if (wi.z <= 0.f || wo.z <= 0.f || n_theta < 2 || n_phi < 1 || shadow.size() != size_t(nodes()) * size_t(nodes())) return 0.f;
    const Taps a = taps_of(wi, n_theta, n_phi), b = taps_of(wo, n_theta, n_phi);
    float r = 0.f;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r += a.w[i] * b.w[j] * shadow[size_t(a.node[i]) * size_t(nodes()) + size_t(b.node[j])];
    return r;
}

vec3 SimulatedBrdf::eval_env(vec3 wo) const {
    wo = safe_normalize(wo);
    if (wo.z <= 0.f || n_theta < 2 || n_phi < 1 || env.size() != size_t(nodes())) return vec3(0.f);
    const Taps b = taps_of(wo, n_theta, n_phi);
    vec3 r(0.f);
    for (int j = 0; j < 4; ++j) r += b.w[j] * env[size_t(b.node[j])];
    return r;
}

vec3 SimulatedBrdf::eval_sh(vec3 wi, vec3 wo) const {
    wi = safe_normalize(wi);
    wo = safe_normalize(wo);
    const int B = sh_bands * sh_bands;
    if (wi.z <= 0.f || wo.z <= 0.f || sh_bands < 1 || sh.size() != size_t(B) * size_t(B)) return vec3(0.f);
    std::vector<double> yi(static_cast<size_t>(B)), yo(static_cast<size_t>(B));
    real_sh(sh_bands, wi, yi.data());
    real_sh(sh_bands, wo, yo.data());
    double r[3] = {0, 0, 0};
    for (int a = 0; a < B; ++a)
        for (int b = 0; b < B; ++b) {
            const double y = yi[size_t(a)] * yo[size_t(b)];
            const vec3 c = sh[size_t(a) * size_t(B) + size_t(b)];
            for (int k = 0; k < 3; ++k) r[k] += double(c[k]) * y;
        }
    return vec3(float(std::max(0.0, r[0])), float(std::max(0.0, r[1])), float(std::max(0.0, r[2])));
}

size_t SimulatedBrdf::bytes() const { return (table.size() + env.size() + sh.size()) * sizeof(vec3) + shadow.size() * sizeof(float); }

// [SECTION] Goniometer images
Image goniometer_image(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g, vec3 wi, vec3 wo) {
    check_inputs(hf, dirs, vis);
    Image img(hf.width, hf.height, 3, 0.f);
    wi = safe_normalize(wi);
    wo = safe_normalize(wo);
    if (wi.z <= 0.f || wo.z <= 0.f) return img;
    const std::vector<vec3> n = normals_of(hf);
    const LightImage li = std::move(solve_lights(hf, dirs, vis, g, n, {wi})[0]);
    const std::vector<float> V = view_visibility(hf, dirs, vis, g, wo);
    const vec3 h = safe_normalize(wi + wo);
    for (int y = 0; y < hf.height; ++y)
        for (int x = 0; x < hf.width; ++x) {
            const size_t p = hf.index(x, y);
            vec3 L = li.L[p];
            if (g.phong) L += phong_lobe(g, n[p], h, li.cos_vis[p]);
            L *= V[p];
            float* px = img.at(x, y);
            px[0] = L.x;
            px[1] = L.y;
            px[2] = L.z;
        }
    return img;
}

vec3 goniometer_average(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g, vec3 wi, vec3 wo) {
    check_inputs(hf, dirs, vis);
    wi = safe_normalize(wi);
    wo = safe_normalize(wo);
    if (wi.z <= 0.f || wo.z <= 0.f) return vec3(0.f);
    const std::vector<vec3> n = normals_of(hf);
    const LightImage li = std::move(solve_lights(hf, dirs, vis, g, n, {wi})[0]);
    return masked_average(g, n, li, masking(hf, dirs, vis, g, n, wo), wi, wo);
}

// [SECTION] The goniometer
SimulatedBrdf simulate_brdf(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, const GonioSettings& g,
                            const std::function<void(double)>& progress) {
    check_settings(g);
    check_inputs(hf, dirs, vis);
    SimulatedBrdf out;
    const int nt = g.resolution, np = g.resolution, nodes = nt * np, distinct = 1 + (nt - 1) * np;
    out.n_theta = nt;
    out.n_phi = np;
    const std::vector<vec3> n = normals_of(hf);

    // Distinct light (exact) and view (horizon clamped) directions.
    std::vector<vec3> lights(static_cast<size_t>(distinct)), views(static_cast<size_t>(distinct));
    for (int node = 0; node < nodes; ++node) {
        const int d = distinct_of(node, np);
        lights[size_t(d)] = node_dir(node / np, node % np, nt, np, kPiD / 2);
        views[size_t(d)] = node_dir(node / np, node % np, nt, np, kPiD / 2 - kGonioHorizonEps);
    }
    const Eigen::MatrixXf Mn = masking_matrix(hf, dirs, vis, g, n, views);

    // Shadow fraction seen from the view: the masked average of V(x, wi) [n.wi > 0] (no scattering
    // solve: the shadow test's data with the light direction).
    {
        Eigen::MatrixXf S(Eigen::Index(n.size()), Eigen::Index(distinct));
        mesolab::parallel_for(0, distinct, [&](int d) {
            const std::vector<float> V = view_visibility(hf, dirs, vis, g, lights[size_t(d)]);
            for (size_t p = 0; p < V.size(); ++p) S(Eigen::Index(p), d) = lights[size_t(d)].z > 0.f ? V[p] : 0.f;
        });
        const Eigen::MatrixXf R = S.transpose() * Mn;  // distinct lights x distinct views
        out.shadow.resize(size_t(nodes) * size_t(nodes));
        for (int a = 0; a < nodes; ++a)
            for (int b = 0; b < nodes; ++b) out.shadow[size_t(a) * size_t(nodes) + size_t(b)] = std::clamp(R(distinct_of(a, np), distinct_of(b, np)), 0.f, 1.f);
    }

    // Environment: one solve, averaged with the view nodes' masking.
    {
        const std::vector<vec3> Le = solve_env(hf, dirs, vis, g);
        Eigen::MatrixXf E(Eigen::Index(Le.size()), 3);
        for (size_t p = 0; p < Le.size(); ++p)
            for (int c = 0; c < 3; ++c) E(Eigen::Index(p), c) = Le[p][c];
        const Eigen::MatrixXf R = Mn.transpose() * E;  // distinct x 3
        out.env.resize(size_t(nodes));
        for (int node = 0; node < nodes; ++node) {
            const Eigen::Index d = distinct_of(node, np);
            out.env[size_t(node)] = vec3(R(d, 0), R(d, 1), R(d, 2));
        }
        out.images = 1;
    }
    if (progress) progress(0.02);

    if (g.fit == GonioSettings::Fit::Table) {
        std::vector<vec3> Td;
        simulate_table(hf, dirs, vis, g, n, lights, views, Mn, Td, progress, 0.02, 1.0);
        out.images += distinct;
        out.table.resize(size_t(nodes) * size_t(nodes));
        for (int a = 0; a < nodes; ++a)
            for (int b = 0; b < nodes; ++b)
                out.table[size_t(a) * size_t(nodes) + size_t(b)] = Td[size_t(distinct_of(a, np)) * size_t(distinct) + size_t(distinct_of(b, np))];
        return out;
    }

    // SH: random pairs, one goniometer image each (in blocks: parallel within, progress between).
    const int S = g.samples, bands = g.sh_bands, B = bands * bands;
    std::vector<vec3> wis(static_cast<size_t>(S)), wos(static_cast<size_t>(S)), y(static_cast<size_t>(S));
    std::mt19937 rng(g.seed);
    for (int s = 0; s < S; ++s) {
        wis[size_t(s)] = hemisphere_sample(rng);
        wos[size_t(s)] = hemisphere_sample(rng);
    }
    const int batch = light_batch(g);
    for (int s0 = 0; s0 < S; s0 += batch) {
        const int sn = std::min(batch, S - s0);
        const std::vector<LightImage> images = solve_lights(hf, dirs, vis, g, n, std::vector<vec3>(wis.begin() + s0, wis.begin() + s0 + sn));
        mesolab::parallel_for(s0, s0 + sn, [&](int s) {
            y[size_t(s)] = masked_average(g, n, images[size_t(s - s0)], masking(hf, dirs, vis, g, n, wos[size_t(s)]), wis[size_t(s)], wos[size_t(s)]);
        });
        if (progress) progress(0.02 + 0.93 * double(s0 + sn) / double(S));
    }
    out.images += S;

    // Tikhonov least squares for c (B^2 x 3): primal or dual form, whichever is smaller.
    const Eigen::MatrixXd Yi = sh_rows(bands, wis), Yo = sh_rows(bands, wos);
    Eigen::MatrixXd A(S, B * B), Y(S, 3);
    for (int s = 0; s < S; ++s) {
        for (int a = 0; a < B; ++a)
            for (int b = 0; b < B; ++b) A(s, a * B + b) = Yi(s, a) * Yo(s, b);
        for (int c = 0; c < 3; ++c) Y(s, c) = double(y[size_t(s)][c]);
    }
    const double lambda = std::max(kGonioShLambda * A.squaredNorm() / double(B * B), 1e-300);
    Eigen::VectorXd w(B * B);  // smoothness penalty per coefficient: (1 + l_a (l_a + 1) + l_b (l_b + 1))^2
    for (int a = 0; a < B; ++a)
        for (int b = 0; b < B; ++b) {
            const int la = int(std::sqrt(double(a)) + 1e-9), lb = int(std::sqrt(double(b)) + 1e-9);
            const double e = 1.0 + la * (la + 1.0) + lb * (lb + 1.0);
            w(a * B + b) = e * e;
        }
    Eigen::MatrixXd C;
    if (S >= B * B) {
        Eigen::MatrixXd M = A.transpose() * A;
        M.diagonal() += lambda * w;
        C = M.ldlt().solve(A.transpose() * Y);
    } else {
        const Eigen::VectorXd winv = w.cwiseInverse();
        Eigen::MatrixXd K = A * winv.asDiagonal() * A.transpose();
        K.diagonal().array() += lambda;
        C = winv.asDiagonal() * (A.transpose() * K.ldlt().solve(Y));
    }
    if (!C.allFinite()) C.setZero(B * B, 3);  // never a NaN fit
    out.sh_bands = bands;
    out.sh.resize(size_t(B) * size_t(B));
    for (int k = 0; k < B * B; ++k) out.sh[size_t(k)] = vec3(float(C(k, 0)), float(C(k, 1)), float(C(k, 2)));

    // Residual of the clamped fit on the samples.
    {
        const Eigen::MatrixXd F = (A * C).cwiseMax(0.0);
        const double num = (F - Y).squaredNorm(), den = Y.squaredNorm();
        out.fit_residual = den > 0 ? std::sqrt(num / den) : (num > 0 ? 1.0 : 0.0);
    }

    // Tabulate at the exact node directions: T_c = Ynodes C_c Ynodes^T, clamped >= 0.
    std::vector<vec3> node_dirs(static_cast<size_t>(nodes));
    for (int node = 0; node < nodes; ++node) node_dirs[size_t(node)] = node_dir(node / np, node % np, nt, np, kPiD / 2);
    const Eigen::MatrixXd Yn = sh_rows(bands, node_dirs);
    out.table.assign(size_t(nodes) * size_t(nodes), vec3(0.f));
    for (int c = 0; c < 3; ++c) {
        Eigen::MatrixXd Cc(B, B);
        for (int a = 0; a < B; ++a)
            for (int b = 0; b < B; ++b) Cc(a, b) = C(a * B + b, c);
        const Eigen::MatrixXd Tc = Yn * Cc * Yn.transpose();
        for (int a = 0; a < nodes; ++a)
            for (int b = 0; b < nodes; ++b) out.table[size_t(a) * size_t(nodes) + size_t(b)][c] = float(std::max(0.0, Tc(a, b)));
    }
    if (progress) progress(1.0);
    return out;
}
}  // namespace mesolab::microgeom
