#include "core/basic/basic.h"
#include "core/basic/stages.h"
#include "core/scene_stages.h"
#include "core/error.h"
#include "core/render.h"
#include "core/technique.h"

#include <tbb/parallel_for.h>
#include <map>

namespace mesolab::basic {

Material Material::from(const ParamTable& t, const std::string& resolved_map) {
    Material m;
    m.kd = t.get_vec3("kd");
    m.ks = t.get_vec3("ks");
    m.shininess = float(t.get_float("shininess"));
    m.albedo_map = resolved_map;
    return m;
}

// [SECTION] BRDF
vec3 brdf(const Material& m, vec3 n, vec3 wo, vec3 wi, vec3 albedo_tex) {
    const vec3 h = glm::normalize(wo + wi);
    const float nh = std::max(0.f, glm::dot(n, h));
    const float spec = (m.shininess + 8.f) / (8.f * kPi) * std::pow(nh, m.shininess);
    return m.kd * albedo_tex * kInvPi + m.ks * spec;
}

vec3 sample_albedo(const Image& img, vec2 uv) {
    if (img.empty()) return vec3(1.f);
    const float fx = uv.x * float(img.width) - 0.5f, fy = (1.f - uv.y) * float(img.height) - 0.5f;
    const float x0f = std::floor(fx), y0f = std::floor(fy);
    const float ax = fx - x0f, ay = fy - y0f;
    auto wrap = [](int i, int n) { return ((i % n) + n) % n; };
    const int x0 = wrap(int(x0f), img.width), x1 = wrap(int(x0f) + 1, img.width);
    const int y0 = wrap(int(y0f), img.height), y1 = wrap(int(y0f) + 1, img.height);
    auto texel = [&](int x, int y) {
        const float* p = img.at(x, y);
        return img.channels >= 3 ? vec3(p[0], p[1], p[2]) : vec3(p[0]);
    };
    return glm::mix(glm::mix(texel(x0, y0), texel(x1, y0), ax), glm::mix(texel(x0, y1), texel(x1, y1), ax), ay);
}

std::optional<Image> read_albedo_map(const Scene& s, const ParamTable& material) {
    const std::string path = s.resolve(material.get_string("albedo_map"));
    if (path.empty()) return std::nullopt;
    return read_image(path, true, true);
}

namespace {

class BasicTechnique final : public Technique {
public:
    // The same arithmetic on both paths; float evaluation order and the GPU's pow and normalize
    // leave differences of about 1e-5 of the radiance. Only silhouettes, where a pixel centre
    // lies within sub-pixel rounding of an edge, can differ by a whole value.
    FrameAgreement agreement() const override {
        return {.tight = 1e-4, .frac_tight = 0.99, .loose = 1e-3, .frac_loose = 0.998, .interior_max = 1e-3, .interior_outliers = 0,
                .why = "float evaluation order and the GPU's transcendentals; silhouettes"};
    }
    BasicTechnique() : Technique("basic", "Basic (Lambert + Blinn-Phong)") {
        params_.add_color("kd", {0.8, 0.8, 0.8}).doc("Diffuse albedo (linear RGB)");
        params_.add_color("ks", {0.04, 0.04, 0.04}).doc("Specular albedo (linear RGB) of the normalised Blinn-Phong lobe");
        params_.add_float("shininess", 64.0).range(1.0, 10000.0).log().doc("Blinn-Phong exponent s");
        params_.add_path("albedo_map", "")
            .doc("Image multiplying kd, looked up at the surface's (u,v) (8-bit images are sRGB); relative to the preset's folder");
    }

    void declare_stages(StageGraph& g) const override {
        // Albedo textures: read once, reused until the file or the path changes.
        g.add(stages::albedo, {
               .help = "Read the object's albedo map",
               .scope = StageScope::Object,
               .technique = "basic",
               .params = {"basic.albedo_map"},
               .run = [](StageContext& ctx) -> std::any {
                   auto img = read_albedo_map(ctx.scene, ctx.material());
                   return img ? stage_result(stages::albedo, std::move(*img)) : std::any();
               }});
    }

    std::vector<StageName> frame_stages() const override { return {stages::albedo}; }

    // Our own table (no paper behind this technique): tessellation and frame times.
    std::vector<BenchTable> bench_tables() const override {
        auto scene = [](const char* type, int res) {
            return [=] {
                Scene s = default_scene("basic");
                s.name = std::string(type) + std::to_string(res);
                s.objects[0].geometry.set("type", std::string(type));
                s.objects[0].geometry.set("resolution", int64_t(res));
                return s;
            };
        };
        BenchTable t;
        t.name = "basic";
        t.title = "basic: tessellation and frame time (no paper figures: this technique carries the pipeline)";
        t.columns = {{"tessellate", mesolab::stages::geometry},
                     {"frame 512x512", {}, 512, 512, true, true},
                     {"frame 1280x720", {}, 1280, 720, true, true}};
        t.rows = {{"sphere 64", scene("sphere", 64), {}},
                  {"sphere 512", scene("sphere", 512), {}},
                  {"torus 256", scene("torus", 256), {}}};
        return {t};
    }

    void shade_cpu(const ShadeContext& ctx) const override {
        const GBuffer& gb = ctx.gbuffer;
        // Materials parsed once per frame; albedo maps by object.
        std::map<int, std::pair<Material, std::shared_ptr<const Image>>> mats;
        for (int i : ctx.objects) {
            const auto& o = ctx.scene.objects[size_t(i)];
            mats[i] = {Material::from(o.material, ctx.scene.resolve(o.material.get_string("albedo_map"))), ctx.eval.get(stages::albedo, i)};
        }
        tbb::parallel_for(0, gb.height, [&](int y) {
            for (int x = 0; x < gb.width; ++x) {
                const size_t px = gb.index(x, y);
                if (!ctx.mine(px)) continue;
                const auto& [m, map] = mats.at(gb.object[px]);
                const vec3 p = gb.position[px];
                const vec3 wo = ctx.camera.wo(p);
                vec3 n = gb.normal[px];
                if (glm::dot(n, wo) < 0.f) n = -n;  // two-sided
                vec3 tex(1.f);
                if (map) tex = sample_albedo(*map, gb.uv[px]);
                vec3 L(0.f);
                for (const Light& l : ctx.lighting.lights) {
                    vec3 wi, E;
                    l.sample(p, wi, E);
                    const float cos_i = glm::dot(n, wi);
                    if (cos_i <= 0.f) continue;
                    L += brdf(m, n, wo, wi, tex) * E * cos_i;
                }
                L += m.kd * tex * kInvPi * ctx.lighting.env_irradiance(n);
                ctx.out.put(AovWriter::kRadiance, x, y, L);
                ctx.out.put(AovWriter::kNormal, x, y, n);
            }
        });
    }
};
}  // namespace
}  // namespace mesolab::basic

namespace mesolab {
void register_basic(Registry& r) { r.add(std::make_unique<basic::BasicTechnique>()); }
}  // namespace mesolab
