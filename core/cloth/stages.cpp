// Technique cloth: the stage graph (stages.h): the stitch mesh, the virtual acquisition (or the
// samples file), the fitted pyramid and the procedural garment.
#include "core/cloth/stages.h"
#include "core/cloth/paper.h"
#include "core/cloth/garment.h"
#include "core/cloth/samples.h"
#include "core/cloth/technique.h"
#include "core/cloth/truth.h"
#include "core/blob.h"
#include "core/error.h"
#include "core/scene_stages.h"

#include <string>
#include <vector>

namespace mesolab::cloth {
namespace {
// [SECTION] Stages
const std::vector<std::string> kStitchKeys = {"cloth.stitch", "cloth.yarn_radius", "cloth.loop_height", "cloth.color_a", "cloth.color_b",
                                              "cloth.stitch_resolution"};

// [SECTION] The acquisition and the fit on disk (core/stage_store.h)
template <class T>
void put_nested(BlobWriter& w, const std::vector<std::vector<T>>& v) {
    w.put(uint64_t(v.size()));
    for (const auto& x : v) w.put_vector(x);
}
template <class T>
std::vector<std::vector<T>> get_nested(BlobReader& r) {
    std::vector<std::vector<T>> v(r.get_count(8));
    for (auto& x : v) x = r.get_vector<T>();
    return v;
}

void write_grid(BlobWriter& w, const SampleGrid& g) {
    w.put(int32_t(g.res));
    w.put_vector(g.l), w.put_vector(g.v), w.put_vector(g.view_of), w.put_vector(g.views);
    put_nested(w, g.f), put_nested(w, g.alpha);
    w.put_vector(g.normal), w.put_vector(g.tangent);
}

SampleGrid read_grid(BlobReader& r) {
    SampleGrid g;
    g.res = r.get<int32_t>();
    g.l = r.get_vector<dvec3>(), g.v = r.get_vector<dvec3>(), g.view_of = r.get_vector<int>(), g.views = r.get_vector<dvec3>();
    g.f = get_nested<dvec3>(r), g.alpha = get_nested<double>(r);
    g.normal = r.get_vector<dvec3>(), g.tangent = r.get_vector<dvec3>();
    return g;
}

void write_pyramid(BlobWriter& w, const BrdfPyramid& p) {
    w.put(int32_t(p.res));
    w.put(uint64_t(p.level.size()));
    for (const auto& level : p.level) {
        w.put(uint64_t(level.size()));
        for (const ClothBrdf& b : level) {
            w.put(b.L.kd), w.put_vector(b.L.lobes);
            w.put(uint8_t(b.sheen ? 1 : 0));
            if (b.sheen) w.put(b.sheen->S), w.put(b.sheen->r);
            w.put_vector(b.table.v), w.put_vector(b.table.T);
            w.put(b.f_max);
        }
    }
    put_nested(w, p.frame), put_nested(w, p.report);
}

BrdfPyramid read_pyramid(BlobReader& r) {
    BrdfPyramid p;
    p.res = r.get<int32_t>();
    p.level.resize(r.get_count(8));
    for (auto& level : p.level) {
        level.resize(r.get_count(64));
        for (ClothBrdf& b : level) {
            b.L.kd = r.get<dvec3>(), b.L.lobes = r.get_vector<LafortuneLobe>();
            if (r.get<uint8_t>()) {
                SheenLobe sh;
                sh.S = r.get<dvec3>(), sh.r = r.get<double>();
                b.sheen = sh;
            }
            b.table.v = r.get_vector<dvec3>(), b.table.T = r.get_vector<dvec4>();
            b.f_max = r.get<dvec3>();
        }
    }
    p.frame = get_nested<glm::dmat3>(r), p.report = get_nested<FitReport>(r);
    return p;
}

}  // namespace

void ClothTechnique::declare_stages(StageGraph& g) const {
    g.add(stages::stitch, {.help = "Stitch micro-geometry: yarn tubes around Bezier skeletons over 3 x 3 tiles, marching cubes",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = kStitchKeys,
           .applies = [](const Scene&, const SceneObject& o) { return o.material.get_string("samples").empty(); },
           .when_text = "cloth.samples is empty (the samples are acquired)",
           .memory = [](const StageContext& ctx) {
               const double n = double(ctx.material().get_int("stitch_resolution"));
               return MemoryEstimate{27.0 * n * n * n * 12.0, "the field over 3 x 3 tiles at " + std::to_string(int(n)) + " cells per side",
                                     {"cloth.stitch_resolution"}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.scene, ctx.obj(), Settings::Stitch);
               return stage_result(stages::stitch, build_stitch_mesh(make_stitch(s.stitch), s.stitch_resolution));
           }});
    std::vector<std::string> acquire_keys = kStitchKeys;
    acquire_keys.insert(acquire_keys.end(), {"cloth.spatial", "cloth.directions", "cloth.visibility_rays", "cloth.bounces", "cloth.samples"});
    g.add(stages::acquire, {.help = "Virtual acquisition (Embree): lighting by precomputed visibility, parallax samples per light x view pair, alpha per view",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = acquire_keys,
           .inputs = {stages::stitch},
           .paper = paper::acquire(),
           .memory = [](const StageContext& ctx) {
               const double n = double(ctx.material().get_int("spatial")), d = double(ctx.material().get_int("directions"));
               return MemoryEstimate{n * n * d * d * 24.0, std::to_string(int(n)) + "² points x " + std::to_string(int(d * d)) + " pairs x 3 doubles",
                                     {"cloth.spatial", "cloth.directions"}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.scene, ctx.obj(), Settings::Acquire);
               if (!s.samples.empty()) {
                   SampleGrid g = read_sample_grid(s.samples);
                   return stage_result(stages::acquire, std::move(g));
               }
               const ProgressFn progress = [&](const std::string&, double f) {
                   if (!ctx.cancelled()) ctx.progress(f);
               };
               return stage_result(stages::acquire, acquire(*ctx.input(stages::stitch), s.acquire, progress, ctx.cancel_flag()));
           },
           .disk = stage_codec(stages::acquire, write_grid, read_grid)});
    g.add(stages::fit, {.help = "Lafortune (or sheen, cloth.method = sheen) x view-table fits (Ceres) of every mip level's entries, coarse to fine",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = {"cloth.method", "cloth.lobes", "cloth.lookup_table", "cloth.tolerance"},
           .inputs = {stages::acquire},
           .paper = paper::fit(),
           .run = [](StageContext& ctx) -> std::any {
               const Settings s = Settings::from(ctx.scene, ctx.obj(), Settings::Fit);
               const ProgressFn progress = [&](const std::string&, double f) {
                   if (!ctx.cancelled()) ctx.progress(f);
               };
               BrdfPyramid p = fit_pyramid(*ctx.input(stages::acquire), s.fit, progress, ctx.cancel_flag());
               size_t unconverged = 0;
               for (const auto& level : p.report)
                   for (const FitReport& r : level) unconverged += r.converged ? 0 : 1;
               if (unconverged)
                   ctx.warn(std::to_string(unconverged) + " of " + std::to_string(p.count()) + " BRDFs stopped before the table met cloth.tolerance");
               return stage_result(stages::fit, std::move(p));
           },
           .disk = stage_codec(stages::fit, write_pyramid, read_pyramid)});
    g.add(stages::garment, {.help = "The procedural garment (folded curtain, bent sleeve) drawn instead of the object's geometry",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = {"cloth.garment", "cloth.garment_resolution"},
           .applies = [](const Scene&, const SceneObject& o) { return o.material.get_string("garment") != "geometry"; },
           .when_text = "cloth.garment is curtain or sleeve",
           .run = [](StageContext& ctx) -> std::any {
               return stage_result(stages::garment, make_garment(ctx.material().get_string("garment"), int(ctx.material().get_int("garment_resolution"))));
           }});
    // The truth (truth.h): the yarns themselves, whatever the acquisition's and the fit's settings.
    g.add(stages::truth_stitch, {.help = "The truth's tile of yarns: the stitch polygonised at 48 cells per tile side, its centre tile (--backend truth)",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = {"cloth.stitch", "cloth.yarn_radius", "cloth.loop_height", "cloth.color_a", "cloth.color_b", "cloth.samples"},
           .run = [](StageContext& ctx) -> std::any {
               const ParamTable& t = ctx.material();
               if (!t.get_string("samples").empty())
                   throw InputError("--backend truth: object '" + ctx.obj().name + "': cloth.samples gives the fabric as samples only; the truth traces the stitch's yarns "
                                    "(clear cloth.samples to acquire them from cloth.stitch)");
               StitchParams p;
               p.stitch = t.get_string("stitch");
               p.yarn_radius = float(t.get_float("yarn_radius"));
               p.loop_height = float(t.get_float("loop_height"));
               p.color_a = t.get_vec3("color_a");
               p.color_b = t.get_vec3("color_b");
               return stage_result(stages::truth_stitch, truth_stitch_tile(p));
           }});
    g.add(stages::truth_fabric, {.help = "The truth's fabric: the tile of yarns instanced over the garment along its pattern tiles (--backend truth)",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = {"cloth.repeat"},
           .inputs = {stages::truth_stitch, stages::garment, mesolab::stages::geometry},
           .memory = [](const StageContext& ctx) {
               const auto tile = ctx.input(stages::truth_stitch);
               const int repeat = int(std::ceil(ctx.material().get_float("repeat")));
               const double triangles = tile ? truth_fabric_triangles(*tile, repeat) : 0.0;
               // The mesh (position, normal, uv, colour: ~44 bytes a vertex, about half a vertex a triangle; 12 a
               // triangle's indices) and Embree's BVH over it (~100 bytes a triangle).
               return MemoryEstimate{triangles * (22.0 + 12.0 + 100.0), "about " + std::to_string(int64_t(triangles)) + " yarn triangles for the truth",
                                     {"cloth.repeat"}};
           },
           .run = [](StageContext& ctx) -> std::any {
               const double r = ctx.material().get_float("repeat");
               if (std::fabs(r - std::round(r)) > 1e-9)
                   throw InputError("--backend truth: object '" + ctx.obj().name + "': cloth.repeat " + std::to_string(r) +
                                    " is not a whole number; the truth instances whole tiles of the stitch");
               auto base = ctx.input(stages::garment);
               if (!base) base = ctx.input(mesolab::stages::geometry);
               return stage_result(stages::truth_fabric, truth_fabric(*ctx.input(stages::truth_stitch), *base, int(std::lround(r))));
           }});
}
}  // namespace mesolab::cloth
