#include "core/truth/truth.h"
#include "core/read_contract.h"
#include "core/parallel.h"
#include "core/error.h"
#include "core/hash.h"
#include "core/raster.h"
#include "core/raytrace.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/scene_stages.h"
#include "core/file.h"
#include "core/strings.h"
#include "core/technique.h"

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>

namespace mesolab {
using glm::dvec3;

// [SECTION] Random numbers
TruthRng::TruthRng(uint64_t seed, uint64_t pixel, uint64_t sample)
    : state_(splitmix64_mix(splitmix64_mix(splitmix64(seed) ^ pixel) + sample * kSplitmix64Gamma)) {}

float TruthRng::next() {
    state_ += kSplitmix64Gamma;
    return float(splitmix64_mix(state_) >> 40) * 0x1p-24f;  // 24 bits: exactly representable, < 1
}

// [SECTION] Materials
vec3 TruthMaterial::sample(const TruthHit& h, vec3 wo, TruthRng& rng, vec3& wi) const {
    // Cosine-weighted: pdf = cos θ / π, so the weight is f π.
    const float u1 = rng.next(), u2 = rng.next();
    const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
    const vec3 local(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.f, 1.f - u1)));
    const vec3 t = std::fabs(h.n.x) > 0.9f ? glm::normalize(glm::cross(vec3(0.f, 1.f, 0.f), h.n)) : glm::normalize(glm::cross(vec3(1.f, 0.f, 0.f), h.n));
    const vec3 b = glm::cross(h.n, t);
    wi = local.x * t + local.y * b + local.z * h.n;
    if (local.z <= 0.f) return vec3(0.f);
    return f(h, wo, wi) * kPi;
}

// [SECTION] Setting up
const std::vector<std::string>& truth_aovs() {
    static const std::vector<std::string> names = {"radiance", "normal", "truth_stderr", "exitance", "irradiance"};
    return names;
}

namespace {
// The truth of object `object`'s technique (InputError when it has none).
TruthDecl truth_of(const Scene& s, size_t object) {
    const std::string& name = s.objects[object].technique;
    const Technique* t = Registry::instance().technique(name);
    if (!t) throw InputError("objects[" + std::to_string(object) + "].technique: unknown technique '" + name + "'");
    std::optional<TruthDecl> d = t->truth();
    if (!d) throw InputError("--backend truth: technique " + name + " (object '" + s.objects[object].name + "') has no truth renderer yet");
    if (!d->object) throw std::logic_error("technique " + name + ": its TruthDecl has no `object`");
    return std::move(*d);
}
}  // namespace

std::vector<StageName> truth_stages(const Scene& s) {
    std::vector<StageName> out = {stages::geometry, stages::env_map};
    std::set<std::string> seen;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const TruthDecl t = truth_of(s, i);
        if (!seen.insert(s.objects[i].technique).second) continue;
        for (const StageName& n : t.stages) out.push_back(n);
    }
    return out;
}

const std::vector<std::string>& truth_scene_params() {
    static const std::vector<std::string> keys = {"camera.*", "light.*", "env.*", "effects.environment", "geometry.*"};
    return keys;
}

std::vector<std::pair<std::string, int>> truth_reads(const Scene& s) {
    const StageGraph& g = Registry::instance().stages();
    // (key pattern, object) pairs, in a fixed order; object -1 for scene-wide keys.
    std::set<std::pair<std::string, int>> keys;
    for (const std::string& p : truth_scene_params())
        if (p != "geometry.*") keys.insert({p, -1});
    std::set<std::pair<std::string, int>> seen;
    std::function<void(const StageDecl&, int)> visit = [&](const StageDecl& d, int object) {
        if (!seen.insert({d.name, object}).second) return;
        for (const std::string& p : d.params) keys.insert({p, object});
        g.for_each_input(s, d, object, visit);
    };
    for (const StageName& n : truth_stages(s)) {
        const StageDecl& d = g.at(n.str());
        for (int object : g.subjects(s, d)) visit(d, object);
    }
    for (size_t i = 0; i < s.objects.size(); ++i) {
        keys.insert({"geometry.*", int(i)});
        for (const std::string& p : truth_of(s, i).params) keys.insert({p, int(i)});
    }
    return {keys.begin(), keys.end()};
}

std::string truth_description(const Scene& s) {
    std::string out;
    for (size_t i = 0; i < s.objects.size(); ++i) out += "object " + std::to_string(i) + " " + s.objects[i].technique + ";";
    for (const auto& [pattern, object] : truth_reads(s)) out += param_fingerprint(s, pattern, object, FileIdentity::Contents);
    return out;
}

namespace {
// The read contract of the truth: it reads only what truth_reads lists.
std::optional<DeclaredReads> truth_contract(const Scene& s) {
    if (!check_reads_by_default()) return std::nullopt;
    std::vector<std::string> patterns;
    for (auto& [p, object] : truth_reads(s)) patterns.push_back(p);
    return DeclaredReads("the truth", s, std::move(patterns), -1,
                         "neither the scene's truth keys nor the object's technique's truth declare: a truth kept on disk would not follow that key "
                         "(declare it in the technique's TruthDecl::params)");
}
}  // namespace

// [SECTION] The path tracer
namespace {
struct TruthScene {
    RayScene rt;
    std::vector<TruthObject> objects;  // by geometry index
    std::vector<glm::mat3> normal_to_world;
    float eps = 1e-4f;                 // ray offset: 1e-5 of the scene's extent

    TruthHit hit_point(const RayHit& h, vec3 o, vec3 d) const {
        const TruthObject& ob = objects[size_t(h.geometry)];
        const TriMesh& m = *ob.mesh;
        const size_t f = size_t(h.triangle);
        const uint32_t i0 = m.index[3 * f], i1 = m.index[3 * f + 1], i2 = m.index[3 * f + 2];
        const float w0 = 1.f - h.u - h.v;
        TruthHit th;
        th.geometry = h.geometry;
        th.triangle = h.triangle;
        th.p = o + h.t * d;
        th.ng = glm::normalize(h.ng);
        vec3 n = th.ng;
        if (!m.normal.empty()) {
            const vec3 ns = normal_to_world[size_t(h.geometry)] * (w0 * m.normal[i0] + h.u * m.normal[i1] + h.v * m.normal[i2]);
            if (glm::dot(ns, ns) > 0.f) n = glm::normalize(ns);
        }
        if (!m.uv.empty()) th.uv = w0 * m.uv[i0] + h.u * m.uv[i1] + h.v * m.uv[i2];
        if (!m.tangent.empty()) th.tangent = glm::mat3(ob.to_world) * (w0 * m.tangent[i0] + h.u * m.tangent[i1] + h.v * m.tangent[i2]);
        th.bary = vec2(h.u, h.v);
        // Two-sided: both normals face the side the ray came from.
        if (glm::dot(th.ng, d) > 0.f) th.ng = -th.ng;
        if (glm::dot(n, th.ng) < 0.f) n = -n;
        th.n = n;
        return th;
    }

    // The uv step of the hit's triangle for rays d_x, d_y from o (the neighbouring pixels' rays),
    // met on the hit's tangent plane (zero where the mesh has no uv or a ray misses the plane).
    void footprint(TruthHit& th, const RayHit& h, vec3 o, vec3 d_x, vec3 d_y) const {
        const TruthObject& ob = objects[size_t(h.geometry)];
        const TriMesh& m = *ob.mesh;
        if (m.uv.empty()) return;
        const size_t f = size_t(h.triangle);
        const uint32_t i0 = m.index[3 * f], i1 = m.index[3 * f + 1], i2 = m.index[3 * f + 2];
        const vec3 p0 = vec3(ob.to_world * vec4(m.position[i0], 1.f));
        const vec3 e1 = vec3(ob.to_world * vec4(m.position[i1], 1.f)) - p0, e2 = vec3(ob.to_world * vec4(m.position[i2], 1.f)) - p0;
        const vec2 t1 = m.uv[i1] - m.uv[i0], t2 = m.uv[i2] - m.uv[i0];
        // dp = a e1 + b e2 in the triangle's plane: the 2x2 normal equations.
        const float g11 = glm::dot(e1, e1), g12 = glm::dot(e1, e2), g22 = glm::dot(e2, e2), det = g11 * g22 - g12 * g12;
        if (!(std::fabs(det) > 0.f)) return;
        auto step = [&](vec3 dir) -> vec2 {
            const float den = glm::dot(dir, th.ng);
            if (std::fabs(den) < 1e-8f) return vec2(0.f);
            const float t = glm::dot(th.p - o, th.ng) / den;
            if (!(t > 0.f)) return vec2(0.f);
            const vec3 dp = o + t * dir - th.p;
            const float r1 = glm::dot(dp, e1), r2 = glm::dot(dp, e2);
            const float a = (g22 * r1 - g12 * r2) / det, b = (g11 * r2 - g12 * r1) / det;
            return a * t1 + b * t2;
        };
        th.duv_dx = step(d_x), th.duv_dy = step(d_y);
    }
};

struct PixelSample {
    vec3 L{0.f};
    vec3 normal{0.f};
    vec3 exitance{0.f};
    vec3 irradiance{0.f};
};

// The first ray of a pixel's paths: through the pixel's centre from the eye (orbit), or, for a
// texel (texture mode), down the drawn surface's normal onto the truth's surface, seen from the
// camera's direction whatever lies between (masking as the real-time texture mode treats it).
// In texture mode each sample starts at a uniform point of the texel's footprint (dpdx, dpdy: the
// drawn surface's step across one pixel), so that a texel is the mean over its patch of the
// micro-surface: at its centre alone, a vertex of facets, the surface has no one normal.
struct Primary {
    vec3 o{0.f}, d{0.f};
    bool texture = false;
    vec3 view{0.f};  // texture: the direction towards the viewer
    vec3 dpdx{0.f}, dpdy{0.f};
    vec3 d_x{0.f}, d_y{0.f};  // orbit: the rays through the next pixel's centre in x and in y
    // Orbit: the hit of the ray through the pixel's centre, the same for every sample, traced once
    // per pixel (a pixel that sees no object then costs no ray per sample).
    bool centre_traced = false;
    RayHit centre;
};

// The power per unit area entering a medium at a camera's hit (the AOV irradiance): each light's
// irradiance on the facet, shadowed, through the material's transmittance, and the sky's by one
// cosine-weighted direction about the facet's normal per sample (its estimate's mean is exact).
vec3 entering_irradiance(const TruthScene& sc, const Lighting& lighting, const TruthHit& th, TruthRng& rng) {
    const TruthMaterial& mat = *sc.objects[size_t(th.geometry)].material;
    const vec3 p = th.p + sc.eps * th.ng;
    vec3 E(0.f);
    for (const Light& l : lighting.lights) {
        vec3 wi, El;
        l.sample(th.p, wi, El);
        const float cos_i = glm::dot(th.ng, wi);
        if (cos_i <= 0.f) continue;
        const float dist = l.point ? glm::length(l.position - p) : 3.4e38f;
        if (sc.rt.occluded(p, wi, 0.f, dist)) continue;
        E += El * cos_i * mat.transmittance(th, wi);
    }
    if (lighting.env_lighting) {
        const float u1 = rng.next(), u2 = rng.next();
        const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
        const vec3 n = th.ng;
        const vec3 t = std::fabs(n.x) > 0.9f ? glm::normalize(glm::cross(vec3(0.f, 1.f, 0.f), n)) : glm::normalize(glm::cross(vec3(1.f, 0.f, 0.f), n));
        const vec3 b = glm::cross(n, t);
        const vec3 wi = glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.f, 1.f - u1)) * n);
        if (!sc.rt.occluded(p, wi)) E += kPi * lighting.env.radiance(wi) * mat.transmittance(th, wi);  // cos θ / pdf = π
    }
    return E;
}

PixelSample trace(const TruthScene& sc, const Lighting& lighting, const Primary& primary, const TruthSettings& st, uint64_t pixel, uint64_t sample) {
    TruthRng rng(st.seed, pixel, sample);
    vec3 d = primary.d;
    vec3 o = primary.o;
    if (primary.texture) {
        const float jx = rng.next() - 0.5f, jy = rng.next() - 0.5f;
        o += jx * primary.dpdx + jy * primary.dpdy;
    }
    PixelSample out;
    vec3 beta(1.f);
    bool spread = false;  // the camera ray spread over the pixel (TruthMaterial::pixel_filter)
    for (int depth = 0; depth < st.max_depth; ++depth) {
        const RayHit h = depth == 0 && !spread && primary.centre_traced ? primary.centre : sc.rt.intersect(o, d, depth == 0 ? 0.f : sc.eps);
        if (depth == 0 && !spread && !primary.texture && h.hit() && sc.objects[size_t(h.geometry)].material->pixel_filter()) {
            spread = true;
            const float jx = rng.next() - 0.5f, jy = rng.next() - 0.5f;
            d = glm::normalize(primary.d + jx * (primary.d_x - primary.d) + jy * (primary.d_y - primary.d));
            --depth;  // the camera's ray again, through this sample's point of the pixel
            continue;
        }
        if (!h.hit()) {
            if ((depth == 0 && !primary.texture) || (depth > 0 && lighting.env_lighting)) out.L += beta * lighting.env.radiance(d);
            break;
        }
        TruthHit th = sc.hit_point(h, o, d);
        const TruthMaterial& mat = *sc.objects[size_t(h.geometry)].material;
        if (depth == 0) {
            out.normal = th.n;
            if (!primary.texture && mat.footprint()) {
                sc.footprint(th, h, o, primary.d_x, primary.d_y);
                th.jitter.x = rng.next(), th.jitter.y = rng.next();
            }
        }
        th.depth = depth;
        const vec3 wo = depth == 0 && primary.texture ? primary.view : -d;
        if (depth == 0 && mat.medium()) out.irradiance = entering_irradiance(sc, lighting, th, rng);
        if (mat.emitter()) {
            out.L += beta * mat.emitted(th, wo, sample);
            if (depth == 0) out.exitance = mat.exitance(th, sample);
            break;
        }
        const vec3 p = th.p + sc.eps * th.ng;
        for (const Light& l : lighting.lights) {
            vec3 wi, E;
            l.sample(th.p, wi, E);
            const float cos_i = glm::dot(th.n, wi);
            if (cos_i <= 0.f || glm::dot(th.ng, wi) <= 0.f) continue;
            const float dist = l.point ? glm::length(l.position - p) : 3.4e38f;
            if (sc.rt.occluded(p, wi, 0.f, dist)) continue;
            out.L += beta * mat.fcos_light(th, wo, wi, rng) * E;
        }
        vec3 wi;
        const vec3 w = mat.sample(th, wo, rng, wi);
        if (!(glm::dot(w, w) > 0.f)) break;
        // A direction above the shading normal's plane but below the triangle's is mirrored to
        // above the triangle: the light the material sends there is kept (no furnace loses it).
        if (const float below = glm::dot(th.ng, wi); below <= 0.f) wi = glm::normalize(wi - 2.f * below * th.ng);
        beta *= w;
        if (depth >= 3) {  // Russian roulette
            const float q = std::max(0.05f, 1.f - std::max(beta.x, std::max(beta.y, beta.z)));
            if (rng.next() < q) break;
            beta /= 1.f - q;
        }
        o = p;
        d = wi;
    }
    return out;
}
}  // namespace

// [SECTION] Exact sums and the build
namespace {
constexpr double kFixedScale = 0x1p64, kFixedMax = 0x1p62;
}

TruthFixed to_fixed(double x) {
    if (!(x == x)) return 0;  // NaN
    x = std::clamp(x, -kFixedMax, kFixedMax);
    return TruthFixed(std::nearbyint(x * kFixedScale));
}

double from_fixed(TruthFixed f) { return double(f) / kFixedScale; }

std::string truth_build(const std::string& version) {
    std::string isa = "x86-64";
#if defined(__x86_64__) || defined(__i386__)
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq"))
        isa += " avx512";
    else if (__builtin_cpu_supports("avx2")) isa += " avx2";
    else if (__builtin_cpu_supports("avx")) isa += " avx";
    else if (__builtin_cpu_supports("sse4.2")) isa += " sse4.2";
    else isa += " sse2";
    if (__builtin_cpu_supports("fma")) isa += " fma";
#else
    isa = "non-x86";
#endif
#if defined(__clang__)
    const std::string compiler = "Clang " __clang_version__;
#elif defined(__GNUC__)
    const std::string compiler = "GCC " __VERSION__;
#else
    const std::string compiler = "unknown compiler";
#endif
    return version + "; " + compiler + "; " + isa;
}

const char* to_string(TruthEnd e) {
    switch (e) {
        case TruthEnd::Samples: return "samples";
        case TruthEnd::Noise: return "noise";
        case TruthEnd::TimeLimit: return "time limit";
        case TruthEnd::Cancelled: return "cancelled";
    }
    return "?";
}

// [SECTION] Sampling
void check_truth_settings(const TruthSettings& st, const TruthOptionNames& names) {
    if (st.spp < 1) throw InputError(std::string(names.spp) + std::to_string(st.spp) + ": expected at least 1 sample per pixel");
    if (st.first < 0 || st.first >= st.spp)
        throw InputError(std::string(names.samples) + std::to_string(st.first) + ":" + std::to_string(st.spp) + ": expected a range A:B of samples with 0 <= A < B");
    if (st.noise != 0.0 && !(st.noise > 0.0 && st.noise < 1.0))
        throw InputError(std::string(names.noise) + strprintf("%g", st.noise) + ": expected a relative noise between 0 and 1 (e.g. 0.01 for 1%)");
    if (!(st.time_limit_s >= 0.0) || !std::isfinite(st.time_limit_s))
        throw InputError(std::string(names.time_limit) + strprintf("%g", st.time_limit_s) + ": expected seconds above 0 (0: no limit)");
}

void check_truth_request(const Scene& s, int width, int height, const TruthSettings& st, const std::vector<std::string>& aovs) {
    check_truth_settings(st);
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError("frame size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range (1..16384 per side)");
    for (const std::string& a : aovs)
        if (std::find(truth_aovs().begin(), truth_aovs().end(), a) == truth_aovs().end())
            throw InputError("--aov " + a + ": the truth does not write it (it writes radiance, normal, truth_stderr, exitance, irradiance)");
    for (size_t i = 0; i < s.objects.size(); ++i) truth_of(s, i);
}

namespace {
std::string duration_text(double s) {
    if (s < 90.0) return strprintf("%.0f s", std::max(1.0, s));
    if (s < 5400.0) return strprintf("%.0f min", s / 60.0);
    return strprintf("%.1f h", s / 3600.0);
}

// One pass over the pixels for the samples [k0, k1): each pixel's samples summed exactly and added
// to the accumulator. Rows stop early when `cancel` is set (the block is then incomplete).
void sample_block(const TruthScene& sc, const Lighting& lighting, const FrameCamera& cam, const GBuffer& gb, const std::vector<float>& lift,
                  const TruthSettings& st, int k0, int k1, TruthAccumulator& a, const std::atomic<bool>* cancel) {
    const int width = a.width, height = a.height;
    const bool media = !a.exitance.empty();
    mesolab::parallel_for(0, height, [&](int y) {
        if (cancel && cancel->load()) return;
        for (int x = 0; x < width; ++x) {
            const uint64_t pixel = uint64_t(y) * uint64_t(width) + uint64_t(x);
            const size_t o = 3 * size_t(pixel);
            Primary primary;
            if (cam.texture_mode) {
                const size_t g = gb.index(x, y);
                if (gb.object[g] < 0) continue;  // no surface at this texel: left 0, as the real-time paths leave it
                const vec3 n = gb.normal[g];
                primary.texture = true;
                primary.view = cam.view_dir;
                primary.o = gb.position[g] + lift[size_t(gb.object[g])] * n;
                primary.d = -n;
                // The footprint: central differences of the drawn positions (one-sided at the object's edge).
                auto step = [&](int dx, int dy) {
                    auto at = [&](int xx, int yy) -> const vec3* {
                        if (xx < 0 || yy < 0 || xx >= width || yy >= height || gb.object[gb.index(xx, yy)] != gb.object[g]) return nullptr;
                        return &gb.position[gb.index(xx, yy)];
                    };
                    const vec3 *p = at(x - dx, y - dy), *q = at(x + dx, y + dy);
                    if (p && q) return 0.5f * (*q - *p);
                    if (q) return *q - gb.position[g];
                    if (p) return gb.position[g] - *p;
                    return vec3(0.f);
                };
                primary.dpdx = step(1, 0), primary.dpdy = step(0, 1);
            } else {
                primary.o = cam.eye;
                primary.d = cam.ray_dir(x, y);
                primary.d_x = cam.ray_dir_at(float(x) + 1.5f, float(y) + 0.5f);
                primary.d_y = cam.ray_dir_at(float(x) + 0.5f, float(y) + 1.5f);
                primary.centre = sc.rt.intersect(primary.o, primary.d, 0.f), primary.centre_traced = true;
            }
            TruthFixed sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0}, exit[3] = {0, 0, 0}, irr[3] = {0, 0, 0};
            for (int k = k0; k < k1; ++k) {
                const PixelSample ps = trace(sc, lighting, primary, st, pixel, uint64_t(k));
                for (int c = 0; c < 3; ++c) {
                    const double L = ps.L[c];
                    sum[c] += to_fixed(L), sum2[c] += to_fixed(L * L);
                    if (media) exit[c] += to_fixed(ps.exitance[c]), irr[c] += to_fixed(ps.irradiance[c]);
                    if (k == a.first) a.normal[o + size_t(c)] = ps.normal[c];
                }
            }
            for (int c = 0; c < 3; ++c) {
                a.sum[o + size_t(c)] += sum[c], a.sum2[o + size_t(c)] += sum2[c];
                if (media) a.exitance[o + size_t(c)] += exit[c], a.irradiance[o + size_t(c)] += irr[c];
            }
        }
    });
}
}  // namespace

TruthAccumulator accumulate_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& st, const TruthAccumulator* from,
                                  const std::function<void(const std::string&, double)>& progress, const std::atomic<bool>* cancel) {
    using clock = std::chrono::steady_clock;
    check_truth_request(s, width, height, st, {});
    std::optional<DeclaredReads> contract = truth_contract(s);
    ParamReadScope reads(contract ? &*contract : nullptr);
    TruthScene sc;
    Bounds all{vec3(1e30f), vec3(-1e30f)};
    bool media = false;
    int block = kTruthBlock;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        TruthObject ob = truth_of(s, i).object(s, ev, int(i));
        if (!ob.mesh || !ob.material)
            throw std::logic_error("truth: technique " + s.objects[i].technique + " gave no mesh or material for object " + std::to_string(i));
        media = media || ob.material->medium();
        block = std::clamp(ob.samples_per_block, 1, block);
        sc.rt.add(*ob.mesh, ob.to_world);
        sc.normal_to_world.push_back(glm::transpose(glm::inverse(glm::mat3(ob.to_world))));
        const Bounds b = bounds(*ob.mesh);
        for (int c = 0; c < 8; ++c) {
            const vec3 corner((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z);
            const vec3 w = vec3(ob.to_world * vec4(corner, 1.f));
            all.lo = glm::min(all.lo, w), all.hi = glm::max(all.hi, w);
        }
        sc.objects.push_back(std::move(ob));
    }
    sc.rt.commit();
    if (!s.objects.empty()) sc.eps = std::max(1e-6f, 1e-5f * glm::length(all.hi - all.lo));

    const FrameCamera cam = make_camera(s, world_bounds(s, ev), width, height);
    const Lighting lighting = make_lighting(s, ev);
    // Texture mode: the texels' surface points, as the real-time paths rasterise them in (u, v).
    GBuffer gb;
    std::vector<float> lift;  // world units above the drawn surface, per object
    if (cam.texture_mode) {
        std::vector<DrawItem> items;
        std::vector<std::shared_ptr<const TriMesh>> keep;
        for (size_t i = 0; i < s.objects.size(); ++i) {
            keep.push_back(drawn_mesh(s, ev, int(i)));
            const mat4 m = object_to_world(s.objects[i]);
            items.push_back({keep.back().get(), m, int(i), false});
            const float scale = std::max({glm::length(vec3(m[0])), glm::length(vec3(m[1])), glm::length(vec3(m[2]))});
            const TruthDecl t = truth_of(s, i);
            lift.push_back((t.lift ? t.lift(s, ev, int(i)) : 0.f) * scale + 2.f * sc.eps);
        }
        rasterize(items, cam.raster, gb);
    }
    // Where the camera sees each object that traces light before the pixels (its importance).
    std::vector<std::vector<vec3>> seen(sc.objects.size());
    bool tracers = false;
    for (const TruthObject& ob : sc.objects) tracers = tracers || bool(ob.prepare);
    if (tracers) {
        std::vector<std::vector<std::vector<vec3>>> rows(size_t(height), std::vector<std::vector<vec3>>(sc.objects.size()));
        mesolab::parallel_for(0, height, [&](int y) {
            for (int x = 0; x < width; ++x) {
                if (cam.texture_mode) {
                    const size_t g = gb.index(x, y);
                    if (gb.object[g] >= 0 && sc.objects[size_t(gb.object[g])].prepare) rows[size_t(y)][size_t(gb.object[g])].push_back(gb.position[g]);
                } else {
                    const vec3 d = cam.ray_dir(x, y);
                    const RayHit h = sc.rt.intersect(cam.eye, d, 0.f);
                    if (h.hit() && sc.objects[size_t(h.geometry)].prepare) rows[size_t(y)][size_t(h.geometry)].push_back(cam.eye + h.t * d);
                }
            }
        });
        for (auto& row : rows)  // in row order: the same list at any thread count
            for (size_t i = 0; i < row.size(); ++i) seen[i].insert(seen[i].end(), row[i].begin(), row[i].end());
    }
    TruthAccumulator a;
    if (from && from->continues(width, height, st.seed, st.first, st.spp) && !from->exitance.empty() == media) {
        a = *from;
    } else {
        a.width = width, a.height = height, a.seed = st.seed, a.first = a.spp = st.first;
        const size_t n = size_t(width) * size_t(height) * 3;
        a.sum.assign(n, 0), a.sum2.assign(n, 0), a.normal.assign(n, 0.f);
        if (media) a.exitance.assign(n, 0), a.irradiance.assign(n, 0);
    }
    a.ended = TruthEnd::Samples;
    a.seconds = 0;
    const auto t0 = clock::now();
    const int start = a.spp;
    auto noise_reached = [&] { return st.noise > 0.0 && a.samples() >= kNoiseMinSpp && truth_noise_rel(a) <= st.noise; };
    if (noise_reached()) a.ended = TruthEnd::Noise;
    while (a.ended == TruthEnd::Samples && a.spp < st.spp) {
        if (cancel && cancel->load()) {
            a.ended = TruthEnd::Cancelled;
            break;
        }
        const int k0 = a.spp, k1 = std::min(st.spp, (k0 / block + 1) * block);
        for (size_t i = 0; i < sc.objects.size(); ++i)
            if (sc.objects[i].prepare)
                sc.objects[i].prepare(TruthPrep{sc.rt, int(i), lighting, k0, k1, st.seed, sc.eps, 0.5f * (all.lo + all.hi),
                                                0.5f * glm::length(all.hi - all.lo), cancel, &seen[i]});
        sample_block(sc, lighting, cam, gb, lift, st, k0, k1, a, cancel);
        if (cancel && cancel->load()) {
            a.ended = TruthEnd::Cancelled;
            break;
        }
        a.spp = k1;
        const double elapsed = std::chrono::duration<double>(clock::now() - t0).count();
        const double per_sample = elapsed / double(a.spp - start);
        const double noise = st.noise > 0.0 || progress ? truth_noise_rel(a) : 0.0;
        if (st.noise > 0.0 && a.samples() >= kNoiseMinSpp && noise <= st.noise) a.ended = TruthEnd::Noise;
        else if (st.time_limit_s > 0.0 && elapsed >= st.time_limit_s && a.spp < st.spp) a.ended = TruthEnd::TimeLimit;
        if (progress) {
            // Samples still to go: to the end of the range, or, for a noise target, what the
            // estimator's 1/√n law asks for from the noise reached (capped by the range).
            double left = double(st.spp - a.spp), fraction = double(a.spp - a.first) / double(st.spp - a.first);
            std::string what = "truth: " + std::to_string(a.samples()) + " spp, noise " + strprintf("%.2f%%", 100.0 * noise);
            if (st.noise > 0.0 && noise > 0.0) {
                const double needed = std::max(double(kNoiseMinSpp), double(a.samples()) * (noise / st.noise) * (noise / st.noise));
                left = std::min(left, std::max(0.0, needed - double(a.samples())));
                fraction = std::max(fraction, double(a.samples()) / (double(a.samples()) + left));
                what += " (target " + strprintf("%.2f%%", 100.0 * st.noise) + ")";
            }
            if (st.time_limit_s > 0.0) fraction = std::max(fraction, elapsed / st.time_limit_s);
            double eta = left * per_sample;
            if (st.time_limit_s > 0.0) eta = std::min(eta, std::max(0.0, st.time_limit_s - elapsed));
            if (a.ended == TruthEnd::Samples && a.spp < st.spp) what += ", about " + duration_text(eta) + " left";
            progress(what, a.ended != TruthEnd::Samples || a.spp >= st.spp ? 1.0 : std::min(1.0, fraction));
        }
    }
    a.seconds = std::chrono::duration<double>(clock::now() - t0).count();
    return a;
}

Frame truth_frame(const TruthAccumulator& a) {
    std::vector<AovDecl> layout = {{"radiance", 3, ""}, {"normal", 3, ""}, {"truth_stderr", 3, "Standard error of the truth's radiance per pixel"},
                                   {"exitance", 3, "Subsurface exitance where a translucent object is seen (0 elsewhere)"},
                                   {"irradiance", 3, "Power per unit area entering a translucent object where one is seen (0 elsewhere)"}};
    Frame f = make_frame(layout, a.width, a.height);
    const double n = double(a.samples());
    if (!(n > 0.0)) return f;
    Image& radiance = f.aov("radiance");
    Image& normal = f.aov("normal");
    Image& stderr_ = f.aov("truth_stderr");
    Image& exitance = f.aov("exitance");
    Image& irradiance = f.aov("irradiance");
    mesolab::parallel_for(0, a.height, [&](int y) {
        for (int x = 0; x < a.width; ++x) {
            const size_t o = 3 * (size_t(y) * size_t(a.width) + size_t(x));
            float* r = radiance.at(x, y);
            float* nn = normal.at(x, y);
            float* e = stderr_.at(x, y);
            for (int c = 0; c < 3; ++c) {
                const double mean = from_fixed(a.sum[o + size_t(c)]) / n;
                const double var = n > 1.0 ? std::max(0.0, (from_fixed(a.sum2[o + size_t(c)]) - n * mean * mean) / (n - 1.0)) : 0.0;
                r[c] = float(mean), nn[c] = a.normal[o + size_t(c)], e[c] = float(std::sqrt(var / n));
                if (!a.exitance.empty()) {
                    exitance.at(x, y)[c] = float(from_fixed(a.exitance[o + size_t(c)]) / n);
                    irradiance.at(x, y)[c] = float(from_fixed(a.irradiance[o + size_t(c)]) / n);
                }
            }
        }
    });
    return f;
}

double truth_noise_rel(const TruthAccumulator& a) {
    const double n = double(a.samples());
    if (!(n > 1.0)) return 0.0;
    const size_t pixels = size_t(a.width) * size_t(a.height);
    struct Part {
        double sum = 0, se2 = 0;
        size_t count = 0;
    };
    // Rows summed in order, whatever the threads: the same figure every time.
    std::vector<Part> rows(size_t(a.height));
    mesolab::parallel_for(0, a.height, [&](int y) {
        Part& p = rows[size_t(y)];
        for (size_t i = size_t(y) * size_t(a.width); i < size_t(y + 1) * size_t(a.width) && i < pixels; ++i) {
            const float* nn = &a.normal[3 * i];
            if (nn[0] == 0.f && nn[1] == 0.f && nn[2] == 0.f) continue;  // background
            for (int c = 0; c < 3; ++c) {
                const double mean = from_fixed(a.sum[3 * i + size_t(c)]) / n;
                const double var = std::max(0.0, (from_fixed(a.sum2[3 * i + size_t(c)]) - n * mean * mean) / (n - 1.0));
                // As truth_frame rounds them: the same figure as truth_noise_rel(truth_frame(a)).
                const double m = double(float(mean)), se = double(float(std::sqrt(var / n)));
                p.sum += m, p.se2 += se * se;
            }
            p.count += 3;
        }
    });
    Part t;
    for (const Part& p : rows) t.sum += p.sum, t.se2 += p.se2, t.count += p.count;
    if (!t.count || !(t.sum > 0.0)) return 0.0;
    return std::sqrt(t.se2 / double(t.count)) / (t.sum / double(t.count));
}

Frame render_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& st, const std::vector<std::string>& aovs,
                   const std::function<void(const std::string&, double)>& progress, const std::atomic<bool>* cancel) {
    check_truth_request(s, width, height, st, aovs);
    const TruthAccumulator a = accumulate_truth(s, ev, width, height, st, nullptr, progress, cancel);
    if (a.ended == TruthEnd::Cancelled) throw Cancelled();
    return truth_frame(a);
}

// [SECTION] Partial truths
namespace {
constexpr char kPartMagic[8] = {'M', 'L', 'T', 'P', 'A', 'R', 'T', '1'};

void put_string(std::string& out, const std::string& v) {
    const uint64_t n = v.size();
    out.append(reinterpret_cast<const char*>(&n), sizeof n);
    out += v;
}
template <class T>
void put(std::string& out, const T& v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void put_vector(std::string& out, const std::vector<T>& v) {
    put(out, uint64_t(v.size()));
    out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

struct Reader {
    std::istream& in;
    std::string path;
    uint64_t left = 0;  // bytes left in the file
    [[noreturn]] void fail(const std::string& what) const { throw InputError(path + ": " + what); }
    void bytes(void* p, uint64_t n, const char* what) {
        if (n > left || !in.read(static_cast<char*>(p), std::streamsize(n))) fail(std::string("truncated (in its ") + what + ")");
        left -= n;
    }
    template <class T>
    T get(const char* what) {
        T v;
        bytes(&v, sizeof v, what);
        return v;
    }
    std::string string(const char* what) {
        const uint64_t n = get<uint64_t>(what);
        if (n > 1 << 20 || n > left) fail(std::string("truncated or not a partial truth (a ") + what + " of " + std::to_string(n) + " bytes)");
        std::string v(n, '\0');
        bytes(v.data(), n, what);
        return v;
    }
    template <class T>
    void vector(std::vector<T>& v, uint64_t expected, const char* what) {
        const uint64_t n = get<uint64_t>(what);
        if (n != expected) fail(std::string("its ") + what + " holds " + std::to_string(n) + " values where its size asks for " + std::to_string(expected));
        if (n * sizeof(T) > left) fail(std::string("truncated (in its ") + what + ")");
        v.resize(n);
        bytes(v.data(), n * sizeof(T), what);
    }
};
}  // namespace

void write_truth_part(const std::string& path, const TruthPart& p) { write_text_atomic(path, truth_part_bytes(p)); }

std::string truth_part_bytes(const TruthPart& p) {
    const TruthAccumulator& a = p.sums;
    std::string out(kPartMagic, 8);
    put_string(out, p.scene);
    put_string(out, p.key);
    put_string(out, p.build);
    put(out, int32_t(a.width)), put(out, int32_t(a.height)), put(out, int32_t(a.first)), put(out, int32_t(a.spp)), put(out, a.seed);
    put_vector(out, a.sum), put_vector(out, a.sum2), put_vector(out, a.exitance), put_vector(out, a.irradiance), put_vector(out, a.normal);
    return out;
}

namespace {
TruthPart read_part(std::istream& in, uint64_t size, const std::string& path);
}

TruthPart read_truth_part(const std::string& path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot read it (" + ec.message() + ")");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open it");
    return read_part(in, size, path);
}

TruthPart truth_part_from_bytes(const std::string& bytes, const std::string& name) {
    std::istringstream in(bytes);
    return read_part(in, bytes.size(), name);
}

namespace {
TruthPart read_part(std::istream& in, uint64_t size, const std::string& path) {
    Reader r{in, path, size};
    char magic[8];
    if (size < 8 || !r.in.read(magic, 8) || std::memcmp(magic, kPartMagic, 8) != 0)
        r.fail("not a partial truth (written by `mesolab capture --backend truth --samples A:B`)");
    r.left -= 8;
    TruthPart p;
    p.scene = r.string("scene name");
    p.key = r.string("key");
    p.build = r.string("build");
    TruthAccumulator& a = p.sums;
    a.width = r.get<int32_t>("size"), a.height = r.get<int32_t>("size");
    a.first = r.get<int32_t>("sample range"), a.spp = r.get<int32_t>("sample range");
    a.seed = r.get<uint64_t>("seed");
    if (a.width < 1 || a.height < 1 || a.width > 16384 || a.height > 16384)
        r.fail("its size " + std::to_string(a.width) + "x" + std::to_string(a.height) + " is out of range");
    if (a.first < 0 || a.spp <= a.first) r.fail("its sample range " + std::to_string(a.first) + ":" + std::to_string(a.spp) + " is empty");
    const uint64_t n = uint64_t(a.width) * uint64_t(a.height) * 3;
    r.vector(a.sum, n, "sums");
    r.vector(a.sum2, n, "sums of squares");
    const uint64_t m = r.get<uint64_t>("exitance");
    if (m != 0 && m != n) r.fail("its exitance holds " + std::to_string(m) + " values where its size asks for " + std::to_string(n));
    if (m * sizeof(TruthFixed) > r.left) r.fail("truncated (in its exitance)");
    a.exitance.resize(m);
    r.bytes(a.exitance.data(), m * sizeof(TruthFixed), "exitance");
    r.vector(a.irradiance, m, "irradiance");
    r.vector(a.normal, n, "normals");
    if (r.left != 0) r.fail(std::to_string(r.left) + " bytes follow the end of the partial truth");
    return p;
}
}  // namespace

TruthPart merge_truth_parts(const std::vector<std::pair<std::string, TruthPart>>& named) {
    if (named.empty()) throw InputError("truth merge: no partial truths given");
    std::vector<const std::pair<std::string, TruthPart>*> order;
    for (const auto& p : named) order.push_back(&p);
    std::stable_sort(order.begin(), order.end(), [](auto* x, auto* y) { return x->second.sums.first < y->second.sums.first; });
    const auto& [name0, p0] = *order.front();
    auto range = [](const TruthPart& p) { return "samples " + std::to_string(p.sums.first) + ":" + std::to_string(p.sums.spp); };
    for (size_t i = 1; i < order.size(); ++i) {
        const auto& [name, p] = *order[i];
        auto differ = [&](const std::string& what, const std::string& a, const std::string& b) {
            throw InputError(name + ": " + what + " differs from " + name0 + "'s (" + b + " against " + a + "): the parts are not of one truth");
        };
        if (p.scene != p0.scene) differ("the scene", p0.scene, p.scene);
        if (p.build != p0.build)
            differ("the build", p0.build, p.build + "; parts made by another build or instruction set round some rays differently");
        if (p.sums.width != p0.sums.width || p.sums.height != p0.sums.height)
            differ("the size", std::to_string(p0.sums.width) + "x" + std::to_string(p0.sums.height), std::to_string(p.sums.width) + "x" + std::to_string(p.sums.height));
        if (p.sums.seed != p0.sums.seed) differ("the seed", std::to_string(p0.sums.seed), std::to_string(p.sums.seed));
        if (p.key != p0.key) differ("what the truth reads (its key)", p0.key, p.key + "; another scene description, size or seed");
        if (p.sums.exitance.empty() != p0.sums.exitance.empty()) differ("the AOVs summed", "", "");
        const auto& [prev_name, prev] = *order[i - 1];
        if (p.sums.first < prev.sums.spp)
            throw InputError(name + " (" + range(p) + ") overlaps " + prev_name + " (" + range(prev) + "): each sample may be merged once");
        if (p.sums.first > prev.sums.spp)
            throw InputError(prev_name + " (" + range(prev) + ") and " + name + " (" + range(p) + ") leave a gap: samples " +
                             std::to_string(prev.sums.spp) + ":" + std::to_string(p.sums.first) + " are missing");
    }
    TruthPart out = p0;
    TruthAccumulator& a = out.sums;
    for (size_t i = 1; i < order.size(); ++i) {
        const TruthAccumulator& b = order[i]->second.sums;
        for (size_t j = 0; j < a.sum.size(); ++j) a.sum[j] += b.sum[j], a.sum2[j] += b.sum2[j];
        for (size_t j = 0; j < a.exitance.size(); ++j) a.exitance[j] += b.exitance[j], a.irradiance[j] += b.irradiance[j];
        a.spp = b.spp;
    }
    a.ended = TruthEnd::Samples;
    return out;
}

TruthComparison compare_to_truth(const Frame& rt, const Frame& truth, const TruthSettings& st) {
    const Image& a = rt.aov("radiance");
    const Image& b = truth.aov("radiance");
    if (a.width != b.width || a.height != b.height) throw std::invalid_argument("compare_to_truth: the frames differ in size");
    TruthComparison c;
    c.spp = st.spp, c.seed = st.seed;
    c.error = Image(a.width, a.height, 3);
    double se = 0.0, sum = 0.0;
    size_t count = 0;
    const Image& n = truth.aov("normal");
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const float* nn = n.at(x, y);
            const bool object = nn[0] != 0.f || nn[1] != 0.f || nn[2] != 0.f;
            for (int ch = 0; ch < 3; ++ch) {
                const float d = a.at(x, y)[std::min(ch, a.channels - 1)] - b.at(x, y)[ch];
                c.error.at(x, y)[ch] = d;
                if (object) se += double(d) * d, sum += b.at(x, y)[ch], ++count;
            }
        }
    c.noise_rel = truth_noise_rel(truth);
    c.rmse_rel = count && sum > 0.0 ? std::sqrt(se / double(count)) / (sum / double(count)) : 0.0;
    c.below_noise = c.rmse_rel <= 2.0 * c.noise_rel;
    return c;
}

double truth_noise_rel(const Frame& truth) {
    const Image& L = truth.aov("radiance");
    const Image& e = truth.aov("truth_stderr");
    const Image& n = truth.aov("normal");
    double sum = 0.0, se2 = 0.0;
    size_t count = 0;
    for (int y = 0; y < L.height; ++y)
        for (int x = 0; x < L.width; ++x) {
            const float* nn = n.at(x, y);
            if (nn[0] == 0.f && nn[1] == 0.f && nn[2] == 0.f) continue;  // background
            for (int c = 0; c < 3; ++c) sum += L.at(x, y)[c], se2 += double(e.at(x, y)[c]) * e.at(x, y)[c];
            count += 3;
        }
    if (!count || !(sum > 0.0)) return 0.0;
    return std::sqrt(se2 / double(count)) / (sum / double(count));
}
}  // namespace mesolab
