// Technique translucency: its parameters and AOVs, what a frame needs, how closely the GPU follows
// the CPU, the sweep metric against the brute force, and registration (see technique.h).
#include "core/error.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/technique.h"
#include "core/translucency/reference.h"
#include "core/translucency/paper.h"
#include "core/translucency/technique.h"
#include "core/translucency/translucency.h"

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
    if (parts & ProfilePart) s.burley = t.get_string("method") == "lensch-burley";
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
    if (parts & Shadows) {
        s.shadows = t.get_bool("shadows");
        s.shadow_map = int(t.get_int("shadow_map"));
    }
    if (parts & Show) {
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

std::unique_ptr<Profile> Settings::profile() const {
    if (burley) return std::make_unique<BurleyProfile>(medium);
    return std::make_unique<Dipole>(medium);
}

AtlasParams atlas_params(const Settings& s) { return {s.atlas_size, (s.kernel - 1) / 2 + 1, s.chunk_angle}; }

std::vector<std::string> with_material(std::vector<std::string> keys) {
    keys.insert(keys.end(), kMaterialKeys.begin(), kMaterialKeys.end());
    return keys;
}

std::vector<std::string> step_keys(std::vector<std::string> extra) {
    // translucency.method: which objects the steps run for (the paper's pipeline serves lensch and
    // lensch-burley) and which profile the reference sums.
    std::vector<std::string> k = {"light.*", "env.*", "effects.*", "geometry.*", "translucency.shadows", "translucency.shadow_map", "translucency.method"};
    k.insert(k.end(), kMaterialKeys.begin(), kMaterialKeys.end());
    k.insert(k.end(), extra.begin(), extra.end());
    return k;
}

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
    const std::unique_ptr<Profile> d = s.profile();
    auto factor = [&](double r) {
        const dvec3 v = d->Rd(r);
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
TranslucencyTechnique::TranslucencyTechnique() : Technique("translucency", "Translucency (Lensch et al. 2002)") {
    paper_method_ = "lensch";
    std::vector<std::string> names;
    for (const auto& m : measured_materials()) names.push_back(m.name);
    names.push_back("custom");
    const MeasuredMaterial& marble = measured_material("marble");
    auto& p = params_;
    // The atlas and vertex pipeline's keys: read by the paper's method and lensch-burley only.
    const std::vector<std::string> kPipelineMethods = {"lensch", "lensch-burley"};
    p.add_enum("material", names, "marble")
        .doc("One of Jensen et al. 2001's measured materials, or custom (sigma_s, sigma_a, eta)");
    p.add_vec3("sigma_s", {marble.medium.sigma_s.x, marble.medium.sigma_s.y, marble.medium.sigma_s.z}).range(0.0, 1e4).in("1/mm").used_when("material", {"custom"}).doc("Reduced scattering coefficient sigma'_s, RGB");
    p.add_vec3("sigma_a", {marble.medium.sigma_a.x, marble.medium.sigma_a.y, marble.medium.sigma_a.z}).range(0.0, 1e4).in("1/mm").used_when("material", {"custom"}).doc("Absorption coefficient sigma_a, RGB");
    p.add_float("eta", 1.5).range(1.0, 3.0).used_when("material", {"custom"}).doc("Relative index of refraction");
    p.add_float("mm_per_unit", 20.0).range(1e-4, 1e7).log().in("mm")
        .doc("Millimetres per scene unit: the object's size decides how translucent it looks");
    p.add_int("vertices", 10000).used_when("method", kPipelineMethods).range(0, 2000000).more_accurate(Accuracy::Higher)
        .doc("Vertices after simplification (OpenMesh's decimater; 0 keeps every vertex): one hat basis function per vertex");
    p.add_int("atlas_size", 512).used_when("method", kPipelineMethods).range(128, 2048).more_accurate(Accuracy::Higher, int64_t(2048))
        .doc("Texels per side of the texture atlas (local response, illumination map)");
    p.add_float("chunk_angle", 30.0).used_when("method", kPipelineMethods).range(1.0, 89.0).in("degrees")
        .doc("Largest deviation of a triangle's normal from its chunk's average normal");
    p.add_int("kernel", 7).used_when("method", kPipelineMethods).range(3, 15).odd().more_accurate(Accuracy::Higher, int64_t(15))
        .doc("Local kernel size K (odd): K x K texels around each texel");
    p.add_float("threshold", 3e-5).used_when("method", kPipelineMethods).range(0.0, 1.0).more_accurate(Accuracy::Lower, 0.0)
        .doc("Smallest vertex-to-vertex factor kept (largest channel); fewer factors, faster global response");
    p.add_bool("blend", true).used_when("method", kPipelineMethods).doc("Blend local and global responses (§5.4); off shows the double counting of Fig. 6");
    p.add_enum("response", {"both", "local", "global", "reference"}, "both").used_when("method", kPipelineMethods)
        .doc("What the image shows: local + global, one of them, or the brute-force reference");
    p.add_bool("compare", false).used_when("method", kPipelineMethods)
        .doc("Also compute the brute-force reference each frame (the reference and error AOVs): seconds per light move on large meshes");
    p.add_bool("shadows", true).doc("Self-shadowing of the illumination map (a shadow map per light)");
    p.add_int("shadow_map", 512).range(64, 8192).used_when("shadows", {"true"}).doc("Shadow map texels per side");
    p.add_path("albedo_map", "").used_when("method", kPipelineMethods)
        .doc("Surface texture rho multiplying the outgoing radiosity, at the mesh's (u,v); relative to the preset's folder");
    p.add_float("veins", 0.0).used_when("method", kPipelineMethods).range(0.0, 1.0).doc("Strength of procedural fractal veins in rho (0 = none)");
    p.add_float("vein_scale", 10.0).used_when("method", kPipelineMethods).range(0.01, 1e5).log().in("mm").doc("Vein period (used when veins > 0)");
    p.add_color("vein_color", {0.35, 0.3, 0.28}).used_when("method", kPipelineMethods).doc("rho inside a vein");
    p.section("Material and size", {"material", "sigma_s", "sigma_a", "eta", "mm_per_unit"});
    p.section("Accuracy (each costs a recompute)", {"vertices", "atlas_size", "chunk_angle", "kernel", "threshold", "blend"});
    p.section("Display", {"response", "compare", "shadows", "shadow_map"});
    p.section("Texture", {"albedo_map", "veins", "vein_scale", "vein_color"}, false);
    aovs_ = {{"irradiance", 3, "Power per unit area entering the medium: incident irradiance x Fresnel transmittance"},
             {"radiosity", 3, "B: power per unit area leaving through subsurface transport, before the outgoing Fresnel term (local + global)"},
             {"local", 3, "The local (kernel) part of B"},
             {"global", 3, "The global (vertex factor) part of B"},
             {"reference", 3, "B by brute-force summation (translucency.compare or response = reference; else 0)"},
             {"error", 3, "radiosity - reference (0 without a reference)"},
             {"exitance", 3, "Power per unit area the model sends out through the boundary: the outgoing radiance integrated over the hemisphere, "
                             "before rho (the displayed response B x the hemispherical mean of T; the truth's exitance is the same quantity)"}};
}

std::vector<StageName> pipeline_stages() {
    return {stages::mesh, stages::atlas, stages::kernels, stages::factors, stages::blend, stages::gather, stages::albedo};
}

std::vector<StageName> TranslucencyTechnique::frame_stages() const { return pipeline_stages(); }

std::optional<ivec2> TranslucencyTechnique::texture_size(const Scene& s, const Evaluation& ev) const {
    for (size_t i = 0; i < s.objects.size(); ++i)
        if (const auto a = ev.get(stages::atlas, int(i))) return ivec2(a->atlas.size);
    return std::nullopt;
}

std::shared_ptr<const TriMesh> TranslucencyTechnique::object_mesh(const Scene&, const Evaluation& ev, int object) const {
    const auto a = ev.get(stages::atlas, object);
    return a ? a->display : nullptr;
}

// The maps are sums of many float products (kernels, factors), which agree to about 1e-4 of the
// radiosity. The shadow maps are discrete: the CPU's and the GPU's rasterisers put a shadow's edge
// within a shadow-map texel of each other, and every atlas texel whose depth test falls the other
// way is lit on one path and in shadow on the other (a whole light's irradiance: measured 1.16
// against 0.05 in spot-skin), which the bilinear display carries to a band of pixels along the
// shadow's edge: at most 0.09% of the interior values in the presets (llvmpipe).
FrameAgreement TranslucencyTechnique::agreement() const {
    return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.998, .interior_max = 5e-3, .interior_outliers = 1e-3,
            .why = "summation order of the kernels and factors; shadow-map texels along a shadow's edge"};
}

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
        reference_radiosity(a->atlas, texel_positions_mm(a->atlas, m->position, m->index, st.mm_per_unit), *st.profile(), st.mm_per_unit, E);
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
}  // namespace mesolab::translucency

namespace mesolab {
void register_translucency(Registry& r) { r.add(std::make_unique<translucency::TranslucencyTechnique>()); }
}  // namespace mesolab
