// Technique bumpsynth: its truth. What the NDF and the distance-dependent octaves stand in for: per
// pixel, the footprint (a box filter: the pixel's square carried onto the surface's uv) integrated over
// the finest synthesised bumps, all bumpsynth.octaves_max octaves of them wherever the eye is, each
// bump's normal shaded with the micro-BRDF the real-time path applies at full detail (brdf.h: the NDF
// looked up in the bump's frame, Schlick's Fresnel and Smith masking as the material asks, the diffuse
// term with the albedo map).
//
// The bumps are those the synthesis draws, without its approximations: the procedural noise (never the
// baked noise texture), its inputs mapped to normals by the exact inversion of the NDF's CDFs rather
// than the nearest entry of a table, and the NDF tabulated at 512^2 cells whatever
// bumpsynth.ndf_resolution and lut_size say (technique.h, TruthNdf). With index_map on, the bump
// map's own normals through an index texture into that NDF, plus its detail octaves.
//
// Delta lights on near-mirror facets: the kernel is the NDF's cell, 2/512 of the normal's disk
// (0.22 degrees at the pole; a bump map's histogram: 2/R with R for 2 normals per cell, technique.h):
// a lobe narrower than that is spread over the cell, on the truth as in the real-time table. Everything else comes from the path tracer (core/truth/truth.h): shadows of the
// macro-surface, light between its parts and the environment where a path escapes. Paths go on from a
// bump by its lobes: the diffuse cosine-weighted about the bump's normal, the specular by reflecting
// about a normal drawn from the NDF in the bump's frame (uniform within the drawn cell: direct light,
// which looks the NDF up bilinearly, and sampled light see the same 512^2 NDF up to its interpolation).
//
// Direct light at the camera's hit (TruthMaterial::fcos_light). Every point of a pixel's footprint
// lies on the centre ray's hit p, so a delta light's contribution is V(p) E times the footprint's
// mean of fcos, a 2D integral of a known function, which the path's one footprint point estimates
// badly wherever bumps finer than the pixel catch a narrow highlight: fcos is then a patchwork of
// plateaus 10^2-10^3 times the diffuse term over a fraction of the footprint (sec7-index-map-zoom's
// brick tops under the index map's detail noise), or many small bright bumps (fig5's 8 octaves).
// Splitting (Arvo & Kirk 1990) with stratified points (jittered sampling, Cook 1986) estimates
// it instead: the mean of fcos over one uniform point in each cell of an n_x x n_y grid over the
// footprint, fresh points from the sample's own stream. Its expectation is the footprint's mean
// for any grid, so the number of points is chosen per footprint and light by a deterministic pilot
// (fcos at the centres of an 8 x 8 grid, computed once per footprint and kept): one point per
// 0.01 sr⁻¹ of the pilot's standard deviation of fcos (Neyman's allocation: points in proportion
// to the spread), at most 256, the grid's sides in the proportion of the footprint's; a flat
// footprint keeps the path's own point, as the plain estimator. Each sample stays independent of
// the others (the pilot is not random), so truth_stderr remains the estimate's standard error. A
// highlight smaller than the pilot's cells (~1/64 of the footprint) may be missed and is then
// sampled as before. MESOLAB_TRUTH_PLAIN=1 (a developer switch, for measuring) keeps the path's
// own point everywhere.
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/technique.h"
#include "core/render.h"
#include "core/scene_stages.h"

#include <tbb/concurrent_hash_map.h>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace mesolab::bumpsynth {
namespace {
float luminance(vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

class BumpsynthTruthMaterial final : public TruthMaterial {
public:
    // plain: next-event estimation at the path's own point of the footprint only (MESOLAB_TRUTH_PLAIN).
    BumpsynthTruthMaterial(std::shared_ptr<const TruthNdf> t, std::shared_ptr<const NoiseCdfs> cdfs, IndexDetail detail, int octaves,
                           ShadingModel model, std::shared_ptr<const Image> albedo, bool plain)
        : plain_(plain), t_(std::move(t)), cdfs_(std::move(cdfs)), detail_(detail), K_(octaves), model_(model), albedo_(std::move(albedo)) {}

    bool footprint() const override { return true; }

    // The point of the pixel's footprint this sample stands for.
    static vec2 uv_of(const TruthHit& h) { return h.uv + (h.jitter.x - 0.5f) * h.duv_dx + (h.jitter.y - 0.5f) * h.duv_dy; }

    // The bump at uv: its inputs at K octaves through the exact inversion of the NDF.
    LutEntry bump(vec2 uv) const { return microfacet_frame(truth_bump_normal(*t_, cdfs_.get(), detail_, uv, K_)); }
    vec3 texture(vec2 uv) const { return albedo_ ? basic::sample_albedo(*albedo_, uv) : vec3(1.f); }

    vec3 fcos(const TruthHit& h, vec3 wo, vec3 wi) const override {
        const vec2 uv = uv_of(h);
        const TangentFrame fr = tangent_frame(h.n, h.tangent, wo);
        return shade_facet(model_, t_->ndf, t_->smith ? &*t_->smith : nullptr, bump(uv), fr.to_local(wo), fr.to_local(wi), vec3(1.f), texture(uv));
    }
    // Next-event estimation over the footprint (see the file's head): the mean of fcos over n.x n.y
    // points, one uniform in each cell of an n.x x n.y grid over the footprint, n from its pilot
    // (strata); fcos at the path's own point where n is 1, off the camera's hits (no footprint), and
    // for the plain estimator.
    vec3 fcos_light(const TruthHit& h, vec3 wo, vec3 wi, TruthRng& rng) const override {
        if (plain_ || (h.duv_dx == vec2(0.f) && h.duv_dy == vec2(0.f))) return fcos(h, wo, wi);
        const ivec2 n = strata(h, wo, wi);
        if (n.x * n.y == 1) return fcos(h, wo, wi);
        vec3 sum(0.f);
        TruthHit q = h;
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
                const float a = rng.next(), b = rng.next();
                q.jitter = vec2((float(i) + a) / float(n.x), (float(j) + b) / float(n.y));
                sum += fcos(q, wo, wi);
            }
        return sum / float(n.x * n.y);
    }
    vec3 f(const TruthHit& h, vec3 wo, vec3 wi) const override { return fcos(h, wo, wi) / std::max(1e-6f, glm::dot(h.n, wi)); }

    // One lobe, chosen by its albedo's share: the diffuse one cosine-weighted about the bump's normal,
    // the specular one by reflecting wo about a normal the NDF draws in the bump's frame.
    vec3 sample(const TruthHit& h, vec3 wo, TruthRng& rng, vec3& wi) const override {
        const vec2 uv = uv_of(h);
        const TangentFrame fr = tangent_frame(h.n, h.tangent, wo);
        const LutEntry b = bump(uv);
        const vec3 tex = texture(uv);
        const vec3 kd = model_.kd * tex;
        const float ls = luminance(model_.ks), ld = luminance(kd);
        if (!(ls + ld > 0.f)) return vec3(0.f);
        const float ps = ls / (ls + ld);
        const vec3 wo_l = fr.to_local(wo);
        const vec3 o(glm::dot(wo_l, b.t), glm::dot(wo_l, b.b), glm::dot(wo_l, b.m));
        const float u0 = rng.next(), u1 = rng.next(), u2 = rng.next();
        vec3 i;
        vec3 w(0.f);
        if (u0 < ps) {
            if (!(o.z > 0.f)) return vec3(0.f);
            const vec3 m = t_->lut.sample_uniform(double(u1), double(u2));
            const float oh = glm::dot(o, m);
            if (!(oh > 0.f)) return vec3(0.f);
            i = 2.f * oh * m - o;
            if (!(i.z > 0.f)) return vec3(0.f);
            const vec3 F = model_.fresnel ? model_.ks + (vec3(1.f) - model_.ks) * std::pow(std::clamp(1.f - glm::dot(i, m), 0.f, 1.f), 5.f) : model_.ks;
            // f_s cos θi over the density of i, D(m) m_z / (4 o·m): D cancels.
            float g;
            if (model_.masking && t_->smith) {
                const float g1o = std::max(t_->smith->G1(o), 1e-7f), g1i = std::max(t_->smith->G1(i), 1e-7f);
                g = 1.f / (1.f / g1o + 1.f / g1i - 1.f) / std::max(o.z, 1e-7f);
            } else {
                g = i.z;
            }
            w = F * (g * oh / std::max(m.z, 1e-7f)) / ps;
        } else {
            const float r = std::sqrt(u1), phi = 2.f * kPi * u2;
            i = vec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.f, 1.f - u1)));
            if (!(i.z > 0.f)) return vec3(0.f);
            w = kd / (1.f - ps);
        }
        const vec3 wi_l = i.x * b.t + i.y * b.b + i.z * b.m;
        if (!(wi_l.z > 0.f) || !(wo_l.z > 0.f)) return vec3(0.f);  // below the macro-surface: shade_facet's zero
        wi = glm::normalize(fr.to_world(wi_l));
        return w;
    }

private:
    // The footprint and the light a pilot is for: the camera's hit (the same bits for every sample of
    // a pixel), wo and wi.
    struct PilotKey {
        std::array<float, 18> v{};
        bool operator==(const PilotKey&) const = default;
    };
    struct PilotKeyHash {
        static size_t hash(const PilotKey& k) {
            uint64_t z = 0x9e3779b97f4a7c15ull;
            for (float f : k.v) {
                uint32_t b;
                std::memcpy(&b, &f, sizeof b);
                z = (z ^ b) * 0xbf58476d1ce4e5b9ull;
                z ^= z >> 29;
            }
            return size_t(z);
        }
        static bool equal(const PilotKey& a, const PilotKey& b) { return a == b; }
    };

    // The strata (n.x, n.y) of the footprint for the light from wi: a deterministic function of the
    // footprint, wo and wi (so a pixel's samples, at any thread count, all use the same), computed by
    // the pilot once per footprint and light and kept.
    ivec2 strata(const TruthHit& h, vec3 wo, vec3 wi) const {
        PilotKey key;
        const vec3 parts[] = {h.n, h.tangent, wo, wi};
        const vec2 uvs[] = {h.uv, h.duv_dx, h.duv_dy};
        size_t c = 0;
        for (const vec2& u : uvs) key.v[c++] = u.x, key.v[c++] = u.y;
        for (const vec3& w : parts) key.v[c++] = w.x, key.v[c++] = w.y, key.v[c++] = w.z;
        {
            Pilots::const_accessor a;
            if (pilots_.find(a, key)) return a->second;
        }
        // The pilot: fcos at the centres of a kPilot x kPilot grid over the footprint; its spread
        // (standard deviation of the luminance, per unit irradiance) sets the number of points.
        TruthHit q = h;
        double s1 = 0.0, s2 = 0.0;
        for (int j = 0; j < kPilot; ++j)
            for (int i = 0; i < kPilot; ++i) {
                q.jitter = vec2((float(i) + 0.5f) / float(kPilot), (float(j) + 0.5f) / float(kPilot));
                const double v = luminance(fcos(q, wo, wi));
                s1 += v, s2 += v * v;
            }
        const double m = s1 / double(kPilot * kPilot), spread = std::sqrt(std::max(0.0, s2 / double(kPilot * kPilot) - m * m));
        const int points = int(std::clamp(std::ceil(spread / kSpreadPerPoint), 1.0, double(kMaxPoints)));
        // The grid's shape follows the footprint's: more strata along its longer side.
        const float lx = glm::length(h.duv_dx), ly = glm::length(h.duv_dy);
        const int nx = std::clamp(int(std::lround(std::sqrt(double(points) * lx / std::max(ly, 1e-30f)))), 1, points);
        const ivec2 n(nx, (points + nx - 1) / nx);
        pilots_.insert({key, n});
        return n;
    }

    // The pilot's grid (kPilot² points), the spread of fcos (sr⁻¹) one point of the estimate stands
    // for, and the most points per footprint and light (see the file's head).
    static constexpr int kPilot = 8;
    static constexpr double kSpreadPerPoint = 0.01;
    static constexpr int kMaxPoints = 256;
    using Pilots = tbb::concurrent_hash_map<PilotKey, ivec2, PilotKeyHash>;
    mutable Pilots pilots_;
    bool plain_ = false;
    std::shared_ptr<const TruthNdf> t_;
    std::shared_ptr<const NoiseCdfs> cdfs_;
    IndexDetail detail_;
    int K_;
    ShadingModel model_;
    std::shared_ptr<const Image> albedo_;
};
}  // namespace

vec3 truth_bump_normal(const TruthNdf& t, const NoiseCdfs* cdfs, const IndexDetail& detail, vec2 uv, int K) {
    const vec2 u = t.index_map ? index_inputs(*t.index_map, detail, uv, K) : noise_inputs(*cdfs, uv, K);
    return t.lut.sample_uniform(double(u.x), double(u.y));
}

IndexDetail truth_index_detail(const TruthNdf& t, const ParamTable& m) {
    return t.index_map ? index_detail(*t.index_map, noise_from_material(m), float(m.get_float("index_noise"))) : IndexDetail{};
}

TruthObject truth_object(const Scene& s, const Evaluation& ev, int object) {
    const SceneObject& o = s.objects.at(size_t(object));
    const ParamTable& m = o.material;
    auto t = ev.get(stages::truth_ndf, object);
    const IndexDetail detail = t ? truth_index_detail(*t, m) : IndexDetail{};
    TruthObject ob;
    ob.mesh = drawn_mesh(s, ev, object);
    ob.to_world = object_to_world(o);
    ob.material = std::make_shared<BumpsynthTruthMaterial>(std::move(t), index_mode(o) ? nullptr : ev.get(stages::noise_cdf, object), detail,
                                                           int(m.get_int("octaves_max")), shading_from_material(m), ev.get(stages::albedo, object),
                                                           std::getenv("MESOLAB_TRUTH_PLAIN") != nullptr);
    return ob;
}

std::optional<TruthDecl> BumpsynthTechnique::truth() const {
    return TruthDecl{.params = keys({"octaves_max", "noise_frequency", "noise_gain", "noise_seed", "index_noise", "ks", "kd", "fresnel", "masking"}),
                     .stages = {stages::truth_ndf, stages::noise_cdf, stages::albedo},
                     .object = truth_object};
}
}  // namespace mesolab::bumpsynth
