#include "core/microgeom/microgeom.h"
#include "core/error.h"
#include "core/heightfield/params.h"
#include "core/microgeom/device.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/btf.h"
#include "core/microgeom/lod.h"
#include "core/scene_stages.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/technique.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

namespace mesolab::microgeom {

namespace {

// [SECTION] Per-object stage helpers
template <class T, class Make>
PerObject<T> per_object(const Scene& s, const std::vector<std::string>& keys, const Make& make) {
    return mesolab::per_object<T>(s, "microgeom", keys, make);
}

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

const std::vector<std::string> kFieldKeys = with(heightfield_keys(), {"albedo", "albedo_map"});
const std::vector<std::string> kScatterKeys{"depth", "sampling", "paths", "scatter_seed", "shadows"};
const std::vector<std::string> kCurvatureKeys{"curvature_u", "curvature_v"};
const std::vector<std::string> kBrdfKeys{"lod", "brdf_fit", "brdf_resolution", "brdf_samples", "sh_bands", "brdf", "ks", "shininess"};
constexpr int kMaxDisplacementSegments = 2048;

std::string lod(const SceneObject& o) { return o.material.get_string("lod"); }
template <class Pred>
bool any_object(const Scene& s, const Pred& pred) {
    for (const auto& o : s.objects)
        if (o.technique == "microgeom" && pred(o)) return true;
    return false;
}

bool curved(const SceneObject& o) { return o.material.get_float("curvature_u") != 0.0 || o.material.get_float("curvature_v") != 0.0; }

bool planar(const SceneObject& o) { return o.geometry.get_string("type") == "plane"; }
bool any_point_light(const Scene& s) {
    return std::any_of(s.lights.begin(), s.lights.end(), [](const ParamTable& l) { return l.get_string("type") != "directional"; });
}
// Whether an object's light-driven scattering is the table over set directions, blended per pixel
// (scatter_directions): on curved bases, and on planes under a point light, whose direction varies
// over the plane; else one solve per (directional) light.
bool direction_table(const Scene& s, const SceneObject& o) { return !planar(o) || any_point_light(s); }
// The lights' scattering is solved (microgeom.scatter or microgeom.scatter_directions).
bool wants_light_scatter(const SceneObject& o) { return o.material.get_int("depth") > 0 && lod(o) != "brdf"; }

// The first line of an error message (EGL failures list every platform tried).
std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// The per-object results most stages read (null where a stage did not run).
struct FieldInputs {
    explicit FieldInputs(const StageContext& ctx)
        : hf(ctx.input<PerObject<Heightfield>>("microgeom.heightfield")), dirs(ctx.input<PerObject<DirectionSet>>("microgeom.directions")),
          vis(ctx.input<PerObject<Visibility>>("microgeom.visibility")), imp(ctx.input<PerObject<Importance>>("microgeom.importance")),
          ell(ctx.input<PerObject<EllipseMap>>("microgeom.ellipses")) {}
    std::shared_ptr<const PerObject<Heightfield>> hf;
    std::shared_ptr<const PerObject<DirectionSet>> dirs;
    std::shared_ptr<const PerObject<Visibility>> vis;
    std::shared_ptr<const PerObject<Importance>> imp;
    std::shared_ptr<const PerObject<EllipseMap>> ell;
};

ScatterSettings scatter_settings(const ParamTable& m) {
    ScatterSettings st;
    st.depth = int(m.get_int("depth"));
    st.all_directions = m.get_string("sampling") == "all";
    st.paths = int(m.get_int("paths"));
    st.seed = uint32_t(m.get_int("scatter_seed"));
    st.shadows = m.get_string("shadows") != "none";
    return st;
}

// Direction towards light `index` in a planar base's local frame, for its scattering solution.
vec3 light_local(const Scene& s, const SceneObject& o, size_t index) {
    if (index >= s.lights.size()) return {0.f, 0.f, 1.f};
    const ParamTable& l = s.lights[index];
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
// gpu() where the object asks for microgeom.device = gpu and the GPU works; else cpu(), with a
// warning naming `what` (e.g. when OpenGL is missing or fails on the way).
template <class Gpu, class Cpu>
auto on_device(StageContext& ctx, const SceneObject& o, const char* what, bool available, Gpu&& gpu, Cpu&& cpu) {
    if (o.material.get_string("device") == "gpu") {
        try {
            if (!available) throw std::runtime_error("this build has no GPU compute");
            return gpu();
        } catch (const Cancelled&) {
            throw;
        } catch (const InputError&) {
            throw;
        } catch (const std::runtime_error& e) {
            ctx.warn(o.name + ": " + what + " computed on the CPU: the GPU could not (" + first_line(e.what()) + ")");
        }
    }
    return cpu();
}

// f(solver) with the GPU's light solver (goniometer and BTF light images) where the object asks
// for it and OpenGL works; else, or when the GPU fails on the way, f(nullptr) (the CPU) with a warning.
template <class F>
auto with_light_solver(const std::function<void(const std::string&)>& warn, const SceneObject& o, const Heightfield& hf, const DirectionSet& dirs,
                              const Visibility& vis, const ScatterSettings& st, F&& f) {
    if (o.material.get_string("device") == "gpu") {
        try {
            if (!gpu_compute().light_solver) throw std::runtime_error("this build has no GPU compute");
            const std::unique_ptr<LightSolver> solver = gpu_compute().light_solver(hf, dirs, vis, st);
            return f(solver.get());
        } catch (const Cancelled&) {
            throw;
        } catch (const InputError&) {
            throw;
        } catch (const std::runtime_error& e) {
            warn(o.name + ": light images computed on the CPU: the GPU could not (" + first_line(e.what()) + ")");
        }
    }
    return f(nullptr);
}

class MicrogeomTechnique final : public Technique {
public:
    MicrogeomTechnique() : Technique("microgeom", "Micro-geometry (Heidrich et al. 2000)") {
        auto& p = params_;
        declare_heightfield_params(p);
        p.add_color("albedo", {0.8, 0.8, 0.8}).costs(Cost::Recompute)
            .doc("Albedo of the micro-surface (Lambert); procedural fields modulate it (triangles: red/white faces, bricks: brick and mortar)");
        p.add_path("albedo_map", "").costs(Cost::Recompute)
            .doc("Per-texel albedo image (8/16-bit sRGB or float linear), resampled bilinearly (wrapping) onto the heightfield's texels and "
                 "multiplied by albedo; empty: the procedural rule");
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
        p.add_enum("device", {"cpu", "gpu"}, "cpu").costs(Cost::Recompute)
            .doc("Where the precomputations run: cpu (all cores) or gpu (OpenGL compute shaders on a context of their own): S_i, the scattering "
                 "bounces, the curvature importance, the ellipse fits and the goniometer's and BTF's light images; without OpenGL a stage runs on "
                 "the CPU and says so. Both agree to float rounding (tests/microgeom/*_gpu_test.cpp)");
        p.add_enum("shadows", {"none", "exact", "ellipse"}, "exact").costs(Cost::Recompute)
            .doc("none; exact: the visibility of the 3 directions of the spherical triangle containing the light, interpolated; "
                 "ellipse: the paper's per-texel ellipse fitted to the unshadowed directions (§4)");
        p.add_float("ellipse_bend", 90.0).range(1.0, 360.0).in("degrees").costs(Cost::Recompute).used_when("shadows", {"ellipse"})
            .doc("Curved bases with ellipse shadows (§5): ellipses are fitted once at 5 curvatures (flat, +-this bend along u, +-along v) and "
                 "interpolated linearly for the current curvature, so moving the curvature sliders never refits; curvatures beyond it are clamped");
        p.add_enum("brdf", {"lambert", "blinn-phong"}, "lambert").costs(Cost::Recompute).doc("Micro-BRDF seen by the viewer for direct light (recomputes only the simulated BRDF of lod = brdf)");
        p.add_color("ks", {0.04, 0.04, 0.04}).costs(Cost::Recompute).used_when("brdf", {"blinn-phong"}).doc("Specular albedo of the normalised Blinn-Phong lobe");
        p.add_float("shininess", 32.0).range(1.0, 10000.0).log().costs(Cost::Recompute).used_when("brdf", {"blinn-phong"}).doc("Blinn-Phong exponent");
        p.add_float("tiling", 4.0).range(0.01, 1e4).log().costs(Cost::Recompute).doc("Repeats of the heightfield across the object's (u,v) (texture mode: always 1:1); recomputes only the displaced geometry of lod = geometry");
        p.add_enum("lod", {"geometry", "bump", "brdf"}, "bump").costs(Cost::Recompute)
            .doc("Level of detail: geometry (the base re-tessellated at one vertex per texel and displaced by the heights; parallax and "
                 "silhouettes), bump (bump map with precomputed visibility), brdf (smooth surface with the heightfield's simulated BRDF "
                 "from the virtual goniometer, §6)");
        p.add_enum("brdf_fit", {"table", "sh"}, "table").costs(Cost::Recompute).used_when("lod", {"brdf"})
            .doc("Simulated BRDF: a dense table of goniometer images (resolution^4), or a few hundred random images projected into "
                 "spherical harmonics (the paper's suggestion), tabulated for rendering");
        p.add_int("brdf_resolution", 8).range(2, 32).costs(Cost::Recompute).used_when("lod", {"brdf"}).more_accurate(Accuracy::Higher, int64_t(16))
            .doc("Table nodes per angle (theta 0..90 degrees, phi 0..360) for the light and the view: the paper's 16^4 is 16");
        p.add_int("brdf_samples", 300).range(1, 100000).costs(Cost::Recompute).used_when("brdf_fit", {"sh"}).more_accurate(Accuracy::Higher, int64_t(4000))
            .doc("SH fit: random (light, view) goniometer images");
        p.add_int("sh_bands", 3).range(1, 8).costs(Cost::Recompute).used_when("brdf_fit", {"sh"})
            .doc("SH fit: bands per direction (bands^2 coefficients for the light times bands^2 for the view)");

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
                   return stage_result(per_object<Heightfield>(ctx.scene, kFieldKeys, [&](int, const SceneObject& o) {
                       Heightfield hf = heightfield_from_material(ctx.scene, o.material);
                       const vec3 albedo = o.material.get_vec3("albedo");
                       const std::string albedo_map = o.material.get_string("albedo_map");
                       if (!albedo_map.empty()) apply_albedo_map(hf, ctx.scene.resolve(albedo_map), albedo, "microgeom.albedo_map");
                       return hf;
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
               .help = "Visibility textures S_i: first hit for every direction and texel (on microgeom.device)",
               .params = keys({"device"}),
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
                       if (!slot) {
                           std::optional<Visibility> v;
                           if (ctx.scene.objects[i].material.get_string("device") == "gpu") {
                               try {
                                   if (!gpu_compute()) throw std::runtime_error("this build has no GPU compute");
                                   v = gpu_compute().visibility(*h, *d);
                               } catch (const std::runtime_error& e) {
                                   ctx.warn(ctx.scene.objects[i].name + ": S_i computed on the CPU: the GPU was not available (" + first_line(e.what()) + ")");
                               }
                           }
                           if (!v) v = compute_visibility(*h, *d, [&](double f) { ctx.progress(f); });
                           slot = std::make_shared<const Visibility>(std::move(*v));
                       }
                       out.items[i] = slot;
                   }
                   return stage_result(std::move(out));
               }});
        // Curved base: fan-area importance of the bent directions (never recomputes S_i).
        g.add({.name = "microgeom.importance",
               .help = "Bend the directions by the base curvature and weight them by the relative triangle-fan area (§5)",
               .params = with(keys(kCurvatureKeys), {"microgeom.device"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility"},
               .when = [](const Scene& s) {
                   for (const auto& o : s.objects)
                       if (o.technique == "microgeom" && curved(o)) return true;
                   return false;
               },
               .when_text = "microgeom.curvature_u or curvature_v is not 0",
               .run = [](StageContext& ctx) {
                   const auto [hf, dirs, vis, imp, ell] = FieldInputs(ctx);
                   PerObject<Importance> out;
                   out.items.resize(ctx.scene.objects.size());
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const SceneObject& o = ctx.scene.objects[i];
                       const Heightfield* h = hf->get(int(i));
                       if (!h || !curved(o)) continue;
                       const Bending b = Bending::from_degrees(float(o.material.get_float("curvature_u")), float(o.material.get_float("curvature_v")), h->width, h->height);
                       const DirectionSet& d = *dirs->get(int(i));
                       const Visibility& v = *vis->get(int(i));
                       const auto progress = [&](double f) { ctx.progress(f); };
                       auto imp = std::make_shared<Importance>(on_device(
                           ctx, o, "the curvature importance", bool(gpu_compute().importance), [&] { return gpu_compute().importance(*h, d, v, b, progress); },
                           [&] { return compute_importance(*h, d, v, b, progress); }));
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
        // Per-texel ellipses (§4), only when they are the selected shadow method; on a curved base
        // fitted once at 5 curvatures (§5) and interpolated for the current one.
        g.add({.name = "microgeom.ellipses_curved",
               .help = "Fit the per-texel ellipses at 5 base curvatures: flat, +-microgeom.ellipse_bend along u and along v (§5)",
               .params = {"microgeom.ellipse_bend", "microgeom.shadows", "microgeom.device"},
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility"},
               .when = [](const Scene& s) { return any_object(s, [](const SceneObject& o) { return o.material.get_string("shadows") == "ellipse" && curved(o); }); },
               .when_text = "microgeom.shadows is ellipse on a curved base",
               .run = [](StageContext& ctx) {
                   const auto [hf, dirs, vis, imp, ell] = FieldInputs(ctx);
                   PerObject<CurvedEllipses> out;
                   out.items.resize(ctx.scene.objects.size());
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const SceneObject& o = ctx.scene.objects[i];
                       const Visibility* v = vis->get(int(i));
                       if (!v || o.material.get_string("shadows") != "ellipse" || !curved(o)) continue;
                       const Heightfield& h = *hf->get(int(i));
                       const DirectionSet& d = *dirs->get(int(i));
                       const float bend = float(o.material.get_float("ellipse_bend"));
                       const auto progress = [&](double f) { ctx.progress(f); };
                       out.items[i] = std::make_shared<const CurvedEllipses>(on_device(
                           ctx, o, "the ellipses", bool(gpu_compute().ellipses),
                           [&] {
                               return fit_curved_ellipses(h, d, *v, bend, progress, [&](Bending b, const std::function<void(double)>& p) {
                                   return gpu_compute().ellipses(h, d, *v, b, p);
                               });
                           },
                           [&] { return fit_curved_ellipses(h, d, *v, bend, progress); }));
                   }
                   return stage_result(std::move(out));
               }});
        g.add({.name = "microgeom.ellipses",
               .help = "Fit a per-texel ellipse to the projections of the unshadowed directions (covariance start, optimised); on a curved base "
                       "interpolate the 5 fits of microgeom.ellipses_curved",
               .params = with(keys(kCurvatureKeys), {"microgeom.device"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.ellipses_curved"},
               .when = [](const Scene& s) { return any_object(s, [](const SceneObject& o) { return o.material.get_string("shadows") == "ellipse"; }); },
               .when_text = "microgeom.shadows is ellipse",
               .paper = PaperFigure{194e3, "Heidrich et al. 2000, Table 1: Bricks 128x128 shadow precompute (SGI Octane)"},
               .run = [](StageContext& ctx) {
                   const auto [hf, dirs, vis, imp, ell] = FieldInputs(ctx);
                   auto curved_fits = ctx.input<PerObject<CurvedEllipses>>("microgeom.ellipses_curved");
                   PerObject<EllipseMap> out;
                   out.items.resize(ctx.scene.objects.size());
                   std::map<const void*, std::shared_ptr<const EllipseMap>> done;
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const SceneObject& o = ctx.scene.objects[i];
                       const Visibility* v = vis->get(int(i));
                       if (!v || o.material.get_string("shadows") != "ellipse") continue;
                       const Heightfield& h = *hf->get(int(i));
                       if (const CurvedEllipses* c = curved_fits ? curved_fits->get(int(i)) : nullptr) {
                           const float cu = float(o.material.get_float("curvature_u")), cv = float(o.material.get_float("curvature_v"));
                           if (std::fabs(cu) > c->bend_deg || std::fabs(cv) > c->bend_deg)
                               ctx.warn(o.name + ": the curvature exceeds microgeom.ellipse_bend (" + std::to_string(int(c->bend_deg)) +
                                        " degrees): the ellipses are those of the largest fitted bend; raise ellipse_bend");
                           out.items[i] = std::make_shared<const EllipseMap>(interpolate_ellipses(*c, Bending::from_degrees(cu, cv, h.width, h.height)));
                           continue;
                       }
                       auto& slot = done[v];
                       if (!slot) {
                           const DirectionSet& d = *dirs->get(int(i));
                           const auto progress = [&](double f) { ctx.progress(f); };
                           slot = std::make_shared<const EllipseMap>(on_device(
                               ctx, o, "the ellipses", bool(gpu_compute().ellipses), [&] { return gpu_compute().ellipses(h, d, *v, Bending{}, progress); },
                               [&] { return fit_ellipses(h, d, *v, progress); }));
                       }
                       out.items[i] = slot;
                   }
                   return stage_result(std::move(out));
               }});
        // Geometry level of detail: the base re-tessellated at the texel rate and displaced.
        g.add({.name = "microgeom.displaced",
               .help = "Re-tessellate the base surface at one vertex per texel and displace it by the heights (lod = geometry)",
               .params = {"microgeom.lod", "microgeom.tiling", "geometry.type", "geometry.resolution", "geometry.minor_ratio"},
               .inputs = {"microgeom.heightfield"},
               .when = [](const Scene& s) { return any_object(s, [](const SceneObject& o) { return lod(o) == "geometry"; }); },
               .when_text = "microgeom.lod is geometry",
               .run = [](StageContext& ctx) {
                   auto hf = ctx.input<PerObject<Heightfield>>("microgeom.heightfield");
                   PerObject<TriMesh> out;
                   out.items.resize(ctx.scene.objects.size());
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const SceneObject& o = ctx.scene.objects[i];
                       const Heightfield* h = hf->get(int(i));
                       if (!h || lod(o) != "geometry") continue;
                       const std::string type = o.geometry.get_string("type");
                       if (type == "mesh") {
                           ctx.warn(o.name + ": microgeom.lod = geometry needs a procedural base (plane, sphere, cylinder, torus, teapot); the mesh is drawn undisplaced (bump level)");
                           continue;
                       }
                       bool capped = false;
                       const float tiling = float(o.material.get_float("tiling"));
                       const int res = displacement_resolution(type, int(o.geometry.get_int("resolution")), h->width, h->height, tiling, kMaxDisplacementSegments, &capped);
                       if (capped)
                           ctx.warn(o.name + ": the displaced geometry is capped at " + std::to_string(kMaxDisplacementSegments) +
                                    " segments, fewer than one vertex per texel: lower microgeom.tiling or the heightfield resolution");
                       if (type == "teapot")
                           ctx.warn(o.name + ": the teapot's 32 patches are displaced independently (each has its own cell of the uv atlas), so cracks can open along the patch borders");
                       out.items[i] = std::make_shared<const TriMesh>(displace(make_primitive(primitive_named(type), res, float(o.geometry.get_float("minor_ratio"))), *h, tiling));
                       ctx.progress(double(i + 1) / double(out.items.size()));
                   }
                   return stage_result(std::move(out));
               }});
        // BRDF level of detail: the virtual goniometer (§6).
        g.add({.name = "microgeom.brdf",
               .help = "Simulate the heightfield's BRDF with the virtual goniometer: average radiance of texture-space images with masking (lod = brdf)",
               .params = with(with(keys(kScatterKeys), keys(kBrdfKeys)), {"microgeom.device", "effects.indirect", "effects.environment"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "microgeom.ellipses"},
               .when = [](const Scene& s) { return any_object(s, [](const SceneObject& o) { return lod(o) == "brdf"; }); },
               .when_text = "microgeom.lod is brdf",
               .paper = PaperFigure{7.5 * 3600e3, "Heidrich et al. 2000, §6: a 16^4 BRDF would take about 7-8 hours (hardware, 2000)"},
               .run = [](StageContext& ctx) {
                   const auto [hf, dirs, vis, imp, ell] = FieldInputs(ctx);
                   PerObject<SimulatedBrdf> out;
                   out.items.resize(ctx.scene.objects.size());
                   for (size_t i = 0; i < out.items.size(); ++i) {
                       const SceneObject& o = ctx.scene.objects[i];
                       if (!hf->get(int(i)) || lod(o) != "brdf") continue;
                       const ParamTable& m = o.material;
                       GonioSettings gs;
                       gs.scatter = scatter_settings(m);
                       if (!ctx.scene.effect("indirect")) gs.scatter.depth = 0;
                       gs.scatter.importance = imp ? imp->get(int(i)) : nullptr;
                       gs.scatter.ellipses = ell ? ell->get(int(i)) : nullptr;
                       gs.phong = m.get_string("brdf") == "blinn-phong";
                       gs.ks = m.get_vec3("ks");
                       gs.shininess = float(m.get_float("shininess"));
                       gs.resolution = int(m.get_int("brdf_resolution"));
                       gs.fit = m.get_string("brdf_fit") == "sh" ? GonioSettings::Fit::SH : GonioSettings::Fit::Table;
                       gs.samples = int(m.get_int("brdf_samples"));
                       gs.sh_bands = int(m.get_int("sh_bands"));
                       gs.seed = uint32_t(m.get_int("scatter_seed"));
                       const Heightfield& h = *hf->get(int(i));
                       const DirectionSet& d = *dirs->get(int(i));
                       const Visibility& v = *vis->get(int(i));
                       out.items[i] = with_light_solver([&](const std::string& m) { ctx.warn(m); }, o, h, d, v, gs.scatter, [&](LightSolver* solver) {
                           gs.lights = solver;
                           return std::make_shared<const SimulatedBrdf>(simulate_brdf(h, d, v, gs, [&](double f) { ctx.progress((double(i) + f) / double(out.items.size())); }));
                       });
                   }
                   return stage_result(std::move(out));
               }});
        // Environment light scattered: independent of the light.
        g.add({.name = "microgeom.scatter_env",
               .help = "Environment light gathered where S_i has no hit, scattered microgeom.depth times",
               .params = with(with(keys(kScatterKeys), keys({"device"})), {"env.*"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "env.map"},
               .effects = {"environment"},
               .when = [](const Scene& s) { return any_object(s, [](const SceneObject& o) { return lod(o) != "brdf"; }); },
               .when_text = "an object's microgeom.lod is geometry or bump",
               .run = [](StageContext& ctx) {
                   return stage_result(scatter_env(ctx));
               }});
        // Every light scattered (their direct part is shaded per pixel): planar bases.
        g.add({.name = "microgeom.scatter",
               .help = "Each light scattered inside the heightfield (dependent tests), one solution per light (planar bases)",
               .params = with(with(keys(kScatterKeys), keys({"device"})), {"light.*", "geometry.type"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "microgeom.ellipses"},
               .effects = {"indirect"},
               .when = [](const Scene& s) {
                   return !s.lights.empty() && any_object(s, [&](const SceneObject& o) { return wants_light_scatter(o) && !direction_table(s, o); });
               },
               .when_text = "the scene has a light, microgeom.depth > 0, microgeom.lod is not brdf, the base is a plane and every light is directional",
               .paper = PaperFigure{12e3, "Heidrich et al. 2000, Table 1: Bricks 128x128, software render, 100 samples (SGI Octane)"},
               .run = [](StageContext& ctx) {
                   return stage_result(scatter_lights(ctx));
               }});
        // Non-planar bases: the light-driven scattering for every set direction above the horizon,
        // blended per pixel for each light's tangent-space direction; never depends on the light.
        g.add({.name = "microgeom.scatter_directions",
               .help = "Light scattered inside the heightfield for each of the ~N/2 set directions above the horizon, at unit irradiance (non-planar bases; "
                       "blended per pixel over the light's spherical triangle)",
               .params = with(with(keys(kScatterKeys), keys({"device"})), {"geometry.type"}),
               .inputs = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "microgeom.ellipses"},
               .effects = {"indirect"},
               .when = [](const Scene& s) {
                   return !s.lights.empty() && any_object(s, [&](const SceneObject& o) { return wants_light_scatter(o) && direction_table(s, o); });
               },
               .when_text = "the scene has a light, microgeom.depth > 0, microgeom.lod is not brdf, and the base is not a plane or a light is a point light",
               .run = [](StageContext& ctx) {
                   return stage_result(scatter_directions_stage(ctx));
               }});
    }

    // The GPU's gatherer where the object asks for it and OpenGL works; else null (the CPU), with a warning.
    static std::unique_ptr<Gatherer> make_gatherer(StageContext& ctx, const SceneObject& o) {
        if (o.material.get_string("device") != "gpu") return nullptr;
        try {
            if (!gpu_compute()) throw std::runtime_error("this build has no GPU compute");
            return gpu_compute().gatherer();
        } catch (const std::runtime_error& e) {
            ctx.warn(o.name + ": scattering computed on the CPU: the GPU was not available (" + first_line(e.what()) + ")");
            return nullptr;
        }
    }

    // solve(st) on the gatherer in st (the GPU), or on the CPU with a warning where the GPU fails.
    template <class Solve>
    static auto on_gpu_or_cpu(StageContext& ctx, const SceneObject& o, ScatterSettings st, const Solve& solve) {
        if (st.gatherer) {
            try {
                return solve(st);
            } catch (const Cancelled&) {
                throw;
            } catch (const InputError&) {
                throw;
            } catch (const std::runtime_error& e) {
                ctx.warn(o.name + ": scattering computed on the CPU: the GPU could not (" + first_line(e.what()) + ")");
                st.gatherer = nullptr;
            }
        }
        return solve(st);
    }

    static ScatterResult scatter_on(StageContext& ctx, const SceneObject& o, const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis,
                                    const ScatterSettings& st, const std::function<void(double)>& progress) {
        return on_gpu_or_cpu(ctx, o, st, [&](const ScatterSettings& s) { return scatter(hf, dirs, vis, s, progress); });
    }

    // The environment's scattering solution per object.
    static PerObject<LightScatter> scatter_env(StageContext& ctx) {
        const auto [hf, dirs, vis, imp, ell] = FieldInputs(ctx);
        Environment env;
        env.color = ctx.scene.env.get_vec3("color");
        env.intensity = float(ctx.scene.env.get_float("intensity"));
        env.map = ctx.input<Image>("env.map");
        PerObject<LightScatter> out;
        out.items.resize(ctx.scene.objects.size());
        for (size_t i = 0; i < out.items.size(); ++i) {
            const SceneObject& o = ctx.scene.objects[i];
            if (!hf->get(int(i)) || lod(o) == "brdf") continue;
            LightScatter ls;
            ScatterSettings st = scatter_settings(o.material);
            st.importance = imp ? imp->get(int(i)) : nullptr;
            st.env = &env;
            const auto gatherer = make_gatherer(ctx, o);
            st.gatherer = gatherer.get();
            ls.result = scatter_on(ctx, o, *hf->get(int(i)), *dirs->get(int(i)), *vis->get(int(i)), st, [&](double f) { ctx.progress((double(i) + f) / double(out.items.size())); });
            out.items[i] = std::make_shared<const LightScatter>(std::move(ls));
        }
        return out;
    }

    // One solution per planar object and light, at unit irradiance from the light's direction
    // (non-planar bases: scatter_directions).
    static PerObject<LightsScatter> scatter_lights(StageContext& ctx) {
        const auto [hf, dirs, vis, imp, ell] = FieldInputs(ctx);
        PerObject<LightsScatter> out;
        out.items.resize(ctx.scene.objects.size());
        const size_t L = ctx.scene.lights.size();
        for (size_t i = 0; i < out.items.size(); ++i) {
            const SceneObject& o = ctx.scene.objects[i];
            if (!hf->get(int(i)) || !wants_light_scatter(o) || direction_table(ctx.scene, o)) continue;
            LightsScatter all;
            const auto gatherer = make_gatherer(ctx, o);
            for (size_t li = 0; li < L; ++li) {
                LightScatter ls;
                ScatterSettings st = scatter_settings(o.material);
                st.importance = imp ? imp->get(int(i)) : nullptr;
                st.ellipses = ell ? ell->get(int(i)) : nullptr;
                ls.light_dir = light_local(ctx.scene, o, li);
                st.light_dir = ls.light_dir;
                st.light_E = vec3(1.f);
                st.gatherer = gatherer.get();
                ls.result = scatter_on(ctx, o, *hf->get(int(i)), *dirs->get(int(i)), *vis->get(int(i)), st, [&](double f) {
                    ctx.progress((double(i) + (double(li) + f) / double(L)) / double(out.items.size()));
                });
                all.lights.push_back(std::move(ls));
            }
            out.items[i] = std::make_shared<const LightsScatter>(std::move(all));
        }
        return out;
    }

    // Non-planar objects: the light-driven scattering for every set direction above the horizon
    // (scatter.h DirectionalScatter), on the object's device; the GPU's failure falls back to the CPU.
    static PerObject<DirectionalScatter> scatter_directions_stage(StageContext& ctx) {
        const auto [hf, dirs, vis, imp, ell] = FieldInputs(ctx);
        PerObject<DirectionalScatter> out;
        out.items.resize(ctx.scene.objects.size());
        for (size_t i = 0; i < out.items.size(); ++i) {
            const SceneObject& o = ctx.scene.objects[i];
            if (!hf->get(int(i)) || !wants_light_scatter(o) || !direction_table(ctx.scene, o)) continue;
            ScatterSettings st = scatter_settings(o.material);
            st.importance = imp ? imp->get(int(i)) : nullptr;
            st.ellipses = ell ? ell->get(int(i)) : nullptr;
            const auto progress = [&](double f) { ctx.progress((double(i) + f) / double(out.items.size())); };
            const auto gatherer = make_gatherer(ctx, o);
            st.gatherer = gatherer.get();
            DirectionalScatter table = on_gpu_or_cpu(ctx, o, st, [&](const ScatterSettings& s) {
                return scatter_directions(*hf->get(int(i)), *dirs->get(int(i)), *vis->get(int(i)), s, progress);
            });
            out.items[i] = std::make_shared<const DirectionalScatter>(std::move(table));
        }
        return out;
    }

    std::vector<std::string> frame_stages() const override {
        return {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "microgeom.ellipses_curved", "microgeom.ellipses",
                "microgeom.scatter_env", "microgeom.scatter", "microgeom.scatter_directions", "microgeom.displaced", "microgeom.brdf"};
    }

    std::shared_ptr<const TriMesh> object_mesh(const Scene&, const Evaluation& ev, int object) const override {
        auto d = ev.get<PerObject<TriMesh>>("microgeom.displaced");
        if (!d || !d->get(object)) return nullptr;
        return d->items[size_t(object)];
    }

    std::optional<ivec2> texture_size(const Scene& s, const Evaluation& ev) const override {
        auto hf = ev.get<PerObject<Heightfield>>("microgeom.heightfield");
        for (size_t i = 0; hf && i < s.objects.size(); ++i)
            if (const Heightfield* h = hf->get(int(i))) return ivec2(h->width, h->height);
        return std::nullopt;
    }

    void shade_cpu(const ShadeContext& ctx) const override;
    std::vector<BenchTable> bench_tables() const override;
    std::vector<ExportDecl> exports() const override;
};

// [SECTION] CPU shading (bump level of detail; texture mode = the heightfield's texels 1:1)
void MicrogeomTechnique::shade_cpu(const ShadeContext& ctx) const {
    auto hfs = ctx.eval.get<PerObject<Heightfield>>("microgeom.heightfield");
    auto dirss = ctx.eval.get<PerObject<DirectionSet>>("microgeom.directions");
    auto viss = ctx.eval.get<PerObject<Visibility>>("microgeom.visibility");
    auto envs = ctx.eval.get<PerObject<LightScatter>>("microgeom.scatter_env");
    auto lights = ctx.eval.get<PerObject<LightsScatter>>("microgeom.scatter");
    auto tables = ctx.eval.get<PerObject<DirectionalScatter>>("microgeom.scatter_directions");
    const GBuffer& gb = ctx.gbuffer;
    Image& rad = ctx.frame.aov("radiance");
    Image& nrm = ctx.frame.aov("normal");
    Image& dir_img = ctx.frame.aov("direct");
    Image& ind_img = ctx.frame.aov("indirect");
    Image& sh_img = ctx.frame.aov("shadow");
    Image& fold_img = ctx.frame.aov("folded");
    auto imps = ctx.eval.get<PerObject<Importance>>("microgeom.importance");
    auto ells = ctx.eval.get<PerObject<EllipseMap>>("microgeom.ellipses");
    auto brdfs = ctx.eval.get<PerObject<SimulatedBrdf>>("microgeom.brdf");
    // One pixel's AOVs.
    auto store = [&](int x, int y, vec3 L, vec3 n, vec3 direct, vec3 indirect, float shadow) {
        for (auto [img, v] : {std::pair{&rad, L}, std::pair{&nrm, n}, std::pair{&dir_img, direct}, std::pair{&ind_img, indirect}}) {
            float* q = img->at(x, y);
            q[0] = v.x, q[1] = v.y, q[2] = v.z;
        }
        sh_img.at(x, y)[0] = shadow;
    };

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
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec3 N = frame.N, T = frame.T, B = frame.B;
            const float tiling = ctx.camera.texture_mode ? 1.f : float(m.get_float("tiling"));
            const vec2 uv = gb.uv[px];
            const float c = uv.x * float(hf.width) * tiling - 0.5f, r = (1.f - uv.y) * float(hf.height) * tiling - 0.5f;
            auto to_local = [&](vec3 w) { return frame.to_local(w); };

            // BRDF level: a smooth surface with the simulated BRDF (it folds in shadows, masking and
            // scattering); the environment part is exact for a constant environment and scaled by the
            // irradiance at the macro normal for a map.
            if (const SimulatedBrdf* brdf = brdfs ? brdfs->get(obj) : nullptr) {
                const vec3 v_loc = to_local(wo);
                vec3 Lo_lights(0.f);
                float shadow_first = 0.f;
                for (size_t li = 0; li < ctx.lighting.lights.size(); ++li) {
                    vec3 wi, E;
                    ctx.lighting.lights[li].sample(p, wi, E);
                    const vec3 l_loc = to_local(wi);
                    Lo_lights += brdf->eval(l_loc, v_loc) * E;
                    if (li == 0) shadow_first = brdf->eval_shadow(l_loc, v_loc);
                }
                const vec3 Lo_env = ctx.lighting.env_lighting ? brdf->eval_env(v_loc) * ctx.lighting.env_irradiance(N) * kInvPi : vec3(0.f);
                store(x, y, Lo_lights + Lo_env, N, Lo_lights, Lo_env, shadow_first);
                continue;
            }

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

            // Scattered light: environment part, plus each light's part scaled by its irradiance
            // (non-planar bases: blended over the spherical triangle of its tangent-space direction).
            vec3 E_ind(0.f);
            const LightScatter* es = envs ? envs->get(obj) : nullptr;
            if (es) E_ind += sample_bilinear(es->result.E_indirect, hf.width, hf.height, true, c, r);
            const LightsScatter* ls = lights ? lights->get(obj) : nullptr;
            for (size_t li = 0; ls && li < std::min(ls->lights.size(), ctx.lighting.lights.size()); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                E_ind += sample_bilinear(ls->lights[li].result.E_indirect, hf.width, hf.height, true, c, r) * E;
            }
            const DirectionalScatter* table = tables ? tables->get(obj) : nullptr;
            for (size_t li = 0; table && li < ctx.lighting.lights.size(); ++li) {
                vec3 wi, E;
                ctx.lighting.lights[li].sample(p, wi, E);
                E_ind += table->irradiance(dirs, glm::normalize(to_local(wi)), c, r) * E;
            }
            const vec3 indirect = albedo * kInvPi * E_ind;
            store(x, y, direct + indirect, n, direct, indirect, shadow0);
            const Importance* imp = imps ? imps->get(obj) : nullptr;
            if (imp && !imp->folded.empty()) {
                const int fx = ((int(std::floor(c + 0.5f)) % hf.width) + hf.width) % hf.width, fy = ((int(std::floor(r + 0.5f)) % hf.height) + hf.height) % hf.height;
                fold_img.at(x, y)[0] = float(imp->folded[hf.index(fx, fy)]);
            }
        }
    });
}

// [SECTION] BTF export (§6)
namespace {
ivec2 parse_grid(const std::string& key, const std::string& text) {
    int a = 0, b = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &a, &x, &b, &extra) != 3 || (x != 'x' && x != 'X') || a < 1 || b < 1 || a > 64 || b > 128)
        throw InputError("--option " + key + "=" + text + ": expected THETAxPHI with 1..64 theta and 1..128 phi steps, e.g. 4x8");
    return {a, b};
}
}  // namespace

std::vector<ExportDecl> MicrogeomTechnique::exports() const {
    ExportDecl btf;
    btf.name = "btf";
    btf.help = "Light field / BTF: a view x light grid of texture-space heightfield images (shadows, scattering, masking) as one EXR mosaic";
    btf.options_help = "grid=THETAxPHI (default 4x8; both lights and views), lights=THETAxPHI, views=THETAxPHI";
    btf.stages = {"microgeom.heightfield", "microgeom.directions", "microgeom.visibility", "microgeom.importance", "microgeom.ellipses_curved", "microgeom.ellipses"};
    btf.run = [](const Scene& s, const Evaluation& ev, int object, const std::map<std::string, std::string>& options, const std::string& path,
                 const ProgressFn& progress) {
        ivec2 lg(4, 8), vg(4, 8);
        for (const auto& [k, v] : options) {
            if (k == "grid") lg = vg = parse_grid(k, v);
            else if (k == "lights") lg = parse_grid(k, v);
            else if (k == "views") vg = parse_grid(k, v);
            else throw InputError("--option " + k + ": unknown option of export btf (accepts grid, lights, views)");
        }
        for (const auto& [k, v] : options)  // explicit lights/views win over grid whatever the order
            if (k == "lights") lg = parse_grid(k, v);
            else if (k == "views") vg = parse_grid(k, v);
        const SceneObject& o = s.objects[size_t(object)];
        const Heightfield& hf = *ev.get<PerObject<Heightfield>>("microgeom.heightfield")->get(object);
        const DirectionSet& dirs = *ev.get<PerObject<DirectionSet>>("microgeom.directions")->get(object);
        const Visibility& vis = *ev.get<PerObject<Visibility>>("microgeom.visibility")->get(object);
        auto imp = ev.get<PerObject<Importance>>("microgeom.importance");
        auto ell = ev.get<PerObject<EllipseMap>>("microgeom.ellipses");
        GonioSettings gs;
        gs.scatter = scatter_settings(o.material);
        if (!s.effect("indirect")) gs.scatter.depth = 0;
        gs.scatter.importance = imp ? imp->get(object) : nullptr;
        gs.scatter.ellipses = ell ? ell->get(object) : nullptr;
        gs.phong = o.material.get_string("brdf") == "blinn-phong";
        gs.ks = o.material.get_vec3("ks");
        gs.shininess = float(o.material.get_float("shininess"));
        const std::vector<vec3> lights = btf_directions(lg.x, lg.y), views = btf_directions(vg.x, vg.y);
        const auto t0 = std::chrono::steady_clock::now();
        std::string warnings;
        const Image mosaic = with_light_solver([&](const std::string& m) { warnings += "\nwarning: " + m; }, o, hf, dirs, vis, gs.scatter,
                                                                   [&](LightSolver* solver) {
                                                                       gs.lights = solver;
                                                                       return btf_mosaic(hf, dirs, vis, gs, lights, views, [&](double f) { if (progress) progress("export.btf", f); });
                                                                   });
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        write_exr(path, mosaic);
        // Sidecar: layout and directions.
        nlohmann::json j;
        j["export"] = "btf";
        j["object"] = o.name;
        j["tile"] = {hf.width, hf.height};
        j["layout"] = "tile (row = light index, column = view index); tile row 0 = heightfield row 0 (top)";
        auto list = [](ivec2 g) {
            nlohmann::json a = nlohmann::json::array();
            for (int i = 0; i < g.x; ++i)
                for (int k = 0; k < g.y; ++k) a.push_back({(double(i) + 0.5) * 90.0 / g.x, double(k) * 360.0 / g.y});
            return a;
        };
        j["lights_theta_phi_deg"] = list(lg);
        j["views_theta_phi_deg"] = list(vg);
        j["unit"] = "radiance towards the view per unit irradiance from the light (at normal incidence to the light); 0 where masked";
        j["compute_ms"] = ms;
        write_text_atomic(path + ".json", j.dump(2) + "\n");
        char buf[256];
        std::snprintf(buf, sizeof buf, "btf: %zu lights x %zu views of %dx%d texels (%dx%d EXR), computed in %.0f ms; directions in %s.json", lights.size(), views.size(),
                      hf.width, hf.height, mosaic.width, mosaic.height, ms, path.c_str());
        return std::string(buf) + warnings;
    };
    return {btf};
}

// [SECTION] Table 1
std::vector<BenchTable> MicrogeomTechnique::bench_tables() const {
    auto scene = [](const char* field, int res, std::vector<std::pair<const char*, const char*>> extra = {}) {
        return [=] {
            Scene s = default_scene("microgeom");
            s.name = std::string(field) + std::to_string(res);
            apply_set(s, "camera.mode", "texture");
            apply_set(s, "geometry.type", "plane");
            apply_set(s, "microgeom.heightfield", field);
            apply_set(s, "microgeom.resolution", std::to_string(res));
            apply_set(s, "microgeom.directions", "100");
            apply_set(s, "microgeom.shadows", "ellipse");
            for (const auto& [k, v] : extra) apply_set(s, k, v);
            return s;
        };
    };
    auto mb = [](size_t bytes) {
        char b[32];
        std::snprintf(b, sizeof b, "%.2f MB", double(bytes) / 1048576.0);
        return std::string(b);
    };
    BenchTable t;
    t.name = "microgeom";
    t.title = "Heidrich et al. 2000, Table 1: precomputation and rendering (100 directions)";
    t.paper_machine = "SGI Octane 300 MHz R12000 (software) / GeForce 256 (hardware), seconds converted to ms";
    BenchColumn memory;
    memory.name = "memory: S_i / ellipses / scattered light";
    memory.info = [mb](const Scene& s, const Evaluation& ev) {
        auto vis = ev.get<PerObject<Visibility>>("microgeom.visibility");
        auto ell = ev.get<PerObject<EllipseMap>>("microgeom.ellipses");
        auto sc = ev.get<PerObject<LightsScatter>>("microgeom.scatter");
        auto table = ev.get<PerObject<DirectionalScatter>>("microgeom.scatter_directions");
        (void)s;
        const size_t v = vis && vis->get(0) ? vis->get(0)->bytes() : 0, e = ell && ell->get(0) ? ell->get(0)->bytes() : 0;
        size_t l = 0;
        if (sc && sc->get(0))
            for (const LightScatter& one : sc->get(0)->lights) l += one.result.E_indirect.size() * sizeof(vec3);
        if (table && table->get(0)) l += table->get(0)->bytes();
        return mb(v) + " / " + mb(e) + " / " + mb(l);
    };
    BenchColumn vis_col{"S_i precompute", "microgeom.visibility"};
    vis_col.gpu_set = "microgeom.device=gpu";
    BenchColumn scatter_col{"software render (scattering, depth 2, all 100 directions)", "microgeom.scatter"};
    scatter_col.gpu_set = "microgeom.device=gpu";
    BenchColumn ellipse_col{"shadow (ellipse) precompute", "microgeom.ellipses"};
    ellipse_col.gpu_set = "microgeom.device=gpu";
    t.columns = {vis_col,
                 ellipse_col,
                 scatter_col,
                 {"frame (texture space, 1 pixel per texel; GPU = hardware render)", "", 0, 0, true, true},
                 memory};
    t.rows = {{"Triangles 32x32", scene("triangles", 32), {27e3, 32e3, 10e3, 480}},
              {"Bricks 128x128", scene("bricks", 128), {1029e3, 194e3, 12e3, 2100}},
              {"Bumps 32x32", scene("bumps", 32), {109e3, 65e3, 8e3, 480}},
              {"Bricks 512x512", scene("bricks", 512), {}},
              {"Bricks 1024x1024", scene("bricks", 1024), {}}};

    BenchTable lod;
    lod.name = "microgeom-brdf";
    lod.title = "Heidrich et al. 2000, §6: simulated BRDF (virtual goniometer) and displaced geometry, Bricks 128x128, 100 directions, depth 2";
    lod.paper_machine = "SGI Octane + GeForce 256 (hardware goniometer images)";
    BenchColumn brdf_mem;
    brdf_mem.name = "memory";
    brdf_mem.info = [mb](const Scene&, const Evaluation& ev) {
        auto b = ev.get<PerObject<SimulatedBrdf>>("microgeom.brdf");
        auto d = ev.get<PerObject<TriMesh>>("microgeom.displaced");
        if (b && b->get(0)) return mb(b->get(0)->bytes()) + " (" + std::to_string(b->get(0)->images) + " images)";
        if (d && d->get(0)) return mb(d->get(0)->vertex_count() * (3 * sizeof(vec3) + sizeof(vec2)) + d->get(0)->index.size() * 4) + " (" +
                                   std::to_string(d->get(0)->triangle_count()) + " triangles)";
        return std::string("—");
    };
    BenchColumn brdf_col{"precompute", "microgeom.brdf"};
    brdf_col.gpu_set = "microgeom.device=gpu";
    lod.columns = {brdf_col, brdf_mem};
    lod.rows = {{"BRDF table 8^4", scene("bricks", 128, {{"microgeom.lod", "brdf"}, {"microgeom.brdf_resolution", "8"}, {"microgeom.shadows", "exact"}}), {}},
                {"BRDF table 16^4", scene("bricks", 128, {{"microgeom.lod", "brdf"}, {"microgeom.brdf_resolution", "16"}, {"microgeom.shadows", "exact"}}), {7.5 * 3600e3}},
                {"BRDF SH, 300 random images, 3 bands", scene("bricks", 128, {{"microgeom.lod", "brdf"}, {"microgeom.brdf_fit", "sh"}, {"microgeom.shadows", "exact"}}), {}}};
    BenchTable geo;
    geo.name = "microgeom-geometry";
    geo.title = "Displaced geometry level of detail: Bricks 128x128 tiled 4x4 on a sphere (one vertex per texel), 512x512 frame";
    geo.columns = {{"displace (re-tessellate + displace)", "microgeom.displaced"}, {"frame 512x512", "", 512, 512, true, true}, brdf_mem};
    geo.rows = {{"Bricks 128x128 on a sphere", [scene] {
                     Scene s = scene("bricks", 128, {{"microgeom.lod", "geometry"}, {"microgeom.shadows", "exact"}})();
                     apply_set(s, "camera.mode", "orbit");
                     apply_set(s, "geometry.type", "sphere");
                     return s;
                 }, {}}};
    BenchTable curved_t;
    curved_t.name = "microgeom-curved";
    curved_t.title = "Scattering on a non-planar base: Bricks 128x128 on a sphere, 100 directions (50 above the horizon), depth 2";
    BenchColumn table_col{"scattering for 50 light directions", "microgeom.scatter_directions"};
    table_col.gpu_set = "microgeom.device=gpu";
    BenchColumn table_mem;
    table_mem.name = "memory: scattered light";
    table_mem.info = [mb](const Scene&, const Evaluation& ev) {
        auto table = ev.get<PerObject<DirectionalScatter>>("microgeom.scatter_directions");
        if (!table || !table->get(0)) return std::string("—");
        return mb(table->get(0)->bytes()) + " (" + std::to_string(table->get(0)->count) + " directions)";
    };
    curved_t.columns = {table_col, {"frame 512x512", "", 512, 512, true, true}, table_mem};
    curved_t.rows = {{"Bricks 128x128 on a sphere", [scene] {
                          Scene s = scene("bricks", 128, {{"microgeom.shadows", "exact"}})();
                          apply_set(s, "camera.mode", "orbit");
                          apply_set(s, "geometry.type", "sphere");
                          return s;
                      }, {}}};
    return {t, lod, geo, curved_t};
}
}  // namespace
}  // namespace mesolab::microgeom

namespace mesolab {
void register_microgeom(Registry& r) { r.add(std::make_unique<microgeom::MicrogeomTechnique>()); }
}  // namespace mesolab
