// Method horizon of technique microgeom: horizon mapping with GTAO's multi-bounce ambient
// visibility (see horizon.h). Its keys, its stage, the map, and its CPU shading; the GPU pass is
// gpu/microgeom/horizon_pass.cpp with horizon.frag.
#include "core/microgeom/horizon.h"
#include "core/error.h"
#include "core/microgeom/microgeom.h"
#include "core/microgeom/stages.h"
#include "core/parallel.h"
#include "core/render.h"
#include "core/technique.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

namespace mesolab::microgeom {

// [SECTION] The map
HorizonMap make_horizon_map(const PomField& f, int directions, int radius) {
    if (directions < 1) throw InputError("microgeom.horizon_directions: expected at least 1, got " + std::to_string(directions));
    if (radius < 1) throw InputError("microgeom.horizon_radius: expected at least 1, got " + std::to_string(radius));
    HorizonMap m;
    m.width = f.width, m.height = f.height, m.directions = directions;
    m.sin_theta.assign(size_t(directions) * size_t(f.width) * size_t(f.height), 0.f);
    mesolab::parallel_for(0, directions * f.height, [&](int jy) {
        const int j = jy / f.height, y = jy % f.height;
        const double phi = 2.0 * std::numbers::pi * double(j) / double(directions);
        // Snap the axis and diagonal directions' components so their samples land on texel centres.
        const auto snap = [](double v) { return std::fabs(v) < 1e-12 ? 0.0 : v; };
        const double dx = snap(std::cos(phi)), dy = snap(std::sin(phi));
        const double scale = std::max(std::fabs(dx), std::fabs(dy));
        // Along an axis or a diagonal, step to the next texel centre: t counts those steps' length.
        const bool on_grid = std::fabs(std::fabs(dx) - std::fabs(dy)) < 1e-9 || std::fabs(dx) < 1e-9 || std::fabs(dy) < 1e-9;
        const double sx = on_grid ? std::round(dx / scale) : dx, sy = on_grid ? std::round(dy / scale) : dy;
        const double step = std::sqrt(sx * sx + sy * sy);
        for (int x = 0; x < f.width; ++x) {
            const float z0 = f.z[size_t(y) * size_t(f.width) + size_t(x)];
            double best = -1e30;
            int k = 1;
            for (; k * step <= double(radius) + 1e-9; ++k) {
                const float c = float(x + k * sx), r = float(y - k * sy);  // +y in the tangent frame is -r
                best = std::max(best, (double(f.at(c, r)) - double(z0)) / (double(k) * step));
            }
            // The search's end, where it falls between two samples (a diagonal's last part step).
            if ((k - 1) * step < double(radius) - 1e-9) {
                const double t = double(radius) / step;
                best = std::max(best, (double(f.at(float(x + t * sx), float(y - t * sy))) - double(z0)) / double(radius));
            }
            if (best < -1e29) best = 0.0;  // R below one step: nothing is searched
            m.sin_theta[(size_t(j) * size_t(f.height) + size_t(y)) * size_t(f.width) + size_t(x)] = float(best / std::sqrt(1.0 + best * best));
        }
    });
    return m;
}

float HorizonMap::sin_horizon(float c, float r, float phi) const {
    const float a = phi / (2.f * kPi) * float(directions);
    const float af = std::floor(a);
    const float t = a - af;
    const int j0 = ((int(af) % directions) + directions) % directions, j1 = (j0 + 1) % directions;
    const float cf = std::floor(c), rf = std::floor(r), fc = c - cf, fr = r - rf;
    const int x0 = ((int(cf) % width) + width) % width, x1 = (x0 + 1) % width;
    const int y0 = ((int(rf) % height) + height) % height, y1 = (y0 + 1) % height;
    const auto bil = [&](int j) {
        const float top = at(j, x0, y0) + fc * (at(j, x1, y0) - at(j, x0, y0));
        const float bot = at(j, x0, y1) + fc * (at(j, x1, y1) - at(j, x0, y1));
        return top + fr * (bot - top);
    };
    const float h0 = bil(j0), h1 = bil(j1);
    return h0 + t * (h1 - h0);
}

float HorizonMap::ambient(float c, float r) const {
    const float cf = std::floor(c), rf = std::floor(r), fc = c - cf, fr = r - rf;
    const int x0 = ((int(cf) % width) + width) % width, x1 = (x0 + 1) % width;
    const int y0 = ((int(rf) % height) + height) % height, y1 = (y0 + 1) % height;
    const auto occ = [&](int x, int y) {
        float s = 0.f;
        for (int j = 0; j < directions; ++j) {
            const float v = std::max(0.f, at(j, x, y));
            s += v * v;
        }
        return 1.f - s / float(directions);
    };
    const float top = occ(x0, y0) + fc * (occ(x1, y0) - occ(x0, y0));
    const float bot = occ(x0, y1) + fc * (occ(x1, y1) - occ(x0, y1));
    return top + fr * (bot - top);
}

namespace {

// [SECTION] The method
class HorizonMethod final : public Method {
public:
    HorizonMethod()
        : Method("microgeom", "horizon", "Horizon mapping (Max 1988; Sloan and Cohen 2000) with GTAO's multi-bounce ambient visibility (Jimenez et al. 2016)") {}

    void declare_params(ParamGroup& p) const override {
        p.add_int("horizon_directions", 16).used_when("method", {"horizon"}).range(1, 64).more_accurate(Accuracy::Higher, int64_t(64))
            .doc("Horizon mapping: azimuths whose horizon angle each texel keeps (interpolated linearly between them)");
        p.add_int("horizon_radius", 32).used_when("method", {"horizon"}).range(1, 1024).log().in("texels").more_accurate(Accuracy::Higher, int64_t(256))
            .doc("How far from each texel the horizon is searched, in texels (one sample per texel along the direction)");
        p.section("Horizon mapping", {"horizon_directions", "horizon_radius"});
    }

    void declare_stages(StageGraph& g) const override {
        g.add(stages::horizon_map, {.help = "Find each texel's horizon angle in every direction (horizon mapping)",
                                    .scope = StageScope::Object,
                                    .technique = "microgeom",
                                    .params = {"microgeom.horizon_directions", "microgeom.horizon_radius"},
                                    .inputs = {stages::pom_field},
                                    .memory = [](const StageContext& ctx) {
                                        const double n = double(ctx.material().get_int("horizon_directions"));
                                        const auto f = ctx.input(stages::pom_field);
                                        const double texels = f ? double(f->width) * double(f->height) : 0.0;
                                        return MemoryEstimate{n * texels * sizeof(float), "horizon map: " + std::to_string(int(n)) + " angles per texel",
                                                              {"microgeom.horizon_directions", "microgeom.resolution"}};
                                    },
                                    .run = [](StageContext& ctx) {
                                        const ParamTable& m = ctx.material();
                                        return stage_result(stages::horizon_map, make_horizon_map(*ctx.input(stages::pom_field), int(m.get_int("horizon_directions")),
                                                                                                  int(m.get_int("horizon_radius"))));
                                    }});
    }

    std::vector<StageName> frame_stages() const override { return {stages::heightfield, stages::horizon_map}; }

    void shade_cpu(const ShadeContext& ctx) const override;

    // Both paths read the same map with the same weights; what differs is float evaluation (atan2,
    // the frame), which can move a light across a texel's horizon where the two nearly coincide:
    // there a pixel is lit on one path and shadowed on the other.
    FrameAgreement agreement() const override {
        return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.995, .interior_max = 2e-3, .interior_outliers = 2e-3,
                .why = "float evaluation; a light grazing a texel's horizon is a discrete choice"};
    }
};

struct HorizonObject {
    std::shared_ptr<const Heightfield> hf;
    std::shared_ptr<const HorizonMap> map;
    FieldMaterial mat;
};

void HorizonMethod::shade_cpu(const ShadeContext& ctx) const {
    std::map<int, HorizonObject> objects;
    for (int i : ctx.objects) {
        const ParamTable& m = ctx.scene.objects[size_t(i)].material;
        HorizonObject o;
        o.hf = ctx.eval.get(stages::heightfield, i);
        o.map = ctx.eval.get(stages::horizon_map, i);
        if (!o.hf || !o.map) throw std::logic_error("microgeom/horizon: the frame's stages were not evaluated for object " + std::to_string(i));
        o.mat = FieldMaterial::from(m, ctx.camera.texture_mode);
        objects.emplace(i, std::move(o));
    }
    const GBuffer& gb = ctx.gbuffer;
    const AovWriter& out = ctx.out;
    const int direct_out = out.index("direct"), indirect_out = out.index("indirect"), shadow_out = out.index("shadow"), folded_out = out.index("folded");
    mesolab::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const HorizonObject& o = objects.at(gb.object[px]);
            const Heightfield& hf = *o.hf;
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec2 uv = gb.uv[px];
            const float c = uv.x * float(hf.width) * o.mat.tiling - 0.5f, r = (1.f - uv.y) * float(hf.height) * o.mat.tiling - 0.5f;

            // The heightfield's normal and albedo at the base point, bilinear (as the bump level).
            const FieldSample fs = sample_field(hf, c, r);
            const vec3 n_loc = fs.n_loc, albedo = fs.albedo;
            const vec3 n = glm::normalize(frame.T * n_loc.x + frame.B * n_loc.y + frame.N * n_loc.z);

            vec3 direct(0.f);
            float shadow0 = 0.f;
            for (size_t li = 0; li < ctx.lighting.lights.size(); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                const float cos_i = glm::dot(n, wi);
                const vec3 l = glm::normalize(frame.to_local(wi));
                float V = 0.f;
                if (cos_i > 0.f && l.z > 0.f) {
                    float phi = std::atan2(l.y, l.x);
                    if (phi < 0.f) phi += 2.f * kPi;
                    V = l.z > o.map->sin_horizon(c, r, phi) ? 1.f : 0.f;
                }
                if (li == 0) shadow0 = V;
                if (cos_i <= 0.f || V <= 0.f) continue;
                const vec3 f = micro_brdf(albedo, n, wo, wi, o.mat.phong, o.mat.ks, o.mat.shininess);
                direct += f * E * cos_i;
            }
            vec3 env(0.f);
            if (ctx.lighting.env_lighting) {
                const float A = o.map->ambient(c, r);
                const vec3 A3(gtao_multibounce(A, albedo.x), gtao_multibounce(A, albedo.y), gtao_multibounce(A, albedo.z));
                env = albedo * kInvPi * ctx.lighting.env_irradiance(n) * A3;
            }
            out.put(AovWriter::kRadiance, x, y, direct + env);
            out.put(AovWriter::kNormal, x, y, n);
            out.put(direct_out, x, y, direct);
            out.put(indirect_out, x, y, env);
            out.put(shadow_out, x, y, shadow0);
            out.put(folded_out, x, y, 0.f);
        }
    });
}
}  // namespace
}  // namespace mesolab::microgeom

namespace mesolab {
void register_microgeom_horizon(Registry& r) { r.add_method(std::make_unique<microgeom::HorizonMethod>()); }
}  // namespace mesolab
