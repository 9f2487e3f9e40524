#include "core/truth/truth.h"
#include "core/error.h"
#include "core/raster.h"
#include "core/raytrace.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/scene_stages.h"
#include "core/technique.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <set>
#include <stdexcept>

namespace mesolab {
using glm::dvec3;

// [SECTION] Random numbers
namespace {
uint64_t mix(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
}  // namespace

TruthRng::TruthRng(uint64_t seed, uint64_t pixel, uint64_t sample)
    : state_(mix(mix(mix(seed + 0x9e3779b97f4a7c15ull) ^ pixel) + sample * 0x9e3779b97f4a7c15ull)) {}

float TruthRng::next() {
    state_ += 0x9e3779b97f4a7c15ull;
    return float(mix(state_) >> 40) * 0x1p-24f;  // 24 bits: exactly representable, < 1
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
    static const std::vector<std::string> names = {"radiance", "normal", "truth_stderr", "exitance"};
    return names;
}

namespace {
const Technique& technique_with_truth(const Scene& s, size_t object) {
    const std::string& name = s.objects[object].technique;
    const Technique* t = Registry::instance().technique(name);
    if (!t) throw InputError("objects[" + std::to_string(object) + "].technique: unknown technique '" + name + "'");
    if (!t->has_truth())
        throw InputError("--backend truth: technique " + name + " (object '" + s.objects[object].name + "') has no truth renderer yet");
    return *t;
}
}  // namespace

std::vector<StageName> truth_stages(const Scene& s) {
    std::vector<StageName> out = {stages::geometry, stages::env_map};
    std::set<std::string> seen;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const Technique& t = technique_with_truth(s, i);
        if (!seen.insert(t.name()).second) continue;
        for (const StageName& n : t.truth_stages()) out.push_back(n);
    }
    return out;
}

std::string truth_description(const Scene& s) {
    const StageGraph& g = Registry::instance().stages();
    // (key pattern, object) pairs the truth reads, in a fixed order; object -1 for scene-wide keys.
    std::set<std::pair<std::string, int>> keys = {{"camera.*", -1}, {"light.*", -1}, {"env.*", -1}, {"effects.environment", -1}};
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
    std::string out;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const Technique& t = technique_with_truth(s, i);
        out += "object " + std::to_string(i) + " " + t.name() + ";";
        keys.insert({"geometry.*", int(i)});
        for (const std::string& p : t.truth_params()) keys.insert({p, int(i)});
    }
    for (const auto& [pattern, object] : keys) out += param_fingerprint(s, pattern, object, FileIdentity::Contents);
    return out;
}

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

void check_truth_request(const Scene& s, int width, int height, const TruthSettings& st, const std::vector<std::string>& aovs) {
    if (st.spp < 1) throw InputError("--spp " + std::to_string(st.spp) + ": expected at least 1 sample per pixel");
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError("frame size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range (1..16384 per side)");
    for (const std::string& a : aovs)
        if (std::find(truth_aovs().begin(), truth_aovs().end(), a) == truth_aovs().end())
            throw InputError("--aov " + a + ": the truth does not write it (it writes radiance, normal, truth_stderr, exitance)");
    for (size_t i = 0; i < s.objects.size(); ++i) technique_with_truth(s, i);
}

TruthAccumulator accumulate_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& st, const TruthAccumulator* from,
                                  const std::function<void(const std::string&, double)>& progress, const std::atomic<bool>* cancel) {
    check_truth_request(s, width, height, st, {});
    TruthScene sc;
    Bounds all{vec3(1e30f), vec3(-1e30f)};
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const Technique& t = technique_with_truth(s, i);
        TruthObject ob = t.truth_object(s, ev, int(i));
        if (!ob.mesh || !ob.material) throw std::logic_error("truth: technique " + t.name() + " gave no mesh or material for object " + std::to_string(i));
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
            lift.push_back(technique_with_truth(s, i).truth_lift(s, ev, int(i)) * scale + 2.f * sc.eps);
        }
        rasterize(items, cam.raster, gb);
    }
    TruthAccumulator a;
    if (from && from->continues(width, height, st.seed, st.spp)) a = *from;
    else {
        a.width = width, a.height = height, a.seed = st.seed, a.spp = 0;
        const size_t n = size_t(width) * size_t(height) * 3;
        a.sum.assign(n, 0.0), a.sum2.assign(n, 0.0), a.exitance.assign(n, 0.0), a.normal.assign(n, 0.f);
    }
    const int first = a.spp;
    for (size_t i = 0; i < sc.objects.size(); ++i)
        if (sc.objects[i].prepare && first < st.spp) {
            if (progress) progress("truth: " + s.objects[i].name, 0.0);
            sc.objects[i].prepare(TruthPrep{sc.rt, int(i), lighting, first, st.spp, st.seed, sc.eps, 0.5f * (all.lo + all.hi),
                                            0.5f * glm::length(all.hi - all.lo), cancel});
        }
    std::atomic<int> rows_done{0};
    std::mutex progress_mutex;
    tbb::parallel_for(0, height, [&](int y) {
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
                    const vec3 *a = at(x - dx, y - dy), *b = at(x + dx, y + dy);
                    if (a && b) return 0.5f * (*b - *a);
                    if (b) return *b - gb.position[g];
                    if (a) return gb.position[g] - *a;
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
            for (int k = first; k < st.spp; ++k) {
                const PixelSample ps = trace(sc, lighting, primary, st, pixel, uint64_t(k));
                for (int c = 0; c < 3; ++c) {
                    const double L = ps.L[c];
                    a.sum[o + size_t(c)] += L, a.sum2[o + size_t(c)] += L * L;
                    a.exitance[o + size_t(c)] += ps.exitance[c];
                    if (k == 0) a.normal[o + size_t(c)] = ps.normal[c];
                }
            }
        }
        const int done = ++rows_done;
        if (progress && (done % 8 == 0 || done == height)) {
            std::lock_guard<std::mutex> lock(progress_mutex);
            progress("truth", double(done) / double(height));
        }
    });
    a.spp = st.spp;
    return a;
}

Frame truth_frame(const TruthAccumulator& a) {
    std::vector<AovDecl> layout = {{"radiance", 3, ""}, {"normal", 3, ""}, {"truth_stderr", 3, "Standard error of the truth's radiance per pixel"},
                                   {"exitance", 3, "Subsurface exitance where a translucent object is seen (0 elsewhere)"}};
    Frame f = make_frame(layout, a.width, a.height);
    const double n = double(a.spp);
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const size_t o = 3 * (size_t(y) * size_t(a.width) + size_t(x));
            float* r = f.aov("radiance").at(x, y);
            float* nn = f.aov("normal").at(x, y);
            float* e = f.aov("truth_stderr").at(x, y);
            float* m = f.aov("exitance").at(x, y);
            for (int c = 0; c < 3; ++c) {
                const double mean = a.sum[o + size_t(c)] / n;
                const double var = n > 1.0 ? std::max(0.0, (a.sum2[o + size_t(c)] - n * mean * mean) / (n - 1.0)) : 0.0;
                r[c] = float(mean), nn[c] = a.normal[o + size_t(c)], e[c] = float(std::sqrt(var / n));
                m[c] = a.exitance.empty() ? 0.f : float(a.exitance[o + size_t(c)] / n);
            }
        }
    return f;
}

Frame render_truth(const Scene& s, const Evaluation& ev, int width, int height, const TruthSettings& st, const std::vector<std::string>& aovs,
                   const std::function<void(const std::string&, double)>& progress, const std::atomic<bool>* cancel) {
    check_truth_request(s, width, height, st, aovs);
    return truth_frame(accumulate_truth(s, ev, width, height, st, nullptr, progress, cancel));
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
