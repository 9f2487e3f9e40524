// Technique microgeom: the stage graph (see microgeom.h for the stages and technique.h for the files).
#include "core/error.h"
#include "core/heightfield/params.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/lod.h"
#include "core/microgeom/paper.h"
#include "core/microgeom/technique.h"
#include "core/scene_stages.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

namespace mesolab::microgeom {

// [SECTION] Scattering settings (shared with the BTF export)
ScatterSettings scatter_settings(const ParamTable& m) {
    ScatterSettings st;
    st.depth = int(m.get_int("depth"));
    st.all_directions = m.get_string("sampling") == "all";
    st.paths = int(m.get_int("paths"));
    st.seed = uint32_t(m.get_int("scatter_seed"));
    st.shadows = m.get_string("shadows") != "none";
    return st;
}

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

// [SECTION] GPU or CPU
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

// The GPU's gatherer where the object asks for it and OpenGL works; else null (the CPU), with a warning.
std::unique_ptr<Gatherer> make_gatherer(StageContext& ctx, const SceneObject& o) {
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
auto on_gpu_or_cpu(StageContext& ctx, const SceneObject& o, ScatterSettings st, const Solve& solve) {
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

ScatterResult scatter_on(StageContext& ctx, const SceneObject& o, const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis,
                         const ScatterSettings& st, const std::function<void(double)>& progress) {
    return on_gpu_or_cpu(ctx, o, st, [&](const ScatterSettings& s) { return scatter(hf, dirs, vis, s, progress); });
}

// [SECTION] Scattering stages
// The environment's scattering solution per object.
PerObject<LightScatter> scatter_env(StageContext& ctx) {
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
PerObject<LightsScatter> scatter_lights(StageContext& ctx) {
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
PerObject<DirectionalScatter> scatter_directions_stage(StageContext& ctx) {
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
}  // namespace

// [SECTION] The stages
void MicrogeomTechnique::declare_stages(StageGraph& g) const {
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
           .paper = paper::kBricks128.visibility,
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
           .paper = paper::kBricks128.shadows,
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
           .paper = paper::kBrdf16,
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
           .paper = paper::kBricks128.scattering,
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
}  // namespace mesolab::microgeom
