#include "core/microgeom/microgeom.h"
#include "core/error.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/technique.h"

#include <tbb/parallel_for.h>
#include <map>

namespace mesolab::microgeom {

ProceduralParams procedural_params(const ParamTable& m) {
    ProceduralParams p;
    p.name = m.get_string("heightfield");
    p.resolution = int(m.get_int("resolution"));
    p.height_scale = float(m.get_float("height_scale"));
    p.periodic = m.get_bool("periodic");
    p.vgroove_angle = float(m.get_float("vgroove_angle"));
    p.rms_slope = float(m.get_float("rms_slope"));
    p.correlation = float(m.get_float("correlation"));
    p.seed = uint32_t(m.get_int("seed"));
    p.albedo = m.get_vec3("albedo");
    return p;
}

namespace {

// [SECTION] Per-object stage helpers
// Run `make` once per distinct fingerprint of `keys` among the objects using microgeom.
template <class T, class Make>
PerObject<T> per_object(const Scene& s, const std::vector<std::string>& keys, const Make& make) {
    PerObject<T> out;
    out.items.resize(s.objects.size());
    std::map<std::string, std::shared_ptr<const T>> done;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const SceneObject& o = s.objects[i];
        if (o.technique != "microgeom") continue;
        std::string fp;
        for (const auto& k : keys) fp += value_canonical(*o.material.group().find(k), o.material.get(k), s.base_dir) + ";";
        auto it = done.find(fp);
        if (it == done.end()) it = done.emplace(fp, std::make_shared<const T>(make(int(i), o))).first;
        out.items[i] = it->second;
    }
    return out;
}

const std::vector<std::string> kFieldKeys{"heightfield", "resolution", "height_scale", "periodic", "vgroove_angle", "rms_slope", "correlation", "seed", "albedo"};
const std::vector<std::string> kScatterKeys{"depth", "sampling", "paths", "scatter_seed", "shadows"};
const std::vector<std::string> kCurvatureKeys{"curvature_u", "curvature_v"};

bool curved(const SceneObject& o) { return o.material.get_float("curvature_u") != 0.0 || o.material.get_float("curvature_v") != 0.0; }

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

bool planar(const SceneObject& o) { return o.geometry.get_string("type") == "plane"; }

ScatterSettings scatter_settings(const ParamTable& m) {
    ScatterSettings st;
    st.depth = int(m.get_int("depth"));
    st.all_directions = m.get_string("sampling") == "all";
    st.paths = int(m.get_int("paths"));
    st.seed = uint32_t(m.get_int("scatter_seed"));
    st.shadows = m.get_string("shadows") != "none";
    return st;
}

// Direction towards the first light in the heightfield's local frame, for the scattering solution.
vec3 first_light_local(const Scene& s, const SceneObject& o) {
    if (!planar(o) || s.lights.empty()) return {0.f, 0.f, 1.f};
    const ParamTable& l = s.lights[0];
    vec3 wi;
    if (l.get_string("type") == "directional") {
        const vec2 d = l.get_vec2("direction");
        wi = direction_from_degrees(d.x, d.y);
    } else {
        wi = glm::normalize(l.get_vec3("position") - o.geometry.get_vec3("position"));
    }
    return wi;  // the plane's local frame is the world frame (u = +x, v = +y, n = +z)
}

// [SECTION] The technique
class MicrogeomTechnique final : public Technique {
public:
    MicrogeomTechnique() : Technique("microgeom", "Micro-geometry (Heidrich et al. 2000)") {
        auto& p = params_;
        p.add_path("heightfield", "bricks").builtins(procedural_names()).costs(Cost::Recompute)
            .doc("Procedural heightfield (triangles: the paper's Fig. 2 ridge, bricks, bumps, vgrooves, gaussian, flat) or an image "
                 "(8/16-bit, float EXR/TIFF; first channel = height in texels before height_scale)");
        p.add_int("resolution", 128).range(8, 4096).costs(Cost::Recompute).in("texels").doc("Size of a procedural heightfield (texels per side)");
        p.add_float("height_scale", 1.0).range(0.0, 1e4).costs(Cost::Recompute).doc("Multiplies the heights (procedural heights are in texels)");
        p.add_bool("periodic", true).costs(Cost::Recompute).doc("Wrap-around visibility across the borders (tileable fields)");
        p.add_float("vgroove_angle", 90.0).range(1.0, 179.0).in("degrees").costs(Cost::Recompute).doc("vgrooves: opening angle of the V");
        p.add_float("rms_slope", 0.5).range(0.0, 10.0).costs(Cost::Recompute).doc("gaussian: RMS slope");
        p.add_float("correlation", 4.0).range(0.5, 64.0).in("texels").costs(Cost::Recompute).doc("gaussian: correlation length");
        p.add_int("seed", 1).range(0, 2147483647).costs(Cost::Recompute).doc("gaussian: random seed");
        p.add_color("albedo", {0.8, 0.8, 0.8}).costs(Cost::Recompute)
            .doc("Albedo of the micro-surface (Lambert); procedural fields modulate it (triangles: red/white faces, bricks: brick and mortar)");
        p.add_int("directions", 100).range(16, 1024).costs(Cost::Recompute).more_accurate(Accuracy::Higher, int64_t(1024))
            .doc("N: directions over the whole sphere for the visibility textures S_i (and their triangulation)");
        p.add_int("depth", 2).range(0, 8).costs(Cost::Recompute).more_accurate(Accuracy::Higher, int64_t(8))
            .doc("K: bounces of light scattered inside the heightfield (direct light is added at every scattering point)");
        p.add_enum("sampling", {"all", "random"}, "all").costs(Cost::Recompute)
            .doc("Directions gathered per bounce: all N (deterministic quadrature) or a random subset (dependent tests)");
        p.add_int("paths", 64).range(1, 4096).costs(Cost::Recompute).used_when("sampling", {"random"}).doc("Random directions per bounce");
        p.add_int("scatter_seed", 1).range(0, 2147483647).costs(Cost::Recompute).used_when("sampling", {"random"}).doc("Seed of the random subsets");
        p.add_float("curvature_u", 0.0).range(-360.0, 360.0).in("degrees").costs(Cost::Recompute)
            .doc("Curvature of the base geometry along u, as the total bend across the field (+ convex, - concave): bends the "
                 "scattering directions and reweights paths by the triangle-fan area importance (§5); S_i are not recomputed");
        p.add_float("curvature_v", 0.0).range(-360.0, 360.0).in("degrees").costs(Cost::Recompute).doc("Curvature along v (see curvature_u)");
        p.add_enum("shadows", {"none", "exact", "ellipse"}, "exact").costs(Cost::Recompute)
            .doc("none; exact: the visibility of the 3 directions of the spherical triangle containing the light, interpolated; "
                 "ellipse: the paper's per-texel ellipse fitted to the unshadowed directions (§4)");
        p.add_enum("brdf", {"lambert", "blinn-phong"}, "lambert").doc("Micro-BRDF seen by the viewer for direct light");
        p.add_color("ks", {0.04, 0.04, 0.04}).used_when("brdf", {"blinn-phong"}).doc("Specular albedo of the normalised Blinn-Phong lobe");
        p.add_float("shininess", 32.0).range(1.0, 10000.0).log().used_when("brdf", {"blinn-phong"}).doc("Blinn-Phong exponent");
        p.add_float("tiling", 4.0).range(0.01, 1e4).log().doc("Repeats of the heightfield across the object's (u,v) (texture mode: always 1:1)");

        effects_.push_back({"indirect", true, "Light scattered inside micro-geometry (microgeom.depth bounces)"});
        aovs_ = {{"direct", 3, "Direct light reflected towards the eye (with shadows)"},
                 {"indirect", 3, "Scattered and environment light reflected towards the eye"},
                 {"shadow", 1, "Fraction of the first light reaching each point (0..1)"},
                 {"folded", 1, "1 where the curvature folds the direction triangulation over (visibility would change; §5)"}};
    }

    void declare_stages(StageGraph& g) const override {
        auto keys = [](const std::vector<std::string>& ks) {
            std::vector<std::string> r;
            for (const auto& k : ks) r.push_back("microgeom." + k);
            return r;
        };
        g.add({.name = "microgeom.heightfield",
               .help = "Build or read the heightfields",
               .params = keys(kFieldKeys),
               .run = [](StageContext& ctx) {
                   return stage_result(per_object<Heightfield>(ctx.scene, kFieldKeys, [&](int i, const SceneObject& o) {
                       const ProceduralParams p = procedural_params(o.material);
                       const ParamDecl& d = *o.material.group().find("heightfield");
                       if (!d.is_file(o.material.get("heightfield"))) return make_procedural(p);
                       (void)i;
                       return load_heightfield(ctx.scene.resolve(p.name), p.height_scale, 1.f, p.periodic, p.albedo);
                   }));
               }});
        g.add({.name = "microgeom.directions",
               .help = "N directions over the sphere and their spherical triangulation",
               .params = {"microgeom.directions"},
               .run = [](StageContext& ctx) {
                   return stage_result(per_object<DirectionSet>(ctx.scene, {"directions"}, [](int, const SceneObject& o) {
                       return make_direction_set(int(o.material.get_int("directions")));
                   }));
               }});
        g.add({.name = "microgeom.visibility",
               .help = "Visibility textures S_i: first hit for every direction and texel",
               .inputs = {"microgeom.heightfield", "microgeom.directions"},
               .paper = PaperFigure{1029e3, "Heidrich et al. 2000, Table 1: Bricks 128x128, 100 directions (SGI Octane)"},
               .run = [](StageContext& ctx) {
                   auto hf = ctx.input<PerObject<Heightfield>>("microgeom.heightfield");
                   auto dirs = ctx.input<PerObject<DirectionSet>>("microgeom.directions");
                   PerObject<Visibility> out;
                   out.items.resize(ctx.scene.objects.size());
                   std::map<std::pair<const void*, const void*>, std::shared_ptr<const Visibility>> done;
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const Heightfield* h = hf->get(int(i));
                       const DirectionSet* d = dirs->get(int(i));
                       if (!h || !d) continue;
                       auto& slot = done[{h, d}];
                       if (!slot) slot = std::make_shared<const Visibility>(compute_visibility(*h, *d, [&](double f) { ctx.progress(f); }));
                       out.items[i] = slot;
                   }
                   return stage_result(std::move(out));
               }});
        // Curved base: fan-area importance of the bent directions (never recomputes S_i).
        g.add({.name = "microgeom.importance",
               .help = "Bend the directions by the base curvature and weight them by the relative triangle-fan area (§5)",
               .params = keys(kCurvatureKeys),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility"},
               .when = [](const Scene& s) {
                   for (const auto& o : s.objects)
                       if (o.technique == "microgeom" && curved(o)) return true;
                   return false;
               },
               .when_text = "microgeom.curvature_u or curvature_v is not 0",
               .run = [](StageContext& ctx) {
                   auto hf = ctx.input<PerObject<Heightfield>>("microgeom.heightfield");
                   auto dirs = ctx.input<PerObject<DirectionSet>>("microgeom.directions");
                   auto vis = ctx.input<PerObject<Visibility>>("microgeom.visibility");
                   PerObject<Importance> out;
                   out.items.resize(ctx.scene.objects.size());
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const SceneObject& o = ctx.scene.objects[i];
                       const Heightfield* h = hf->get(int(i));
                       if (!h || !curved(o)) continue;
                       const Bending b = Bending::from_degrees(float(o.material.get_float("curvature_u")), float(o.material.get_float("curvature_v")), h->width, h->height);
                       auto imp = std::make_shared<Importance>(compute_importance(*h, *dirs->get(int(i)), *vis->get(int(i)), b, [&](double f) { ctx.progress(f); }));
                       if (imp->folded_count > 0) {
                           char msg[256];
                           std::snprintf(msg, sizeof msg, "%s: the curvature folds the direction triangulation over at %zu of %zu texels (%.1f%%): visibility would change there; "
                                         "see the 'folded' AOV, or reduce microgeom.curvature_u/v", o.name.c_str(), imp->folded_count, size_t(h->width) * size_t(h->height),
                                         100.0 * double(imp->folded_count) / double(size_t(h->width) * size_t(h->height)));
                           ctx.warn(msg);
                       }
                       out.items[i] = std::move(imp);
                   }
                   return stage_result(std::move(out));
               }});
        // Per-texel ellipses (§4), only when they are the selected shadow method.
        g.add({.name = "microgeom.ellipses",
               .help = "Fit a per-texel ellipse to the projections of the unshadowed directions (covariance start, optimised)",
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility"},
               .when = [](const Scene& s) {
                   for (const auto& o : s.objects)
                       if (o.technique == "microgeom" && o.material.get_string("shadows") == "ellipse") return true;
                   return false;
               },
               .when_text = "microgeom.shadows is ellipse",
               .paper = PaperFigure{194e3, "Heidrich et al. 2000, Table 1: Bricks 128x128 shadow precompute (SGI Octane)"},
               .run = [](StageContext& ctx) {
                   auto hf = ctx.input<PerObject<Heightfield>>("microgeom.heightfield");
                   auto dirs = ctx.input<PerObject<DirectionSet>>("microgeom.directions");
                   auto vis = ctx.input<PerObject<Visibility>>("microgeom.visibility");
                   PerObject<EllipseMap> out;
                   out.items.resize(ctx.scene.objects.size());
                   std::map<const void*, std::shared_ptr<const EllipseMap>> done;
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const Visibility* v = vis->get(int(i));
                       if (!v || ctx.scene.objects[i].material.get_string("shadows") != "ellipse") continue;
                       auto& slot = done[v];
                       if (!slot) slot = std::make_shared<const EllipseMap>(fit_ellipses(*hf->get(int(i)), *dirs->get(int(i)), *v, [&](double f) { ctx.progress(f); }));
                       out.items[i] = slot;
                   }
                   return stage_result(std::move(out));
               }});
        // Environment light scattered: independent of the light.
        g.add({.name = "microgeom.scatter_env",
               .help = "Environment light gathered where S_i has no hit, scattered microgeom.depth times",
               .params = with(keys(kScatterKeys), {"env.*"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "env.map"},
               .effects = {"environment"},
               .run = [](StageContext& ctx) {
                   return stage_result(scatter_all(ctx, /*environment=*/true));
               }});
        // The first light scattered (its direct part is shaded per pixel).
        g.add({.name = "microgeom.scatter",
               .help = "The first light scattered inside the heightfield (dependent tests)",
               .params = with(keys(kScatterKeys), {"light.*", "geometry.type"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "microgeom.ellipses"},
               .effects = {"indirect"},
               .when = [](const Scene& s) {
                   for (const auto& o : s.objects)
                       if (o.technique == "microgeom" && o.material.get_int("depth") > 0) return true;
                   return false;
               },
               .when_text = "microgeom.depth > 0",
               .paper = PaperFigure{12e3, "Heidrich et al. 2000, Table 1: Bricks 128x128, software render, 100 samples (SGI Octane)"},
               .run = [](StageContext& ctx) {
                   return stage_result(scatter_all(ctx, /*environment=*/false));
               }});
    }

    // One scattering solution per object: environment only, or the first light at unit irradiance.
    static PerObject<LightScatter> scatter_all(StageContext& ctx, bool environment) {
        auto hf = ctx.input<PerObject<Heightfield>>("microgeom.heightfield");
        auto dirs = ctx.input<PerObject<DirectionSet>>("microgeom.directions");
        auto vis = ctx.input<PerObject<Visibility>>("microgeom.visibility");
        auto imp = ctx.input<PerObject<Importance>>("microgeom.importance");
        auto ell = ctx.input<PerObject<EllipseMap>>("microgeom.ellipses");
        Environment env;
        if (environment) {
            env.color = ctx.scene.env.get_vec3("color");
            env.intensity = float(ctx.scene.env.get_float("intensity"));
            env.map = ctx.input<Image>("env.map");
        }
        PerObject<LightScatter> out;
        out.items.resize(ctx.scene.objects.size());
        for (size_t i = 0; i < out.items.size(); ++i) {
            const SceneObject& o = ctx.scene.objects[i];
            if (!hf->get(int(i))) continue;
            LightScatter ls;
            ScatterSettings st = scatter_settings(o.material);
            st.importance = imp ? imp->get(int(i)) : nullptr;
            st.ellipses = ell ? ell->get(int(i)) : nullptr;
            ls.planar = planar(o);
            ls.light_dir = first_light_local(ctx.scene, o);
            if (environment) {
                st.env = &env;
            } else {
                st.light_dir = ls.light_dir;
                st.light_E = vec3(1.f);
            }
            ls.result = scatter(*hf->get(int(i)), *dirs->get(int(i)), *vis->get(int(i)), st, [&](double f) { ctx.progress(f); });
            out.items[i] = std::make_shared<const LightScatter>(std::move(ls));
        }
        return out;
    }

    std::vector<std::string> frame_stages() const override {
        return {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "microgeom.ellipses", "microgeom.scatter_env", "microgeom.scatter"};
    }

    std::optional<ivec2> texture_size(const Scene& s, const Evaluation& ev) const override {
        auto hf = ev.get<PerObject<Heightfield>>("microgeom.heightfield");
        for (size_t i = 0; hf && i < s.objects.size(); ++i)
            if (const Heightfield* h = hf->get(int(i))) return ivec2(h->width, h->height);
        return std::nullopt;
    }

    void shade_cpu(const ShadeContext& ctx) const override;
    std::vector<BenchTable> bench_tables() const override;
};

// [SECTION] CPU shading (bump level of detail; texture mode = the heightfield's texels 1:1)
void MicrogeomTechnique::shade_cpu(const ShadeContext& ctx) const {
    auto hfs = ctx.eval.get<PerObject<Heightfield>>("microgeom.heightfield");
    auto dirss = ctx.eval.get<PerObject<DirectionSet>>("microgeom.directions");
    auto viss = ctx.eval.get<PerObject<Visibility>>("microgeom.visibility");
    auto envs = ctx.eval.get<PerObject<LightScatter>>("microgeom.scatter_env");
    auto lights = ctx.eval.get<PerObject<LightScatter>>("microgeom.scatter");
    const GBuffer& gb = ctx.gbuffer;
    Image& rad = ctx.frame.aov("radiance");
    Image& nrm = ctx.frame.aov("normal");
    Image& dir_img = ctx.frame.aov("direct");
    Image& ind_img = ctx.frame.aov("indirect");
    Image& sh_img = ctx.frame.aov("shadow");
    Image& fold_img = ctx.frame.aov("folded");
    auto imps = ctx.eval.get<PerObject<Importance>>("microgeom.importance");
    auto ells = ctx.eval.get<PerObject<EllipseMap>>("microgeom.ellipses");

    tbb::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const int obj = gb.object[px];
            const SceneObject& o = ctx.scene.objects[size_t(obj)];
            const Heightfield& hf = *hfs->get(obj);
            const DirectionSet& dirs = *dirss->get(obj);
            const Visibility& vis = *viss->get(obj);
            const ParamTable& m = o.material;

            // Macro frame (two-sided) and the texel position of this pixel.
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            vec3 N = gb.normal[px];
            if (glm::dot(N, wo) < 0.f) N = -N;
            vec3 T = gb.tangent[px] - N * glm::dot(gb.tangent[px], N);
            T = glm::dot(T, T) > 1e-12f ? glm::normalize(T) : (std::fabs(N.x) < 0.9f ? glm::normalize(glm::cross(N, vec3(1, 0, 0))) : glm::normalize(glm::cross(N, vec3(0, 1, 0))));
            const vec3 B = glm::cross(N, T);
            const float tiling = ctx.camera.texture_mode ? 1.f : float(m.get_float("tiling"));
            const vec2 uv = gb.uv[px];
            const float c = uv.x * float(hf.width) * tiling - 0.5f, r = (1.f - uv.y) * float(hf.height) * tiling - 0.5f;
            auto to_local = [&](vec3 w) { return vec3(glm::dot(w, T), glm::dot(w, B), glm::dot(w, N)); };

            // Micro normal and albedo, bilinear.
            const float c0f = std::floor(c), r0f = std::floor(r), fc = c - c0f, fr = r - r0f;
            int tx[2], ty[2];
            for (int k = 0; k < 2; ++k) {
                tx[k] = ((int(c0f) + k) % hf.width + hf.width) % hf.width;
                ty[k] = ((int(r0f) + k) % hf.height + hf.height) % hf.height;
            }
            const float wts[4] = {(1 - fc) * (1 - fr), fc * (1 - fr), (1 - fc) * fr, fc * fr};
            vec3 n_loc(0.f), albedo(0.f);
            for (int k = 0; k < 4; ++k) {
                n_loc += wts[k] * hf.normal(tx[k & 1], ty[k >> 1]);
                albedo += wts[k] * hf.albedo[hf.index(tx[k & 1], ty[k >> 1])];
            }
            n_loc = glm::normalize(n_loc);
            const vec3 n = glm::normalize(T * n_loc.x + B * n_loc.y + N * n_loc.z);
            const bool phong = m.get_string("brdf") == "blinn-phong";
            const vec3 ks = phong ? m.get_vec3("ks") : vec3(0.f);
            const float shininess = float(m.get_float("shininess"));
            const bool shadows = m.get_string("shadows") != "none";
            const EllipseMap* ellipses = ells ? ells->get(obj) : nullptr;

            // Direct light: per pixel, exact shadows bilinear over the 4 texels.
            vec3 direct(0.f);
            float shadow0 = 0.f;
            for (size_t li = 0; li < ctx.lighting.lights.size(); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                const float cos_i = glm::dot(n, wi);
                float V = 0.f;
                if (cos_i > 0.f) {
                    if (!shadows) {
                        V = 1.f;
                    } else {
                        const vec3 l_loc = glm::normalize(to_local(wi));
                        if (ellipses) {
                            for (int k = 0; k < 4; ++k) {
                                const int ex = tx[k & 1], ey = ty[k >> 1];
                                if (glm::dot(hf.normal(ex, ey), l_loc) > 0.f) V += wts[k] * ellipse_visibility(ellipses->at(ex, ey), l_loc, ellipses->edge);
                            }
                        } else {
                        vec3 bary;
                        const auto& tri = dirs.triangles[size_t(dirs.locate(l_loc, bary))];
                        for (int k = 0; k < 4; ++k) V += wts[k] * visibility_fraction(hf, vis, tri, bary, tx[k & 1], ty[k >> 1], l_loc);
                        }
                    }
                }
                if (li == 0) shadow0 = V;
                if (cos_i <= 0.f || V <= 0.f) continue;
                vec3 f = albedo * kInvPi;
                if (phong) {
                    const vec3 h = glm::normalize(wo + wi);
                    f += ks * (shininess + 8.f) / (8.f * kPi) * std::pow(std::max(0.f, glm::dot(n, h)), shininess);
                }
                direct += f * E * cos_i * V;
            }

            // Scattered light: environment part, plus the first light's part scaled by its irradiance
            // (on curved bases: computed for light along the macro normal, scaled by the macro cosine).
            vec3 E_ind(0.f);
            const LightScatter* es = envs ? envs->get(obj) : nullptr;
            if (es) E_ind += sample_bilinear(es->result.E_indirect, hf.width, hf.height, true, c, r);
            const LightScatter* ls = lights ? lights->get(obj) : nullptr;
            if (ls && !ctx.lighting.lights.empty()) {
                vec3 wi, E;
                ctx.lighting.lights[0].sample(p, wi, E);
                const float scale = ls->planar ? 1.f : std::max(0.f, glm::dot(N, wi));
                E_ind += sample_bilinear(ls->result.E_indirect, hf.width, hf.height, true, c, r) * E * scale;
            }
            const vec3 indirect = albedo * kInvPi * E_ind;
            const vec3 L = direct + indirect;
            float* q = rad.at(x, y);
            q[0] = L.x, q[1] = L.y, q[2] = L.z;
            q = nrm.at(x, y);
            q[0] = n.x, q[1] = n.y, q[2] = n.z;
            q = dir_img.at(x, y);
            q[0] = direct.x, q[1] = direct.y, q[2] = direct.z;
            q = ind_img.at(x, y);
            q[0] = indirect.x, q[1] = indirect.y, q[2] = indirect.z;
            sh_img.at(x, y)[0] = shadow0;
            const Importance* imp = imps ? imps->get(obj) : nullptr;
            if (imp && !imp->folded.empty()) {
                const int fx = ((int(std::floor(c + 0.5f)) % hf.width) + hf.width) % hf.width, fy = ((int(std::floor(r + 0.5f)) % hf.height) + hf.height) % hf.height;
                fold_img.at(x, y)[0] = float(imp->folded[hf.index(fx, fy)]);
            }
        }
    });
}

// [SECTION] Table 1
std::vector<BenchTable> MicrogeomTechnique::bench_tables() const {
    auto scene = [](const char* field, int res) {
        return [=] {
            Scene s = default_scene("microgeom");
            s.name = std::string(field) + std::to_string(res);
            apply_set(s, "camera.mode", "texture");
            apply_set(s, "geometry.type", "plane");
            apply_set(s, "microgeom.heightfield", field);
            apply_set(s, "microgeom.resolution", std::to_string(res));
            apply_set(s, "microgeom.directions", "100");
            return s;
        };
    };
    BenchTable t;
    t.name = "microgeom";
    t.title = "Heidrich et al. 2000, Table 1: precomputation and rendering (100 directions)";
    t.paper_machine = "SGI Octane 300 MHz R12000 (software) / GeForce 256 (hardware), seconds converted to ms";
    t.columns = {{"S_i precompute", "microgeom.visibility"},
                 {"software render (scattering, depth 2, all 100 directions)", "microgeom.scatter"},
                 {"frame (texture space, 1 pixel per texel)", "", 0, 0, true, false}};
    t.rows = {{"Triangles 32x32", scene("triangles", 32), {27e3, 10e3, std::nullopt}},
              {"Bricks 128x128", scene("bricks", 128), {1029e3, 12e3, std::nullopt}},
              {"Bumps 32x32", scene("bumps", 32), {109e3, 8e3, std::nullopt}},
              {"Bricks 512x512", scene("bricks", 512), {}},
              {"Bricks 1024x1024", scene("bricks", 1024), {}}};
    return {t};
}
}  // namespace
}  // namespace mesolab::microgeom

namespace mesolab {
void register_microgeom(Registry& r) { r.add(std::make_unique<microgeom::MicrogeomTechnique>()); }
}  // namespace mesolab
