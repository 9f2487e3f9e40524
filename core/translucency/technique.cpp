// Technique translucency: parameters, stages, frame steps and CPU shading (see translucency.h).
#include "core/error.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/technique.h"
#include "core/translucency/reference.h"
#include "core/translucency/paper.h"
#include "core/translucency/technique.h"
#include "core/translucency/translucency.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <map>

namespace mesolab::translucency {

// [SECTION] Settings
Settings Settings::from(const SceneObject& o, unsigned parts) {
    const ParamTable& t = o.material;
    Settings s;
    if (parts & Medium_) {
        s.material = t.get_string("material");
        if (s.material == "custom") {
            const vec3 ss = t.get_vec3("sigma_s"), sa = t.get_vec3("sigma_a");
            s.medium = Medium{dvec3(ss), dvec3(sa), t.get_float("eta")};
        } else {
            s.medium = measured_material(s.material).medium;
        }
        validate(s.medium);
    }
    if (parts & Scale) s.mm_per_unit = t.get_float("mm_per_unit") * o.geometry.get_float("scale");
    if (parts & Mesh) s.vertices = int(t.get_int("vertices"));
    if (parts & AtlasPart) {
        s.atlas_size = int(t.get_int("atlas_size"));
        s.kernel = int(t.get_int("kernel"));
        s.chunk_angle = float(t.get_float("chunk_angle"));
    }
    if (parts & Factors) {
        s.threshold = float(t.get_float("threshold"));
        s.blend = t.get_bool("blend");
    }
    if (parts & Frame) {
        s.shadows = t.get_bool("shadows");
        s.shadow_map = int(t.get_int("shadow_map"));
        s.compare = t.get_bool("compare");
        const std::string& r = t.get_string("response");
        s.response = r == "local" ? Response::Local : r == "global" ? Response::Global : r == "reference" ? Response::Reference : Response::Both;
    }
    if (parts & Rho) {
        s.albedo_map = t.get_string("albedo_map");
        s.veins = float(t.get_float("veins"));
        s.vein_color = t.get_vec3("vein_color");
        s.vein_scale = t.get_float("vein_scale");
    }
    return s;
}

namespace {

AtlasParams atlas_params(const Settings& s) { return {s.atlas_size, (s.kernel - 1) / 2 + 1, s.chunk_angle}; }

// [SECTION] Memory estimates
// Factors above the threshold: the radius where R_d A/3 falls below it, and the share of vertex
// pairs within it, counted from up to 256 vertices.
MemoryEstimate factor_memory(const PreparedMesh& m, const Settings& s) {
    const size_t n = m.vertex_count();
    MemoryEstimate e;
    e.lower = {"translucency.threshold", "translucency.vertices"};
    if (n == 0) return e;
    double area = 0.0;
    for (size_t f = 0; f < m.triangle_count(); ++f)
        area += 0.5 * double(glm::length(glm::cross(m.position[m.index[3 * f + 1]] - m.position[m.index[3 * f]],
                                                    m.position[m.index[3 * f + 2]] - m.position[m.index[3 * f]])));
    const double mean_area = 3.0 * area * s.mm_per_unit * s.mm_per_unit / double(n);  // A_j, mm²
    const Dipole d(s.medium);
    auto factor = [&](double r) {
        const dvec3 v = d.Rd(r);
        return std::max({v.x, v.y, v.z}) * mean_area / 3.0;
    };
    double lo = 0.0, hi = 1.0;
    while (factor(hi) >= double(s.threshold) && hi < 1e7) hi *= 2.0;
    for (int i = 0; i < 40; ++i) (factor(0.5 * (lo + hi)) >= double(s.threshold) ? lo : hi) = 0.5 * (lo + hi);
    const float r_unit = float(hi / s.mm_per_unit), r2 = r_unit * r_unit;
    const size_t samples = std::min<size_t>(256, n);
    size_t within = 0;
    for (size_t k = 0; k < samples; ++k) {
        const vec3 p = m.position[k * n / samples];
        for (const vec3& q : m.position) within += glm::dot(q - p, q - p) <= r2 ? 1 : 0;
    }
    const double count = double(within) / double(samples) * double(n);
    // Each kept pair: 8 bytes in a row's buffer while building, 8 in the final array.
    e.bytes = count * 0.5 * (n > 65536 ? 20.0 : 16.0) + double(n + 1) * 4.0;
    e.what = "about " + std::to_string(int64_t(count)) + " vertex-to-vertex factors (" + std::to_string(n) +
             " vertices, translucency.threshold = " + std::to_string(s.threshold) + "), a symmetric pair of them in 8 bytes, twice while building";
    return e;
}

// [SECTION] The technique
class TranslucencyTechnique final : public Technique {
public:
    TranslucencyTechnique() : Technique("translucency", "Translucency (Lensch et al. 2002)") {
        std::vector<std::string> names;
        for (const auto& m : measured_materials()) names.push_back(m.name);
        names.push_back("custom");
        const MeasuredMaterial& marble = measured_material("marble");
        auto& p = params_;
        p.add_enum("material", names, "marble")
            .doc("One of Jensen et al. 2001's measured materials, or custom (sigma_s, sigma_a, eta)");
        p.add_vec3("sigma_s", {marble.medium.sigma_s.x, marble.medium.sigma_s.y, marble.medium.sigma_s.z}).range(0.0, 1e4).in("1/mm").used_when("material", {"custom"}).doc("Reduced scattering coefficient sigma'_s, RGB");
        p.add_vec3("sigma_a", {marble.medium.sigma_a.x, marble.medium.sigma_a.y, marble.medium.sigma_a.z}).range(0.0, 1e4).in("1/mm").used_when("material", {"custom"}).doc("Absorption coefficient sigma_a, RGB");
        p.add_float("eta", 1.5).range(1.0, 3.0).used_when("material", {"custom"}).doc("Relative index of refraction");
        p.add_float("mm_per_unit", 20.0).range(1e-4, 1e7).log().in("mm")
            .doc("Millimetres per scene unit: the object's size decides how translucent it looks");
        p.add_int("vertices", 10000).range(0, 2000000).more_accurate(Accuracy::Higher)
            .doc("Vertices after simplification (OpenMesh's decimater; 0 keeps every vertex): one hat basis function per vertex");
        p.add_int("atlas_size", 512).range(128, 2048).more_accurate(Accuracy::Higher, int64_t(2048))
            .doc("Texels per side of the texture atlas (local response, illumination map)");
        p.add_float("chunk_angle", 30.0).range(1.0, 89.0).in("degrees")
            .doc("Largest deviation of a triangle's normal from its chunk's average normal");
        p.add_int("kernel", 7).range(3, 15).more_accurate(Accuracy::Higher, int64_t(15))
            .doc("Local kernel size K (odd): K x K texels around each texel");
        p.add_float("threshold", 3e-5).range(0.0, 1.0).more_accurate(Accuracy::Lower, 0.0)
            .doc("Smallest vertex-to-vertex factor kept (largest channel); fewer factors, faster global response");
        p.add_bool("blend", true).doc("Blend local and global responses (§5.4); off shows the double counting of Fig. 6");
        p.add_enum("response", {"both", "local", "global", "reference"}, "both")
            .doc("What the image shows: local + global, one of them, or the brute-force reference");
        p.add_bool("compare", false)
            .doc("Also compute the brute-force reference each frame (the reference and error AOVs): seconds per light move on large meshes");
        p.add_bool("shadows", true).doc("Self-shadowing of the illumination map (a shadow map per light)");
        p.add_int("shadow_map", 512).range(64, 8192).used_when("shadows", {"true"}).doc("Shadow map texels per side");
        p.add_path("albedo_map", "")
            .doc("Surface texture rho multiplying the outgoing radiosity, at the mesh's (u,v); relative to the preset's folder");
        p.add_float("veins", 0.0).range(0.0, 1.0).doc("Strength of procedural fractal veins in rho (0 = none)");
        p.add_float("vein_scale", 10.0).range(0.01, 1e5).log().in("mm").doc("Vein period (used when veins > 0)");
        p.add_color("vein_color", {0.35, 0.3, 0.28}).doc("rho inside a vein");
        aovs_ = {{"irradiance", 3, "Power per unit area entering the medium: incident irradiance x Fresnel transmittance"},
                 {"radiosity", 3, "B: power per unit area leaving through subsurface transport, before the outgoing Fresnel term (local + global)"},
                 {"local", 3, "The local (kernel) part of B"},
                 {"global", 3, "The global (vertex factor) part of B"},
                 {"reference", 3, "B by brute-force summation (translucency.compare or response = reference; else 0)"},
                 {"error", 3, "radiosity - reference (0 without a reference)"}};
    }

    void declare_stages(StageGraph& g) const override;
    std::vector<StageName> frame_stages() const override {
        return {stages::mesh, stages::atlas, stages::kernels, stages::factors, stages::blend, stages::gather, stages::albedo};
    }
    std::vector<FrameStepDecl> frame_steps() const override;
    void shade_cpu(const ShadeContext& ctx) const override;
    std::optional<ivec2> texture_size(const Scene& s, const Evaluation& ev) const override {
        for (size_t i = 0; i < s.objects.size(); ++i)
            if (const auto a = ev.get(stages::atlas, int(i))) return ivec2(a->atlas.size);
        return std::nullopt;
    }
    std::shared_ptr<const TriMesh> object_mesh(const Scene&, const Evaluation& ev, int object) const override {
        const auto a = ev.get(stages::atlas, object);
        return a ? a->display : nullptr;
    }
    std::vector<BenchTable> bench_tables() const override { return translucency_bench_tables(); }
    // The maps are sums of many float products (kernels, factors), which agree to about 1e-4 of the
    // radiosity; shadow-map depth tests on the terminator and the bilinear look-up of the atlas
    // between charts are discrete.
    FrameAgreement agreement() const override {
        return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.998, .interior_max = 5e-3, .interior_outliers = 5e-4,
                .why = "summation order of the kernels and factors; shadow-map texels on the terminator"};
    }
    std::vector<SweepMetricDecl> sweep_metrics() const override;
};

// [SECTION] Stages
const std::vector<std::string> kMaterialKeys = {"translucency.material", "translucency.sigma_s", "translucency.sigma_a", "translucency.eta",
                                                "translucency.mm_per_unit", "geometry.scale"};
std::vector<std::string> with_material(std::vector<std::string> keys) {
    keys.insert(keys.end(), kMaterialKeys.begin(), kMaterialKeys.end());
    return keys;
}

void TranslucencyTechnique::declare_stages(StageGraph& g) const {
    g.add(stages::mesh, {.help = "Weld, clean and simplify the object's mesh (OpenMesh decimater) to translucency.vertices",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = {"translucency.vertices"},
           .inputs = {mesolab::stages::geometry},
           .memory = [](const StageContext& ctx) {
               const auto m = ctx.input(mesolab::stages::geometry);
               return MemoryEstimate{double(m ? m->vertex_count() : 0) * 400.0, "mesh preparation: about 400 bytes per input vertex", {}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const auto m = ctx.input(mesolab::stages::geometry);
               PreparedMesh p = prepare_mesh(m->position, m->index, int(ctx.material().get_int("vertices")), m->has_uv ? &m->uv : nullptr);
               for (const auto& w : p.warnings) ctx.warn(w);
               return stage_result(stages::mesh, std::move(p));
           }});
    g.add(stages::atlas, {.help = "Texture atlas (§5.1): chunks, projection, minimum-area rectangles, packing, borders",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = {"translucency.atlas_size", "translucency.chunk_angle", "translucency.kernel"},
           .inputs = {stages::mesh},
           .memory = [](const StageContext& ctx) {
               const double n = double(ctx.material().get_int("atlas_size"));
               return MemoryEstimate{n * n * 70.0, "atlas: " + std::to_string(int(n)) + "² texels x about 70 bytes", {"translucency.atlas_size"}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.obj(), Settings::AtlasPart);
               AtlasStage a = make_atlas_stage(*ctx.input(stages::mesh), atlas_params(s));
               for (const auto& w : a.atlas.warnings) ctx.warn(w);
               return stage_result(stages::atlas, std::move(a));
           }});
    g.add(stages::kernels, {.help = "Local K x K kernels per texel from R_d (§5.3)",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = with_material({"translucency.kernel"}),
           .inputs = {stages::mesh, stages::atlas},
           .paper = PaperFigure{paper::kKernelsMaxMs, "Lensch 2002, §6: kernels 1-2 min (dual Xeon 1.7 GHz)"},
           .memory = [](const StageContext& ctx) {
               const auto a = ctx.input(stages::atlas);
               const double K = double(ctx.material().get_int("kernel"));
               const double inner = a ? a->atlas.fill_ratio * double(a->atlas.size) * double(a->atlas.size) : 0.0;
               return MemoryEstimate{inner * K * K * 12.0, "kernels: " + std::to_string(int64_t(inner)) + " texels x K² x 3 channels x 4 bytes",
                                     {"translucency.kernel", "translucency.atlas_size"}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.obj(), Settings::Medium_ | Settings::Scale | Settings::AtlasPart);
               const auto m = ctx.input(stages::mesh);
               const auto a = ctx.input(stages::atlas);
               return stage_result(stages::kernels, build_local_kernels(a->atlas, m->position, m->index, Dipole(s.medium), s.mm_per_unit, s.kernel));
           }});
    g.add(stages::factors, {.help = "Vertex-to-vertex throughput factors above translucency.threshold (§5.2)",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = with_material({"translucency.threshold", "translucency.blend"}),
           .inputs = {stages::mesh},
           .paper = PaperFigure{paper::kFactorsMaxMs, "Lensch 2002, §6: form factors 2-8 min (dual Xeon 1.7 GHz)"},
           .memory = [](const StageContext& ctx) {
               return factor_memory(*ctx.input(stages::mesh), Settings::from(ctx.obj()));
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.obj(), Settings::Medium_ | Settings::Scale | Settings::Factors);
               const auto m = ctx.input(stages::mesh);
               VertexFactors F = build_vertex_factors(m->position, m->index, Dipole(s.medium), {s.mm_per_unit, s.threshold, s.blend});
               if (F.count() == 0 && m->vertex_count() > 1)
                   ctx.warn("translucency.threshold = " + std::to_string(s.threshold) + " drops every factor: the global response is zero");
               return stage_result(stages::factors, std::move(F));
           }});
    g.add(stages::blend, {.help = "Blending (§5.4): direct weights fitted by least squares, kernels corrected",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = {"translucency.blend"},
           .inputs = {stages::mesh, stages::atlas, stages::kernels, stages::factors},
           .applies = [](const Scene&, const SceneObject& o) { return o.material.get_bool("blend"); },
           .when_text = "translucency.blend is on",
           .memory = [](const StageContext& ctx) {
               const auto k = ctx.input(stages::kernels);
               return MemoryEstimate{double(k ? k->bytes() + k->texel.size() * 36 : 0), "a corrected copy of the kernels and 9 weights per texel",
                                     {"translucency.kernel", "translucency.atlas_size"}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.obj(), Settings::Medium_ | Settings::Scale);
               const auto m = ctx.input(stages::mesh);
               Blended b{*ctx.input(stages::kernels), {}};
               b.weights = fit_blending(ctx.input(stages::atlas)->atlas, m->position, m->index, Dipole(s.medium), s.mm_per_unit,
                                        *ctx.input(stages::factors), b.kernels);
               return stage_result(stages::blend, std::move(b));
           }});
    g.add(stages::gather, {.help = "Per vertex, the texels its irradiance (hat-weighted) and its direct radiosity (blending) come from",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = {"translucency.blend"},
           .inputs = {stages::mesh, stages::atlas, stages::factors, stages::blend},
           .memory = [](const StageContext& ctx) {
               const auto a = ctx.input(stages::atlas);
               const double inner = a ? a->atlas.fill_ratio * double(a->atlas.size) * double(a->atlas.size) : 0.0;
               return MemoryEstimate{inner * 3.0 * 20.0, "3 entries of 20 bytes per texel", {"translucency.atlas_size"}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.obj(), Settings::Scale);
               const auto m = ctx.input(stages::mesh);
               const auto b = ctx.input(stages::blend);
               return stage_result(stages::gather, make_gather(ctx.input(stages::atlas)->atlas, m->index,
                                               ctx.input(stages::factors)->vertex_area, s.mm_per_unit,
                                               b ? &b->weights : nullptr, b ? &b->kernels : nullptr));
           }});
    g.add(stages::albedo, {.help = "rho per texel: translucency.albedo_map and the procedural veins",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = {"translucency.albedo_map", "translucency.veins", "translucency.vein_scale", "translucency.vein_color", "translucency.mm_per_unit",
                      "geometry.scale"},
           .inputs = {stages::mesh, stages::atlas},
           .applies = [](const Scene&, const SceneObject& o) {
               return !o.material.get_string("albedo_map").empty() || o.material.get_float("veins") > 0.0;
           },
           .when_text = "translucency.albedo_map is set or translucency.veins > 0",
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.obj(), Settings::Rho | Settings::Scale);
               return stage_result(stages::albedo, texel_albedo(ctx.scene, s, *ctx.input(stages::mesh), *ctx.input(stages::atlas)));
           }});
}

// [SECTION] Frame steps
std::vector<std::string> step_keys(std::vector<std::string> extra) {
    std::vector<std::string> k = {"light.*", "env.*", "effects.*", "geometry.*", "translucency.shadows", "translucency.shadow_map"};
    k.insert(k.end(), kMaterialKeys.begin(), kMaterialKeys.end());
    k.insert(k.end(), extra.begin(), extra.end());
    return k;
}

std::vector<FrameStepDecl> TranslucencyTechnique::frame_steps() const {
    const std::vector<StageName> all = {stages::mesh, stages::atlas, stages::kernels, stages::factors, stages::blend, stages::gather};
    auto atlas = [](const FrameStepContext& ctx, int o) { return ctx.eval.get(stages::atlas, o); };
    return {
        frame_step(steps::illumination, "Irradiance entering the medium per texel (lights x Fresnel, shadow maps, environment)", step_keys({}),
                   {stages::atlas},
                   [atlas](const FrameStepContext& ctx) {
                       PerObject<std::vector<vec3>> out;
                       for (int o : ctx.objects) {
                           const SceneObject& obj = ctx.scene.objects[size_t(o)];
                           const Settings s = Settings::from(obj);
                           const auto a = atlas(ctx, o);
                           const mat4 model = object_to_world(obj);
                           std::vector<ShadowMap> shadows;
                           if (s.shadows) {
                               PROFILE_SCOPE("translucency.shadow_maps");
                               for (size_t i = 0; i < ctx.lighting.lights.size() && i < size_t(kMaxShadowMaps); ++i)
                                   shadows.push_back(make_shadow_map(*a->display, model, ctx.lighting.lights[i], s.shadow_map));
                           }
                           PROFILE_SCOPE("translucency.texels");
                           out[o] = illuminate(*a, model, ctx.lighting, s.medium.eta, shadows);
                       }
                       return out;
                   }),
        frame_step(steps::vertices, "Irradiance per vertex (hat-weighted) and the direct radiosity of blending", step_keys({}), all,
                   [](const FrameStepContext& ctx) {
                       const auto& E = ctx.step(steps::illumination);
                       PerObject<VertexValues> out;
                       for (int o : ctx.objects) out[o] = gather_vertices(*ctx.eval.get(stages::gather, o), E.at(o));
                       return out;
                   }),
        frame_step(steps::local, "Local response: K x K kernels over the illumination map", step_keys({}), all,
                   [](const FrameStepContext& ctx) {
                       const auto& E = ctx.step(steps::illumination);
                       PerObject<std::vector<vec3>> out;
                       for (int o : ctx.objects) {
                           const auto b = ctx.eval.get(stages::blend, o);
                           out[o] = convolve_local(b ? b->kernels : *ctx.eval.get(stages::kernels, o), E.at(o));
                       }
                       return out;
                   }),
        frame_step(steps::global, "Global response per vertex: the factors times the vertex irradiance, plus the direct part", step_keys({}), all,
                   [](const FrameStepContext& ctx) {
                       const auto& V = ctx.step(steps::vertices);
                       PerObject<std::vector<vec3>> out;
                       for (int o : ctx.objects) {
                           const VertexValues& v = V.at(o);
                           std::vector<vec3> B = ctx.eval.get(stages::factors, o)->multiply(v.E);
                           for (size_t i = 0; i < B.size(); ++i) B[i] += v.direct[i];
                           out[o] = std::move(B);
                       }
                       return out;
                   }),
        frame_step(steps::combine, "The global response interpolated to the texels, radiosity = local + global, texels outside the triangles filled",
                   step_keys({}), all,
                   [atlas](const FrameStepContext& ctx) {
                       const auto& E = ctx.step(steps::illumination);
                       const auto& Lo = ctx.step(steps::local);
                       const auto& Bv = ctx.step(steps::global);
                       PerObject<Maps> out;
                       for (int o : ctx.objects) out[o] = combine(*atlas(ctx, o), ctx.eval.get(stages::mesh, o)->index, E.at(o), Lo.at(o), Bv.at(o));
                       return out;
                   }),
        frame_step(steps::reference, "Brute-force radiosity (translucency.compare or response = reference)",
                   step_keys({"translucency.compare", "translucency.response"}), all,
                   [atlas](const FrameStepContext& ctx) {
                       const auto& E = ctx.step(steps::illumination);
                       PerObject<std::vector<vec3>> out;
                       for (int o : ctx.objects) {
                           const Settings s = Settings::from(ctx.scene.objects[size_t(o)]);
                           if (!s.needs_reference()) continue;
                           const auto a = atlas(ctx, o);
                           const auto m = ctx.eval.get(stages::mesh, o);
                           out[o] = fill_texels(*a, reference_radiosity(a->atlas, texel_positions_mm(a->atlas, m->position, m->index, s.mm_per_unit),
                                                                        Dipole(s.medium), s.mm_per_unit, E.at(o)));
                       }
                       return out;
                   })};
}

}  // namespace

// [SECTION] The method against the brute-force reference
double radiosity_error(const Scene& s, const Evaluation& ev, int o) {
    const SceneObject& obj = s.objects.at(size_t(o));
    const Settings st = Settings::from(obj);
    const auto a = ev.get(stages::atlas, o);
    const auto m = ev.get(stages::mesh, o);
    const auto g = ev.get(stages::gather, o);
    const auto F = ev.get(stages::factors, o);
    const auto b = ev.get(stages::blend, o);
    const auto K = ev.get(stages::kernels, o);
    if (!a || !m || !g || !F || !K) throw std::logic_error("translucency: the evaluation lacks the object's translucency stages");
    const Lighting L = make_lighting(s, ev);
    const mat4 model = object_to_world(obj);
    std::vector<ShadowMap> shadows;
    if (st.shadows)
        for (size_t i = 0; i < L.lights.size() && i < size_t(kMaxShadowMaps); ++i)
            shadows.push_back(make_shadow_map(*a->display, model, L.lights[i], st.shadow_map));
    const std::vector<vec3> E = illuminate(*a, model, L, st.medium.eta, shadows);
    const VertexValues v = gather_vertices(*g, E);
    std::vector<vec3> Bv = F->multiply(v.E);
    for (size_t i = 0; i < Bv.size(); ++i) Bv[i] += v.direct[i];
    const std::vector<vec3> local = convolve_local(b ? b->kernels : *K, E);
    const std::vector<vec3> global = interpolate_to_texels(a->atlas, m->index, Bv);
    const std::vector<vec3> ref =
        reference_radiosity(a->atlas, texel_positions_mm(a->atlas, m->position, m->index, st.mm_per_unit), Dipole(st.medium), st.mm_per_unit, E);
    double se = 0.0, sum = 0.0;
    size_t n = 0;
    for (size_t t = 0; t < E.size(); ++t) {
        if (a->atlas.texel_kind[t] != Atlas::kInner) continue;
        const vec3 d = local[t] + global[t] - ref[t];
        se += double(glm::dot(d, d)) / 3.0;
        sum += double(ref[t].x + ref[t].y + ref[t].z) / 3.0;
        ++n;
    }
    return n && sum > 0.0 ? std::sqrt(se / double(n)) / (sum / double(n)) : 0.0;
}

namespace {
// [SECTION] Sweep metric: the method against the brute-force reference
// For each setting, the first translucent object's radiosity (local + global, as the frame
// computes it) against the reference summed over the same atlas's texels, RMSE over the inner
// texels relative to the reference's mean (all three channels). The reference is the
// discretisation-independent part: texels are much smaller than a mean free path.
std::vector<SweepMetricDecl> TranslucencyTechnique::sweep_metrics() const {
    auto first = [](const Scene& s) {
        for (size_t i = 0; i < s.objects.size(); ++i)
            if (s.objects[i].technique == "translucency") return int(i);
        throw InputError("no object uses technique translucency (the metric translucency.reference measures the first one's radiosity)");
    };
    SweepMetricDecl m;
    m.name = "translucency.reference";
    m.label = "radiosity RMSE / mean vs brute force";
    m.unit = "fraction of the mean";
    m.help = "RMSE of the radiosity against the brute-force reference on the same atlas, over the mean of the reference";
    m.check = [first](const Scene& s) { first(s); };
    m.prepare = [first](const Scene&, const Evaluation&) {
        SweepMeasure out;
        out.error = [first](const Scene& s, const Evaluation& ev) { return radiosity_error(s, ev, first(s)); };
        out.notes = "Each setting against the brute-force sum over its own atlas (every lit texel to every texel, no kernel, no threshold).";
        return out;
    };
    return {m};
}

// [SECTION] Shading
void TranslucencyTechnique::shade_cpu(const ShadeContext& ctx) const {
    struct Obj {
        Settings s;
        const Maps* maps = nullptr;
        const std::vector<vec3>* reference = nullptr;
        std::shared_ptr<const std::vector<vec3>> rho;
        int size = 0;
    };
    const auto& maps = ctx.step(steps::combine);
    const auto& refs = ctx.step(steps::reference);
    std::vector<Obj> objs(ctx.scene.objects.size());  // by object id
    for (int o : ctx.objects) {
        Obj& b = objs[size_t(o)];
        b.s = Settings::from(ctx.scene.objects[size_t(o)]);
        b.maps = &maps.at(o);
        if (auto it = refs.find(o); it != refs.end()) b.reference = &it->second;
        b.rho = ctx.eval.get(stages::albedo, o);
        b.size = ctx.eval.get(stages::atlas, o)->atlas.size;
    }
    const int out_irr = ctx.out.index("irradiance"), out_rad = ctx.out.index("radiosity"), out_loc = ctx.out.index("local"),
              out_glo = ctx.out.index("global"), out_ref = ctx.out.index("reference"), out_err = ctx.out.index("error");
    // The parts only the displayed response or a requested AOV needs are looked up.
    const bool parts = ctx.out.wanted(out_rad) || ctx.out.wanted(out_loc) || ctx.out.wanted(out_glo) || ctx.out.wanted(out_ref) || ctx.out.wanted(out_err);
    const GBuffer& gb = ctx.gbuffer;
    tbb::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const Obj& b = objs[size_t(gb.object[px])];
            const TexelTap tap(b.size, gb.uv[px]);
            const vec3 wo = ctx.camera.wo(gb.position[px]);
            vec3 n = gb.normal[px];
            if (glm::dot(n, wo) < 0.f) n = -n;
            const Response r = b.s.response;
            const bool need_local = parts || r == Response::Both || r == Response::Local;
            const bool need_global = parts || r == Response::Both || r == Response::Global;
            const vec3 local = need_local ? tap(*b.maps, &MapTexel::local) : vec3(0.f), global = need_global ? tap(*b.maps, &MapTexel::global) : vec3(0.f);
            const vec3 ref = b.reference ? tap(*b.reference) : vec3(0.f);
            const vec3 B = r == Response::Local ? local : r == Response::Global ? global : r == Response::Reference ? ref : local + global;
            const vec3 rho = b.rho ? tap(*b.rho) : vec3(1.f);
            const float T = float(fresnel_transmittance(std::clamp(glm::dot(n, wo), 0.f, 1.f), b.s.medium.eta));
            ctx.out.put(AovWriter::kRadiance, x, y, rho * B * (T * kInvPi));
            ctx.out.put(AovWriter::kNormal, x, y, n);
            if (ctx.out.wanted(out_irr)) ctx.out.put(out_irr, x, y, tap(*b.maps, &MapTexel::irradiance));
            if (!parts) continue;
            ctx.out.put(out_rad, x, y, local + global);
            ctx.out.put(out_loc, x, y, local);
            ctx.out.put(out_glo, x, y, global);
            ctx.out.put(out_ref, x, y, ref);
            ctx.out.put(out_err, x, y, b.reference ? local + global - ref : vec3(0.f));
        }
    });
}
}  // namespace
}  // namespace mesolab::translucency

namespace mesolab {
void register_translucency(Registry& r) { r.add(std::make_unique<translucency::TranslucencyTechnique>()); }
}  // namespace mesolab
