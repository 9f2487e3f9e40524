// Method lean of technique bumpsynth: LEAN mapping of the synthesised bumps (see lean.h). The map,
// its filtering and shading, the method's keys and stage, and its CPU shading; the GPU pass is
// gpu/bumpsynth/lean_pass.cpp with lean.frag.
#include "core/bumpsynth/lean.h"
#include "core/bumpsynth/stages.h"
#include "core/blob.h"
#include "core/bumpsynth/technique.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/render.h"
#include "core/sampling.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <map>

namespace mesolab::bumpsynth {

// [SECTION] The map
size_t LeanMap::bytes() const {
    size_t n = 0;
    for (const Level& l : levels) n += (l.a.size() + l.b.size()) * sizeof(vec4);
    return n;
}

LeanMap LeanMap::bake(const std::function<vec3(vec2)>& bump, int size, int supersample, vec3 sigma0) {
    if (size < 16 || size > 4096 || !std::has_single_bit(unsigned(size)))
        throw InputError("bumpsynth.lean_size: expected a power of two in [16, 4096], got " + std::to_string(size));
    if (supersample < 1) throw InputError("bumpsynth.lean_supersample: expected at least 1, got " + std::to_string(supersample));
    LeanMap map;
    map.sigma0 = sigma0;
    Level l0;
    l0.n = size;
    l0.a.resize(size_t(size) * size_t(size));
    l0.b.resize(l0.a.size());
    const int s = supersample;
    const double inv = 1.0 / double(s * s);
    mesolab::parallel_for(0, size, [&](int y) {
        for (int x = 0; x < size; ++x) {
            double B[2] = {0, 0}, M[3] = {0, 0, 0}, m[3] = {0, 0, 0};
            for (int j = 0; j < s; ++j)
                for (int i = 0; i < s; ++i) {
                    const vec2 uv((float(x) + (float(i) + 0.5f) / float(s)) / float(size), 1.f - (float(y) + (float(j) + 0.5f) / float(s)) / float(size));
                    const vec3 n = bump(uv);
                    const double z = std::max(double(n.z), double(kLeanMinCos));
                    const double bx = double(n.x) / z, by = double(n.y) / z;
                    B[0] += bx, B[1] += by;
                    M[0] += bx * bx, M[1] += by * by, M[2] += bx * by;
                    m[0] += n.x, m[1] += n.y, m[2] += n.z;
                }
            const size_t k = size_t(y) * size_t(size) + size_t(x);
            l0.a[k] = vec4(float(B[0] * inv), float(B[1] * inv), float(M[0] * inv), float(M[1] * inv));
            l0.b[k] = vec4(float(M[2] * inv), float(m[0] * inv), float(m[1] * inv), float(m[2] * inv));
        }
    });
    map.levels.push_back(std::move(l0));
    while (map.levels.back().n > 1) {
        const Level& f = map.levels.back();
        Level c;
        c.n = f.n / 2;
        c.a.resize(size_t(c.n) * size_t(c.n));
        c.b.resize(c.a.size());
        for (int y = 0; y < c.n; ++y)
            for (int x = 0; x < c.n; ++x) {
                const auto at = [&](const std::vector<vec4>& v, int dx, int dy) { return v[size_t(2 * y + dy) * size_t(f.n) + size_t(2 * x + dx)]; };
                const size_t k = size_t(y) * size_t(c.n) + size_t(x);
                c.a[k] = 0.25f * (at(f.a, 0, 0) + at(f.a, 1, 0) + at(f.a, 0, 1) + at(f.a, 1, 1));
                c.b[k] = 0.25f * (at(f.b, 0, 0) + at(f.b, 1, 0) + at(f.b, 0, 1) + at(f.b, 1, 1));
            }
        map.levels.push_back(std::move(c));
    }
    return map;
}

LeanMoments LeanMap::at_level(int l, vec2 uv) const {
    const Level& L = levels[size_t(std::clamp(l, 0, int(levels.size()) - 1))];
    // Row 0 at v = 1; a + t (b - a), as the GLSL writes it (lean.frag).
    const BilinearTaps taps(uv.x * float(L.n) - 0.5f, (1.f - uv.y) * float(L.n) - 0.5f, L.n, L.n, Edge::Wrap, Edge::Wrap);
    const vec4 a = taps.blend_lerp([&](int x, int y) { return L.a[size_t(y) * size_t(L.n) + size_t(x)]; });
    const vec4 b = taps.blend_lerp([&](int x, int y) { return L.b[size_t(y) * size_t(L.n) + size_t(x)]; });
    LeanMoments mo;
    mo.B = vec2(a.x, a.y);
    mo.M = vec3(a.z, a.w, b.x);
    mo.m = vec3(b.y, b.z, b.w);
    return mo;
}

LeanMoments LeanMap::trilinear(vec2 uv, float lambda) const {
    const int last = int(levels.size()) - 1;
    const float lam = std::clamp(std::isfinite(lambda) ? lambda : 0.f, 0.f, float(last));
    const int l0 = std::min(int(std::floor(lam)), last);
    const float t = lam - float(l0);
    LeanMoments mo = at_level(l0, uv);
    if (t > 0.f && l0 < last) {
        const LeanMoments c = at_level(l0 + 1, uv);
        mo.B += t * (c.B - mo.B);
        mo.M += t * (c.M - mo.M);
        mo.m += t * (c.m - mo.m);
    }
    mo.lambda = lam;
    return mo;
}

LeanMoments LeanMap::filter(vec2 uv, vec2 duv_dx, vec2 duv_dy, int anisotropy) const {
    const float lx = glm::length(duv_dx), ly = glm::length(duv_dy);
    const float major = std::max(lx, ly), minor = std::min(lx, ly);
    const vec2 axis = lx >= ly ? duv_dx : duv_dy;
    const float N = float(size());
    int taps = 1;
    if (anisotropy > 1 && minor > 0.f) taps = std::clamp(int(std::ceil(major / minor)), 1, anisotropy);
    else if (anisotropy > 1 && major > 0.f) taps = anisotropy;
    const float extent = std::max(major / float(taps), minor);
    const float lambda = extent > 0.f ? std::log2(extent * N) : 0.f;
    if (taps == 1) return trilinear(uv, lambda);
    LeanMoments sum;
    sum.m = vec3(0.f);
    for (int k = 0; k < taps; ++k) {
        const float f = (float(k) + 0.5f) / float(taps) - 0.5f;
        const LeanMoments mo = trilinear(uv + f * axis, lambda);
        sum.B += mo.B, sum.M += mo.M, sum.m += mo.m;
        sum.lambda = mo.lambda;
    }
    const float w = 1.f / float(taps);
    sum.B *= w, sum.M *= w, sum.m *= w;
    return sum;
}

vec3 slope_covariance(const Ndf& ndf) {
    const int R = ndf.resolution();
    double s[3] = {0, 0, 0}, total = 0;
    for (int j = 0; j < R; ++j)
        for (int i = 0; i < R; ++i) {
            const double mass = ndf.mass(i, j);
            if (!(mass > 0.0)) continue;
            vec2 c = ndf.cell_centre(i, j);
            const float r2 = glm::dot(c, c);
            if (r2 > 0.9999f) c *= std::sqrt(0.9999f / r2);
            const double z = std::max(double(std::sqrt(1.f - glm::dot(c, c))), double(kLeanMinCos));
            const double bx = double(c.x) / z, by = double(c.y) / z;
            s[0] += mass * bx * bx, s[1] += mass * by * by, s[2] += mass * bx * by;
            total += mass;
        }
    return total > 0.0 ? vec3(float(s[0] / total), float(s[1] / total), float(s[2] / total)) : vec3(0.f);
}

// [SECTION] The lobe and the BRDF
LeanLobe::LeanLobe(const LeanMoments& mo, vec3 sigma0) : B(mo.B) {
    sxx = std::max(mo.M.x - mo.B.x * mo.B.x, 0.f) + sigma0.x + 1e-8f;
    syy = std::max(mo.M.y - mo.B.y * mo.B.y, 0.f) + sigma0.y + 1e-8f;
    sxy = mo.M.z - mo.B.x * mo.B.y + sigma0.z;
    // Keep Σ positive definite where rounding made the filtered covariance slightly indefinite.
    const float lim = 0.999f * std::sqrt(sxx * syy);
    sxy = std::clamp(sxy, -lim, lim);
}

float LeanLobe::D(vec3 h) const {
    if (!(h.z > 0.f)) return 0.f;
    const float dx = h.x / h.z - B.x, dy = h.y / h.z - B.y;
    const float det = sxx * syy - sxy * sxy;
    const float e = (syy * dx * dx - 2.f * sxy * dx * dy + sxx * dy * dy) / det;
    const float h2 = h.z * h.z;
    return std::exp(-0.5f * e) / (2.f * kPi * std::sqrt(det) * h2 * h2);
}

float LeanLobe::Lambda(vec3 w) const {
    const float r2 = w.x * w.x + w.y * w.y;
    if (!(r2 > 0.f)) return 0.f;
    if (!(w.z > 0.f)) return 1e7f;
    const float s2 = (w.x * w.x * sxx + 2.f * w.x * w.y * sxy + w.y * w.y * syy) / r2;  // slope variance along w
    const float a = w.z / std::sqrt(2.f * s2 * r2);                                       // 1 / (α tan θ)
    if (a >= 1.6f) return 0.f;
    return (1.f - 1.259f * a + 0.396f * a * a) / (3.535f * a + 2.181f * a * a);
}

vec3 lean_shade(const ShadingModel& s, const LeanLobe& lobe, const LeanMoments& mo, vec3 wo, vec3 wi, vec3 E, vec3 albedo) {
    if (!(wo.z > 0.f) || !(wi.z > 0.f)) return vec3(0.f);
    vec3 L = s.kd * albedo * (kInvPi * std::max(0.f, glm::dot(mo.m, wi)));
    const vec3 h = glm::normalize(wo + wi);
    const float D = lobe.D(h);
    const vec3 F = s.fresnel ? s.ks + (vec3(1.f) - s.ks) * std::pow(std::clamp(1.f - glm::dot(wi, h), 0.f, 1.f), 5.f) : s.ks;
    if (s.masking) {
        const float G2 = 1.f / (1.f + lobe.Lambda(wo) + lobe.Lambda(wi));
        L += F * (D * G2 / (4.f * wo.z));
    } else {
        L += F * (D * wi.z / 4.f);
    }
    return L * E;
}

namespace {

// [SECTION] The method
class LeanMethod final : public Method {
public:
    LeanMethod() : Method("bumpsynth", "lean", "LEAN mapping of the synthesised bumps (Olano and Baker 2010)") {}

    void declare_params(ParamGroup& p) const override {
        p.add_int("lean_size", 512).used_when("method", {"lean"}).range(16, 4096).power_of_two().log().in("texels").more_accurate(Accuracy::Higher, int64_t(2048))
            .doc("LEAN mapping: texels per side of the baked map's finest level (a power of two); detail finer than a texel enters its second moments");
        p.add_int("lean_supersample", 4).used_when("method", {"lean"}).range(1, 16).more_accurate(Accuracy::Higher, int64_t(8))
            .doc("Points per side of the grid over each texel whose bump slopes the map's moments average");
        p.add_int("lean_anisotropy", 4).used_when("method", {"lean"}).range(1, 16).more_accurate(Accuracy::Higher, int64_t(16))
            .doc("Most trilinear taps along a footprint's major axis (footprint assembly, as anisotropic filtering); 1: isotropic");
        p.section("LEAN mapping", {"lean_size", "lean_supersample", "lean_anisotropy"});
    }

    void declare_stages(StageGraph& g) const override {
        std::vector<std::string> params = keys({"lean_size", "lean_supersample", "octaves_max", "index_noise"});
        for (const auto& k : keys(kNoiseKeys)) params.push_back(k);
        g.add(stages::lean_map,
              {.help = "Bake the synthesised bumps (all octaves, as the truth draws them) into LEAN mapping's slope moments with mip levels",
               .scope = StageScope::Object,
               .technique = "bumpsynth",
               .params = params,
               .inputs = {stages::truth_ndf, stages::noise_cdf},
               .memory = [](const StageContext& ctx) {
                   const double n = double(ctx.material().get_int("lean_size"));
                   return MemoryEstimate{n * n * 4.0 / 3.0 * 2.0 * sizeof(vec4), "LEAN map: " + std::to_string(int(n)) + "^2 texels of moments with mip levels",
                                         {"bumpsynth.lean_size"}};
               },
               .run = [](StageContext& ctx) {
                   const auto t = ctx.input(stages::truth_ndf);
                   const auto cdfs = ctx.input(stages::noise_cdf);
                   const ParamTable& m = ctx.material();
                   const IndexDetail detail = truth_index_detail(*t, m);
                   const int K = int(m.get_int("octaves_max"));
                   const NoiseCdfs* c = cdfs.get();
                   if (!t->index_map && !c) throw std::logic_error("bumpsynth/lean: no noise CDFs for a noise-synthesised object");
                   return stage_result(stages::lean_map,
                                       LeanMap::bake([&](vec2 uv) { return truth_bump_normal(*t, c, detail, uv, K); }, int(m.get_int("lean_size")),
                                                     int(m.get_int("lean_supersample")), slope_covariance(t->ndf)));
               },
               // Kept on disk: the bake (a second or more at the default size) is not redone in the next run.
               .disk = stage_codec(
                   stages::lean_map,
                   [](BlobWriter& w, const LeanMap& map) {
                       w.put(map.sigma0);
                       w.put(uint32_t(map.levels.size()));
                       for (const LeanMap::Level& l : map.levels) w.put(int32_t(l.n)), w.put_vector(l.a), w.put_vector(l.b);
                   },
                   [](BlobReader& r) {
                       LeanMap map;
                       map.sigma0 = r.get<vec3>();
                       const uint32_t n = r.get<uint32_t>();
                       if (n > 13) throw BlobError("LEAN map: " + std::to_string(n) + " levels");
                       for (uint32_t i = 0; i < n; ++i) {
                           LeanMap::Level l;
                           l.n = r.get<int32_t>();
                           l.a = r.get_vector<vec4>();
                           l.b = r.get_vector<vec4>();
                           const int want = i == 0 ? l.n : map.levels.back().n / 2;
                           if (l.n != want || l.n < 1 || l.a.size() != size_t(l.n) * size_t(l.n) || l.b.size() != l.a.size())
                               throw BlobError("LEAN map: level " + std::to_string(i) + " has the wrong size");
                           map.levels.push_back(std::move(l));
                       }
                       if (map.levels.empty() || map.levels.back().n != 1) throw BlobError("LEAN map: its levels do not end at 1x1");
                       return map;
                   })});
    }

    std::vector<StageName> frame_stages() const override { return {stages::lean_map, stages::albedo}; }
    bool uses_uv_derivatives() const override { return true; }

    void shade_cpu(const ShadeContext& ctx) const override;

    // Both paths filter the same moments with the same taps and weights (texelFetch with the CPU's
    // lerps); what differs is the footprint (dFdxFine against the rasteriser's differences, a few
    // ULP, moving λ and the taps slightly) and the float evaluation of exp, log2 and pow. The lobe
    // is smooth in both, so differences stay at rounding scaled by the lobe's slope.
    FrameAgreement agreement() const override {
        return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.999, .interior_max = 5e-3, .interior_outliers = 1e-3,
                .why = "float evaluation of the footprint, exp and pow; the number of anisotropic taps is a whole number of the footprint's ratio"};
    }
};

void LeanMethod::shade_cpu(const ShadeContext& ctx) const {
    struct Obj {
        std::shared_ptr<const LeanMap> map;
        ShadingModel model;
        int anisotropy = 1;
        float octaves = 0;
        const Image* albedo = nullptr;
    };
    std::map<int, Obj> objs;
    for (int i : ctx.objects) {
        const ParamTable& m = ctx.scene.objects[size_t(i)].material;
        Obj o;
        o.map = ctx.eval.get(stages::lean_map, i);
        if (!o.map) throw std::logic_error("bumpsynth/lean: the frame's stages were not evaluated for object " + std::to_string(i));
        o.model = shading_from_material(m);
        o.anisotropy = int(m.get_int("lean_anisotropy"));
        o.octaves = float(m.get_int("octaves_max"));
        o.albedo = ctx.eval.get(stages::albedo, i).get();
        objs.emplace(i, std::move(o));
    }
    const GBuffer& gb = ctx.gbuffer;
    if (gb.uv_dx.size() != gb.uv.size()) throw std::logic_error("bumpsynth/lean: the G-buffer lacks uv derivatives (DrawItem::uv_derivatives)");
    const int octaves_out = ctx.out.index("octaves"), entry_out = ctx.out.index("entry"), entry_fine_out = ctx.out.index("entry_fine");
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const Obj& o = objs.at(gb.object[px]);
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec2 uv = gb.uv[px];
            const LeanMoments mo = o.map->filter(uv, gb.uv_dx[px], gb.uv_dy[px], o.anisotropy);
            const LeanLobe lobe(mo, o.map->sigma0);
            const vec3 tex = o.albedo ? basic::sample_albedo(*o.albedo, uv) : vec3(1.f);
            const vec3 wo_t = frame.to_local(wo);
            const float mlen = glm::length(mo.m);
            const vec3 n = mlen > 0.f ? mo.m / mlen : vec3(0, 0, 1);
            vec3 L(0.f);
            for (const Light& l : ctx.lighting.lights) {
                vec3 wi, E;
                l.sample(p, wi, E);
                L += lean_shade(o.model, lobe, mo, wo_t, frame.to_local(wi), E, tex);
            }
            L += o.model.kd * tex * kInvPi * ctx.lighting.env_irradiance(frame.to_world(n));
            ctx.out.put(AovWriter::kRadiance, x, y, L);
            ctx.out.put(AovWriter::kNormal, x, y, n);
            ctx.out.put(octaves_out, x, y, o.octaves);
            ctx.out.put(entry_out, x, y, vec3(-1.f, -1.f, o.octaves));
            ctx.out.put(entry_fine_out, x, y, vec3(-1.f, -1.f, o.octaves));
        }
    });
}
}  // namespace
}  // namespace mesolab::bumpsynth

namespace mesolab {
void register_bumpsynth_lean(Registry& r) { r.add_method(std::make_unique<bumpsynth::LeanMethod>()); }
}  // namespace mesolab
