// Technique microgeom: the stage graph (see microgeom.h for the stages and technique.h for the files).
#include "core/error.h"
#include "core/gpu_or_cpu.h"
#include "core/heightfield/params.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/lod.h"
#include "core/microgeom/paper.h"
#include "core/microgeom/stages.h"
#include "core/blob.h"
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

// [SECTION] Helpers
std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}
std::vector<std::string> keys(const std::vector<std::string>& ks) {
    std::vector<std::string> r;
    for (const auto& k : ks) r.push_back("microgeom." + k);
    return r;
}

const std::vector<std::string> kFieldKeys = with(heightfield_keys(), {"albedo", "albedo_map"});
const std::vector<std::string> kScatterKeys{"depth", "sampling", "paths", "scatter_seed", "shadows"};
const std::vector<std::string> kCurvatureKeys{"curvature_u", "curvature_v"};
const std::vector<std::string> kBrdfKeys{"lod", "brdf_fit", "brdf_resolution", "brdf_samples", "sh_bands", "brdf", "ks", "shininess"};
constexpr int kMaxDisplacementSegments = 2048;

std::string lod(const SceneObject& o) { return o.material.get_string("lod"); }
bool texture_mode(const Scene& s) { return s.camera.get_string("mode") == "texture"; }
bool curved(const SceneObject& o) { return o.material.get_float("curvature_u") != 0.0 || o.material.get_float("curvature_v") != 0.0; }
bool ellipse_shadows(const SceneObject& o) { return o.material.get_string("shadows") == "ellipse"; }
bool want_gpu(const StageContext& ctx) { return ctx.material().get_string("device") == "gpu"; }

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

// The results of the object's upstream stages most stages read (null where one did not run).
struct FieldInputs {
    explicit FieldInputs(const StageContext& ctx)
        : hf(ctx.input(stages::heightfield)), dirs(ctx.input(stages::directions)),
          vis(ctx.input(stages::visibility)), imp(ctx.input(stages::importance)),
          ell(ctx.input(stages::ellipses)) {}
    std::shared_ptr<const Heightfield> hf;
    std::shared_ptr<const DirectionSet> dirs;
    std::shared_ptr<const Visibility> vis;
    std::shared_ptr<const Importance> imp;
    std::shared_ptr<const EllipseMap> ell;
    size_t texels() const { return size_t(hf->width) * size_t(hf->height); }
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

// solve(settings) with the GPU's gatherer where the object asks for it, else on the CPU (gpu_or_cpu).
template <class Solve>
auto scatter_on_device(StageContext& ctx, ScatterSettings st, const Solve& solve) {
    return gpu_or_cpu(
        ctx, want_gpu(ctx), "scattering",
        [&] {
            require_gpu(bool(gpu_compute()));
            const std::unique_ptr<Gatherer> gatherer = gpu_compute().gatherer();
            st.gatherer = gatherer.get();
            return solve(st);
        },
        [&] {
            st.gatherer = nullptr;
            return solve(st);
        });
}

// [SECTION] Memory estimates (the results' own sizes, plus the solvers' working arrays)
MemoryEstimate memory_of(double bytes, std::string what, std::vector<std::string> lower) { return {bytes, std::move(what), std::move(lower)}; }
std::string texels_text(const Heightfield& hf) { return std::to_string(hf.width) + "x" + std::to_string(hf.height) + " texels"; }
double scatter_working_bytes(const FieldInputs& in) {
    // A solution (E_indirect, shadow, direct) and the bounces' gather arrays: about 6 vec3 per texel.
    return double(in.texels()) * 6.0 * sizeof(vec3);
}

// [SECTION] Scattering stages
// The environment's scattering solution.
LightScatter scatter_env(StageContext& ctx) {
    const FieldInputs in(ctx);
    Environment env;
    env.color = ctx.scene.env.get_vec3("color");
    env.intensity = float(ctx.scene.env.get_float("intensity"));
    env.map = ctx.input(mesolab::stages::env_map);
    LightScatter ls;
    ScatterSettings st = scatter_settings(ctx.material());
    st.importance = in.imp.get();
    st.env = &env;
    ls.result = scatter_on_device(ctx, st, [&](const ScatterSettings& s) { return scatter(*in.hf, *in.dirs, *in.vis, s, [&](double f) { ctx.progress(f); }); });
    return ls;
}

// One solution per light of a planar object, at unit irradiance from the light's direction
// (non-planar bases: scatter_directions).
LightsScatter scatter_lights(StageContext& ctx) {
    const FieldInputs in(ctx);
    const size_t L = ctx.scene.lights.size();
    ScatterSettings st = scatter_settings(ctx.material());
    st.importance = in.imp.get();
    st.ellipses = in.ell.get();
    st.light_E = vec3(1.f);
    return scatter_on_device(ctx, st, [&](ScatterSettings s) {
        LightsScatter all;
        for (size_t li = 0; li < L; ++li) {
            LightScatter ls;
            ls.light_dir = light_local(ctx.scene, ctx.obj(), li);
            s.light_dir = ls.light_dir;
            ls.result = scatter(*in.hf, *in.dirs, *in.vis, s, [&](double f) { ctx.progress((double(li) + f) / double(L)); });
            all.lights.push_back(std::move(ls));
        }
        return all;
    });
}

// Non-planar objects: the light-driven scattering for every set direction above the horizon
// (scatter.h DirectionalScatter).
DirectionalScatter scatter_directions_stage(StageContext& ctx) {
    const FieldInputs in(ctx);
    ScatterSettings st = scatter_settings(ctx.material());
    st.importance = in.imp.get();
    st.ellipses = in.ell.get();
    return scatter_on_device(ctx, st, [&](const ScatterSettings& s) {
        return scatter_directions(*in.hf, *in.dirs, *in.vis, s, [&](double f) { ctx.progress(f); });
    });
}
}  // namespace

// [SECTION] The stages
namespace {
// [SECTION] The ellipse fits on disk (core/stage_store.h)
void write_ellipse_map(BlobWriter& w, const EllipseMap& m) {
    w.put(int32_t(m.width)), w.put(int32_t(m.height)), w.put(m.edge);
    w.put_vector(m.e);
}
EllipseMap read_ellipse_map(BlobReader& r) {
    EllipseMap m;
    m.width = r.get<int32_t>(), m.height = r.get<int32_t>(), m.edge = r.get<float>();
    m.e = r.get_vector<Ellipse>();
    if (m.e.size() != size_t(m.width) * size_t(m.height)) throw BlobError("ellipses: sizes do not match");
    return m;
}
void write_curved_ellipses(BlobWriter& w, const CurvedEllipses& c) {
    w.put(c.bend_deg), w.put(c.step_u), w.put(c.step_v);
    for (const EllipseMap* m : {&c.flat, &c.u_pos, &c.u_neg, &c.v_pos, &c.v_neg}) write_ellipse_map(w, *m);
}
CurvedEllipses read_curved_ellipses(BlobReader& r) {
    CurvedEllipses c;
    c.bend_deg = r.get<float>(), c.step_u = r.get<Bending>(), c.step_v = r.get<Bending>();
    for (EllipseMap* m : {&c.flat, &c.u_pos, &c.u_neg, &c.v_pos, &c.v_neg}) *m = read_ellipse_map(r);
    return c;
}

}  // namespace

void MicrogeomTechnique::declare_stages(StageGraph& g) const {
    // Every stage is an object stage: one result per object, shared by objects with equal keys.
    const auto object = [](StageDecl d) {
        d.scope = StageScope::Object;
        d.technique = "microgeom";
        return d;
    };
    g.add(stages::heightfield, object({.help = "Build or read the heightfield",
                  .params = keys(kFieldKeys),
                  .memory = [](const StageContext& ctx) {
                      const ParamTable& m = ctx.material();
                      if (m.group().find("heightfield")->is_file(m.get("heightfield"))) return MemoryEstimate{};  // the image's size bounds it
                      const double n = double(m.get_int("resolution"));
                      return memory_of(n * n * double(sizeof(float) + sizeof(vec3)), std::to_string(int(n)) + "^2 heights and albedos",
                                       {"microgeom.resolution"});
                  },
                  .run = [](StageContext& ctx) {
                      const ParamTable& m = ctx.material();
                      Heightfield hf = heightfield_from_material(ctx.scene, m);
                      const std::string albedo_map = m.get_string("albedo_map");
                      if (!albedo_map.empty()) apply_albedo_map(hf, ctx.scene.resolve(albedo_map), m.get_vec3("albedo"), "microgeom.albedo_map");
                      return stage_result(stages::heightfield, std::move(hf));
                  }}));
    g.add(stages::directions, object({.help = "N directions over the sphere and their spherical triangulation",
                  .params = {"microgeom.directions"},
                  .run = [](StageContext& ctx) { return stage_result(stages::directions, make_direction_set(int(ctx.material().get_int("directions")))); }}));
    g.add(stages::visibility, object({.help = "Visibility textures S_i: first hit for every direction and texel (on microgeom.device)",
                  .params = keys({"device"}),
                  .inputs = {stages::heightfield, stages::directions},
                  .paper = paper::kBricks128.visibility,
                  .memory = [](const StageContext& ctx) {
                      const FieldInputs in(ctx);
                      return memory_of(double(in.texels()) * double(in.dirs->d.size()) * sizeof(uint32_t),
                                       "S_i: " + texels_text(*in.hf) + " x " + std::to_string(in.dirs->d.size()) + " directions x 4 bytes",
                                       {"microgeom.resolution", "microgeom.directions"});
                  },
                  .run = [](StageContext& ctx) {
                      const FieldInputs in(ctx);
                      return stage_result(stages::visibility, gpu_or_cpu(
                          ctx, want_gpu(ctx), "S_i",
                          [&] {
                              require_gpu(bool(gpu_compute()));
                              return gpu_compute().visibility(*in.hf, *in.dirs);
                          },
                          [&] { return compute_visibility(*in.hf, *in.dirs, [&](double f) { ctx.progress(f); }); }));
                  },
                  // Kept on disk: the first hits (a device's own copy is made again where a pass needs it).
                  .disk = stage_codec(
                      stages::visibility,
                      [](BlobWriter& w, const Visibility& v) {
                          w.put(int32_t(v.width)), w.put(int32_t(v.height)), w.put(int32_t(v.count));
                          w.put_vector(v.hit);
                      },
                      [](BlobReader& r) {
                          Visibility v;
                          v.width = r.get<int32_t>(), v.height = r.get<int32_t>(), v.count = r.get<int32_t>();
                          v.hit = r.get_vector<uint32_t, HitArray::allocator_type>();
                          if (v.hit.size() != size_t(v.width) * size_t(v.height) * size_t(v.count)) throw BlobError("S_i: sizes do not match");
                          return v;
                      })}));
    // Curved base: fan-area importance of the bent directions (never recomputes S_i).
    g.add(stages::importance, object({.help = "Bend the directions by the base curvature and weight them by the relative triangle-fan area (§5)",
                  .params = with(keys(kCurvatureKeys), {"microgeom.device"}),
                  .inputs = {stages::heightfield, stages::directions, stages::visibility},
                  .applies = [](const Scene&, const SceneObject& o) { return curved(o); },
                  .when_text = "microgeom.curvature_u or curvature_v is not 0",
                  .memory = [](const StageContext& ctx) {
                      const FieldInputs in(ctx);
                      return memory_of(double(in.texels()) * (double(in.dirs->d.size()) * 2.0 * sizeof(float) + 1.0),
                                       "importance and weights: " + texels_text(*in.hf) + " x " + std::to_string(in.dirs->d.size()) + " directions x 8 bytes",
                                       {"microgeom.resolution", "microgeom.directions"});
                  },
                  .run = [](StageContext& ctx) {
                      const FieldInputs in(ctx);
                      const ParamTable& m = ctx.material();
                      const Bending b = Bending::from_degrees(float(m.get_float("curvature_u")), float(m.get_float("curvature_v")), in.hf->width, in.hf->height);
                      const auto progress = [&](double f) { ctx.progress(f); };
                      Importance imp = gpu_or_cpu(
                          ctx, want_gpu(ctx), "the curvature importance",
                          [&] {
                              require_gpu(bool(gpu_compute().importance));
                              return gpu_compute().importance(*in.hf, *in.dirs, *in.vis, b, progress);
                          },
                          [&] { return compute_importance(*in.hf, *in.dirs, *in.vis, b, progress); });
                      if (imp.folded_count > 0) {
                          char msg[256];
                          std::snprintf(msg, sizeof msg,
                                        "the curvature folds the direction triangulation over at %zu of %zu texels (%.1f%%): visibility would change there; "
                                        "see the 'folded' AOV, or reduce microgeom.curvature_u/v",
                                        imp.folded_count, in.texels(), 100.0 * double(imp.folded_count) / double(in.texels()));
                          ctx.warn(msg);
                      }
                      return stage_result(stages::importance, std::move(imp));
                  }}));
    // Per-texel ellipses (§4), only when they are the selected shadow method; on a curved base
    // fitted once at 5 curvatures (§5) and interpolated for the current one.
    g.add(stages::ellipses_curved, object({.help = "Fit the per-texel ellipses at 5 base curvatures: flat, +-microgeom.ellipse_bend along u and along v (§5)",
                  .params = {"microgeom.ellipse_bend", "microgeom.shadows", "microgeom.device"},
                  .inputs = {stages::heightfield, stages::directions, stages::visibility},
                  .applies = [](const Scene&, const SceneObject& o) { return ellipse_shadows(o) && curved(o); },
                  .when_text = "microgeom.shadows is ellipse on a curved base",
                  .run = [](StageContext& ctx) {
                      const FieldInputs in(ctx);
                      const float bend = float(ctx.material().get_float("ellipse_bend"));
                      const auto progress = [&](double f) { ctx.progress(f); };
                      return stage_result(stages::ellipses_curved, gpu_or_cpu(
                          ctx, want_gpu(ctx), "the ellipses",
                          [&] {
                              require_gpu(bool(gpu_compute().ellipses));
                              return fit_curved_ellipses(*in.hf, *in.dirs, *in.vis, bend, progress, [&](Bending b, const std::function<void(double)>& p) {
                                  return gpu_compute().ellipses(*in.hf, *in.dirs, *in.vis, b, p);
                              });
                          },
                          [&] { return fit_curved_ellipses(*in.hf, *in.dirs, *in.vis, bend, progress); }));
                  },
                  .disk = stage_codec(stages::ellipses_curved, write_curved_ellipses, read_curved_ellipses)}));
    g.add(stages::ellipses, object({.help = "Fit a per-texel ellipse to the projections of the unshadowed directions (covariance start, optimised); on a curved base "
                          "interpolate the 5 fits of microgeom.ellipses_curved",
                  .params = with(keys(kCurvatureKeys), {"microgeom.device"}),
                  .inputs = {stages::heightfield, stages::directions, stages::visibility, stages::ellipses_curved},
                  .applies = [](const Scene&, const SceneObject& o) { return ellipse_shadows(o); },
                  .when_text = "microgeom.shadows is ellipse",
                  .paper = paper::kBricks128.shadows,
                  .run = [](StageContext& ctx) {
                      const FieldInputs in(ctx);
                      const ParamTable& m = ctx.material();
                      if (const auto c = ctx.input(stages::ellipses_curved)) {
                          const float cu = float(m.get_float("curvature_u")), cv = float(m.get_float("curvature_v"));
                          if (std::fabs(cu) > c->bend_deg || std::fabs(cv) > c->bend_deg)
                              ctx.warn("the curvature exceeds microgeom.ellipse_bend (" + std::to_string(int(c->bend_deg)) +
                                       " degrees): the ellipses are those of the largest fitted bend; raise ellipse_bend");
                          return stage_result(stages::ellipses, interpolate_ellipses(*c, Bending::from_degrees(cu, cv, in.hf->width, in.hf->height)));
                      }
                      const auto progress = [&](double f) { ctx.progress(f); };
                      return stage_result(stages::ellipses, gpu_or_cpu(
                          ctx, want_gpu(ctx), "the ellipses",
                          [&] {
                              require_gpu(bool(gpu_compute().ellipses));
                              return gpu_compute().ellipses(*in.hf, *in.dirs, *in.vis, Bending{}, progress);
                          },
                          [&] { return fit_ellipses(*in.hf, *in.dirs, *in.vis, progress); }));
                  },
                  .disk = stage_codec(stages::ellipses, write_ellipse_map, read_ellipse_map)}));
    // Geometry level of detail: the base re-tessellated at the texel rate and displaced.
    g.add(stages::displaced, object({.help = "Re-tessellate the base surface at one vertex per texel and displace it by the heights (lod = geometry)",
                  .params = {"microgeom.lod", "microgeom.tiling", "geometry.type", "geometry.resolution", "geometry.minor_ratio"},
                  .inputs = {stages::heightfield},
                  .applies = [](const Scene&, const SceneObject& o) { return lod(o) == "geometry"; },
                  .when_text = "microgeom.lod is geometry",
                  .memory = [](const StageContext& ctx) {
                      const SceneObject& o = ctx.obj();
                      const auto hf = ctx.input(stages::heightfield);
                      const std::string type = o.geometry.get_string("type");
                      if (type == "mesh") return MemoryEstimate{};
                      const double n = double(displacement_resolution(type, int(o.geometry.get_int("resolution")), hf->width, hf->height,
                                                                      float(o.material.get_float("tiling")), kMaxDisplacementSegments, nullptr));
                      const double vertices = type == "teapot" ? 32.0 * (n / 8.0 + 1.0) * (n / 8.0 + 1.0) : (n + 1.0) * (n + 1.0);
                      return memory_of(vertices * (3.0 * sizeof(vec3) + sizeof(vec2) + 6.0 * sizeof(uint32_t)),
                                       "about " + std::to_string(int64_t(vertices)) + " displaced vertices", {"microgeom.tiling", "microgeom.resolution"});
                  },
                  .run = [](StageContext& ctx) -> std::any {
                      const SceneObject& o = ctx.obj();
                      const auto h = ctx.input(stages::heightfield);
                      const std::string type = o.geometry.get_string("type");
                      if (type == "mesh") {
                          ctx.warn("microgeom.lod = geometry needs a procedural base (plane, sphere, cylinder, torus, teapot); the mesh is drawn undisplaced (bump level)");
                          return {};
                      }
                      bool capped = false;
                      const float tiling = float(o.material.get_float("tiling"));
                      const int res = displacement_resolution(type, int(o.geometry.get_int("resolution")), h->width, h->height, tiling, kMaxDisplacementSegments, &capped);
                      if (capped)
                          ctx.warn("the displaced geometry is capped at " + std::to_string(kMaxDisplacementSegments) +
                                   " segments, fewer than one vertex per texel: lower microgeom.tiling or the heightfield resolution");
                      if (type == "teapot")
                          ctx.warn("the teapot's 32 patches are displaced independently (each has its own cell of the uv atlas), so cracks can open along the patch borders");
                      return stage_result(stages::displaced, displace(make_primitive(primitive_named(type), res, float(o.geometry.get_float("minor_ratio"))), *h, tiling));
                  }}));
    // The truth's surface: the heightfield through its texel centres on the base (core/truth).
    g.add(stages::truth_surface, object({.help = "The truth's micro-geometry: the base tessellated at two vertices per texel and displaced through the texel centres (--backend truth)",
                  .params = {"microgeom.tiling", "microgeom.curvature_u", "microgeom.curvature_v", "geometry.type", "geometry.resolution", "geometry.minor_ratio",
                             "camera.mode"},
                  .inputs = {stages::heightfield},
                  .memory = [](const StageContext& ctx) {
                      const SceneObject& o = ctx.obj();
                      const std::string type = o.geometry.get_string("type");
                      if (type == "mesh") return MemoryEstimate{};
                      const auto hf = ctx.input(stages::heightfield);
                      const Primitive base = primitive_named(type);
                      const int n = truth_surface_resolution(base, int(o.geometry.get_int("resolution")), hf->width, hf->height,
                                                             truth_tiling(ctx.scene, o), nullptr);
                      const double triangles = truth_surface_triangles(base, n);
                      // The mesh (positions, uv and indices: ~24 bytes a vertex, 12 a triangle) and Embree's BVH over it (~100 bytes a triangle).
                      return memory_of(triangles * (12.0 + 12.0 + 100.0), "about " + std::to_string(int64_t(triangles)) + " triangles for the truth",
                                       {"microgeom.tiling", "microgeom.resolution"});
                  },
                  .run = [](StageContext& ctx) -> std::any {
                      const SceneObject& o = ctx.obj();
                      const ParamTable& m = ctx.material();
                      const std::string type = o.geometry.get_string("type");
                      if (type == "mesh")
                          throw InputError("--backend truth: object '" + o.name + "': microgeom's truth displaces a procedural base (geometry.type plane, sphere, cylinder, torus or teapot), not a mesh file");
                      const auto h = ctx.input(stages::heightfield);
                      const Primitive base = primitive_named(type);
                      const float tiling = truth_tiling(ctx.scene, o);
                      bool capped = false;
                      const int n = truth_surface_resolution(base, int(o.geometry.get_int("resolution")), h->width, h->height, tiling, &capped);
                      if (capped) ctx.warn("the truth's surface is capped at 16384 segments, fewer than two per texel: lower microgeom.tiling or the heightfield resolution");
                      if (base != Primitive::Plane && curved(o))
                          ctx.warn("microgeom.curvature_u/v bend only a plane in the truth; a " + type + " has its own curvature");
                      TriMesh surface = truth_surface(base, n, float(o.geometry.get_float("minor_ratio")), *h, tiling, float(m.get_float("curvature_u")),
                                                      float(m.get_float("curvature_v")));
                      // Texture mode on a plane: the field once on the plane with a copy on every side (3 x 3
                      // over three times the plane), so that light in the border texels meets their neighbours.
                      if (tiling == 3.f && texture_mode(ctx.scene) && base == Primitive::Plane)
                          for (vec3& p : surface.position) p *= 3.f;  // the heights too: displaced at a third of the texel length
                      return stage_result(stages::truth_surface, std::move(surface));
                  }}));
    // BRDF level of detail: the virtual goniometer (§6).
    g.add(stages::brdf, object({.help = "Simulate the heightfield's BRDF with the virtual goniometer: average radiance of texture-space images with masking (lod = brdf)",
                  .params = with(with(keys(kScatterKeys), keys(kBrdfKeys)), {"microgeom.device", "effects.indirect", "effects.environment"}),
                  .inputs = {stages::heightfield, stages::directions, stages::visibility, stages::importance, stages::ellipses},
                  .applies = [](const Scene&, const SceneObject& o) { return lod(o) == "brdf"; },
                  .when_text = "microgeom.lod is brdf",
                  .paper = paper::kBrdf16,
                  .memory = [](const StageContext& ctx) {
                      const FieldInputs in(ctx);
                      const double nodes = std::pow(double(ctx.material().get_int("brdf_resolution")), 2.0);
                      // The table (nodes^2 entries of a vec3 and a shadow fraction) and one light's images at a time.
                      return memory_of(nodes * nodes * (sizeof(vec3) + sizeof(float)) + scatter_working_bytes(in) * nodes,
                                       std::to_string(int64_t(nodes * nodes)) + " (light, view) entries and the light images",
                                       {"microgeom.brdf_resolution", "microgeom.resolution"});
                  },
                  .run = [](StageContext& ctx) {
                      const FieldInputs in(ctx);
                      const ParamTable& m = ctx.material();
                      GonioSettings gs;
                      gs.scatter = scatter_settings(m);
                      if (!ctx.scene.effect("indirect")) gs.scatter.depth = 0;
                      gs.scatter.importance = in.imp.get();
                      gs.scatter.ellipses = in.ell.get();
                      gs.phong = m.get_string("brdf") == "blinn-phong";
                      gs.ks = m.get_vec3("ks");
                      gs.shininess = float(m.get_float("shininess"));
                      gs.resolution = int(m.get_int("brdf_resolution"));
                      gs.fit = m.get_string("brdf_fit") == "sh" ? GonioSettings::Fit::SH : GonioSettings::Fit::Table;
                      gs.samples = int(m.get_int("brdf_samples"));
                      gs.sh_bands = int(m.get_int("sh_bands"));
                      gs.seed = uint32_t(m.get_int("scatter_seed"));
                      return stage_result(stages::brdf, with_light_solver([&](std::string w) { ctx.warn(std::move(w)); ctx.fell_back_to_cpu(); }, ctx.obj(), *in.hf, *in.dirs, *in.vis, gs.scatter,
                                                            [&](LightSolver* solver) {
                                                                gs.lights = solver;
                                                                return simulate_brdf(*in.hf, *in.dirs, *in.vis, gs, [&](double f) { ctx.progress(f); });
                                                            }));
                  }}));
    // Environment light scattered: independent of the light.
    g.add(stages::scatter_env, object({.help = "Environment light gathered where S_i has no hit, scattered microgeom.depth times",
                  .params = with(with(keys(kScatterKeys), keys({"device"})), {"env.*"}),
                  .inputs = {stages::heightfield, stages::directions, stages::visibility, stages::importance, mesolab::stages::env_map},
                  .effects = {"environment"},
                  .applies = [](const Scene&, const SceneObject& o) { return lod(o) != "brdf"; },
                  .when_text = "microgeom.lod is geometry or bump",
                  .memory = [](const StageContext& ctx) {
                      return memory_of(scatter_working_bytes(FieldInputs(ctx)), "one scattering solution", {"microgeom.resolution"});
                  },
                  .run = [](StageContext& ctx) { return stage_result(stages::scatter_env, scatter_env(ctx)); }}));
    // Every light scattered (their direct part is shaded per pixel): planar bases.
    g.add(stages::scatter, object({.help = "Each light scattered inside the heightfield (dependent tests), one solution per light (planar bases)",
                  .params = with(with(keys(kScatterKeys), keys({"device"})), {"light.*", "geometry.type"}),
                  .inputs = {stages::heightfield, stages::directions, stages::visibility, stages::importance, stages::ellipses},
                  .effects = {"indirect"},
                  .applies = [](const Scene& s, const SceneObject& o) { return !s.lights.empty() && wants_light_scatter(o) && !direction_table(s, o); },
                  .when_text = "the scene has a light, microgeom.depth > 0, microgeom.lod is not brdf, the base is a plane and every light is directional",
                  .paper = paper::kBricks128.scattering,
                  .memory = [](const StageContext& ctx) {
                      return memory_of(scatter_working_bytes(FieldInputs(ctx)) * double(std::max<size_t>(1, ctx.scene.lights.size())),
                                       "one scattering solution per light", {"microgeom.resolution"});
                  },
                  .run = [](StageContext& ctx) { return stage_result(stages::scatter, scatter_lights(ctx)); }}));
    // Non-planar bases: the light-driven scattering for every set direction above the horizon,
    // blended per pixel for each light's tangent-space direction; never depends on the light.
    g.add(stages::scatter_directions, object({.help = "Light scattered inside the heightfield for each of the ~N/2 set directions above the horizon, at unit irradiance (non-planar "
                          "bases; blended per pixel over the light's spherical triangle)",
                  .params = with(with(keys(kScatterKeys), keys({"device"})), {"geometry.type"}),
                  .inputs = {stages::heightfield, stages::directions, stages::visibility, stages::importance, stages::ellipses},
                  .effects = {"indirect"},
                  // Reads the lights' types only (directional or point), through direction_table.
                  .applies = [](const Scene& s, const SceneObject& o) { return !s.lights.empty() && wants_light_scatter(o) && direction_table(s, o); },
                  .when_text = "the scene has a light, microgeom.depth > 0, microgeom.lod is not brdf, and the base is not a plane or a light is a point light",
                  .memory = [](const StageContext& ctx) {
                      const FieldInputs in(ctx);
                      const double M = double(in.dirs->d.size()) / 2.0 + 1.0;
                      return memory_of(M * double(in.texels()) * sizeof(vec3) + scatter_working_bytes(in),
                                       texels_text(*in.hf) + " x ~" + std::to_string(int(M)) + " directions above the horizon x 12 bytes",
                                       {"microgeom.resolution", "microgeom.directions"});
                  },
                  .run = [](StageContext& ctx) { return stage_result(stages::scatter_directions, scatter_directions_stage(ctx)); }}));
}
}  // namespace mesolab::microgeom
