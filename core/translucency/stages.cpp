// Technique translucency: the stage graph and the frame steps' CPU work (handles in stages.h).
#include "core/blob.h"
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

// [SECTION] Stages
namespace {
// [SECTION] Kernels on disk (core/stage_store.h), alone and inside the blended copy
void write_kernels(BlobWriter& w, const LocalKernels& k) {
    w.put(int32_t(k.K)), w.put(int32_t(k.size)), w.put(int32_t(k.row));
    w.put_vector(k.texel), w.put_vector(k.slot), w.put_vector(k.w);
}
LocalKernels read_kernels(BlobReader& r) {
    LocalKernels k;
    k.K = r.get<int32_t>(), k.size = r.get<int32_t>(), k.row = r.get<int32_t>();
    k.texel = r.get_vector<int32_t>(), k.slot = r.get_vector<int32_t>(), k.w = r.get_vector<float>();
    return k;
}
}  // namespace

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
           },
           .disk = stage_codec(
               stages::mesh,
               [](BlobWriter& w, const PreparedMesh& m) {
                   w.put_vector(m.position), w.put_vector(m.normal), w.put_vector(m.corner_normal), w.put_vector(m.index), w.put_vector(m.corner_uv);
                   for (int v : {m.welded_vertices, m.removed_triangles, m.detached_triangles, m.boundary_edges, m.input_vertices}) w.put(int32_t(v));
                   w.put(uint64_t(m.warnings.size()));
                   for (const std::string& x : m.warnings) w.put_string(x);
               },
               [](BlobReader& r) {
                   PreparedMesh m;
                   m.position = r.get_vector<vec3>(), m.normal = r.get_vector<vec3>(), m.corner_normal = r.get_vector<vec3>();
                   m.index = r.get_vector<uint32_t>(), m.corner_uv = r.get_vector<vec2>();
                   for (int* v : {&m.welded_vertices, &m.removed_triangles, &m.detached_triangles, &m.boundary_edges, &m.input_vertices}) *v = r.get<int32_t>();
                   m.warnings.resize(r.get_count(8));
                   for (std::string& x : m.warnings) x = r.get_string();
                   return m;
               })});
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
           .params = with_material({"translucency.kernel", "translucency.method"}),
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
               const Settings s = Settings::from(ctx.obj(), Settings::Medium_ | Settings::ProfilePart | Settings::Scale | Settings::AtlasPart);
               const auto m = ctx.input(stages::mesh);
               const auto a = ctx.input(stages::atlas);
               return stage_result(stages::kernels, build_local_kernels(a->atlas, m->position, m->index, *s.profile(), s.mm_per_unit, s.kernel));
           },
           .disk = stage_codec(stages::kernels, write_kernels, read_kernels)});
    g.add(stages::factors, {.help = "Vertex-to-vertex throughput factors above translucency.threshold (§5.2)",
           .scope = StageScope::Object,
           .technique = "translucency",
           .params = with_material({"translucency.threshold", "translucency.blend", "translucency.method"}),
           .inputs = {stages::mesh},
           .paper = PaperFigure{paper::kFactorsMaxMs, "Lensch 2002, §6: form factors 2-8 min (dual Xeon 1.7 GHz)"},
           .memory = [](const StageContext& ctx) {
               return factor_memory(*ctx.input(stages::mesh), Settings::from(ctx.obj(), Settings::Medium_ | Settings::ProfilePart | Settings::Scale | Settings::Factors));
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.obj(), Settings::Medium_ | Settings::ProfilePart | Settings::Scale | Settings::Factors);
               const auto m = ctx.input(stages::mesh);
               VertexFactors F = build_vertex_factors(m->position, m->index, *s.profile(), {s.mm_per_unit, s.threshold, s.blend});
               if (F.count() == 0 && m->vertex_count() > 1)
                   ctx.warn("translucency.threshold = " + std::to_string(s.threshold) + " drops every factor: the global response is zero");
               return stage_result(stages::factors, std::move(F));
           },
           .disk = stage_codec(
               stages::factors,
               [](BlobWriter& w, const VertexFactors& F) {
                   w.put(int32_t(F.n));
                   w.put_vector(F.outer), w.put_vector(F.pair), w.put_vector(F.col_hi);
                   w.put(F.scale);
                   w.put_vector(F.vertex_area);
                   w.put(uint64_t(F.diagonal)), w.put(F.threshold), w.put(F.zero_diagonal);
               },
               [](BlobReader& r) {
                   VertexFactors F;
                   F.n = r.get<int32_t>();
                   F.outer = r.get_vector<int>(), F.pair = r.get_vector<uint64_t>(), F.col_hi = r.get_vector<uint16_t>();
                   F.scale = r.get<vec3>();
                   F.vertex_area = r.get_vector<float>();
                   F.diagonal = size_t(r.get<uint64_t>()), F.threshold = r.get<double>(), F.zero_diagonal = r.get<bool>();
                   return F;
               })});
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
               const Settings s = Settings::from(ctx.obj(), Settings::Medium_ | Settings::ProfilePart | Settings::Scale);
               const auto m = ctx.input(stages::mesh);
               Blended b{*ctx.input(stages::kernels), {}};
               b.weights = fit_blending(ctx.input(stages::atlas)->atlas, m->position, m->index, *s.profile(), s.mm_per_unit,
                                        *ctx.input(stages::factors), b.kernels);
               return stage_result(stages::blend, std::move(b));
           },
           .disk = stage_codec(
               stages::blend,
               [](BlobWriter& w, const Blended& b) {
                   write_kernels(w, b.kernels);
                   w.put_vector(b.weights.c);
               },
               [](BlobReader& r) {
                   Blended b;
                   b.kernels = read_kernels(r);
                   b.weights.c = r.get_vector<std::array<vec3, 3>>();
                   return b;
               })});
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
                           const Settings s = Settings::from(obj, Settings::Medium_ | Settings::Shadows);
                           const auto a = atlas(ctx, o);
                           const mat4 model = object_to_world(obj);
                           std::vector<ShadowMap> shadows;
                           if (s.shadows) {
                               PROFILE_SCOPE("shadow maps");
                               for (size_t i = 0; i < ctx.lighting.lights.size() && i < size_t(kMaxShadowMaps); ++i)
                                   shadows.push_back(make_shadow_map(*a->display, model, ctx.lighting.lights[i], s.shadow_map));
                           }
                           PROFILE_SCOPE("texels lit");
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
                           const Settings s = Settings::from(ctx.scene.objects[size_t(o)], Settings::Medium_ | Settings::ProfilePart | Settings::Scale | Settings::Show);
                           if (!s.needs_reference()) continue;
                           const auto a = atlas(ctx, o);
                           const auto m = ctx.eval.get(stages::mesh, o);
                           out[o] = fill_texels(*a, reference_radiosity(a->atlas, texel_positions_mm(a->atlas, m->position, m->index, s.mm_per_unit),
                                                                        *s.profile(), s.mm_per_unit, E.at(o)));
                       }
                       return out;
                   })};
}
}  // namespace mesolab::translucency
