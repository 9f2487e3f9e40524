// Technique cloth: parameters, stages, CPU shading, the samples export, the fit/eval commands,
// the timing table and the fit-error sweep metric (see technique.h).
#include "core/cloth/stages.h"
#include "core/cloth/technique.h"
#include "core/cloth/garment.h"
#include "core/cloth/samples.h"
#include "core/error.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/scene_stages.h"
#include "core/technique.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>

namespace mesolab::cloth {

// [SECTION] Settings
Settings Settings::from(const Scene& sc, const SceneObject& o, unsigned parts) {
    const ParamTable& t = o.material;
    Settings s;
    if (parts & Stitch) {
        s.stitch.stitch = t.get_string("stitch");
        s.stitch.yarn_radius = float(t.get_float("yarn_radius"));
        s.stitch.loop_height = float(t.get_float("loop_height"));
        s.stitch.color_a = t.get_vec3("color_a");
        s.stitch.color_b = t.get_vec3("color_b");
        s.stitch_resolution = int(t.get_int("stitch_resolution"));
    }
    if (parts & Acquire) {
        s.acquire.spatial = int(t.get_int("spatial"));
        s.acquire.directions = int(t.get_int("directions"));
        s.acquire.visibility_rays = int(t.get_int("visibility_rays"));
        s.samples = sc.resolve(t.get_string("samples"));
    }
    if (parts & Fit) {
        s.fit.lobes = int(t.get_int("lobes"));
        s.fit.lookup_table = t.get_bool("lookup_table");
        s.fit.tolerance = t.get_float("tolerance");
    }
    if (parts & Shading) {
        s.repeat = t.get_float("repeat");
        s.mip = mip_mode_named(t.get_string("mip"));
        s.mip_bias = t.get_float("mip_bias");
        s.garment = t.get_string("garment");
    }
    return s;
}

// [SECTION] The pyramid for the GPU
PackedPyramid pack_pyramid(const BrdfPyramid& p) {
    PackedPyramid out;
    out.res = p.res;
    size_t lobes = 0, dirs = 0, count = 0;
    for (const auto& level : p.level)
        for (const ClothBrdf& b : level) lobes = std::max(lobes, b.L.lobes.size()), dirs = std::max(dirs, b.table.v.size()), ++count;
    out.stride = int(5 + 4 * lobes + 2 * dirs);
    out.lobes = int(lobes), out.dirs = int(dirs);
    out.data.assign(count * size_t(out.stride), vec4(0.f));
    size_t e = 0;
    for (size_t k = 0; k < p.level.size(); ++k) {
        out.level_first.push_back(int(e));
        for (size_t i = 0; i < p.level[k].size(); ++i, ++e) {
            const ClothBrdf& b = p.level[k][i];
            const glm::dmat3& F = p.frame[k][i];
            vec4* r = &out.data[e * size_t(out.stride)];
            r[0] = vec4(vec3(b.L.kd), float(b.L.lobes.size()));
            // glm is column-major: row j of F is (F[0][j], F[1][j], F[2][j]).
            for (int j = 0; j < 3; ++j) r[1 + j] = vec4(float(F[0][j]), float(F[1][j]), float(F[2][j]), 0.f);
            r[1].w = float(b.table.v.size());
            constexpr double kFloatMax = 3.0e38;
            r[4] = vec4(vec3(glm::min(b.f_max, dvec3(kFloatMax))), 0.f);
            vec4* q = r + 5;
            for (const LafortuneLobe& l : b.L.lobes) {
                *q++ = vec4(vec3(l.Cx), 0.f);
                *q++ = vec4(vec3(l.Cy), 0.f);
                *q++ = vec4(vec3(l.Cz), 0.f);
                *q++ = vec4(vec3(l.n), 0.f);
            }
            q = r + 5 + 4 * lobes;
            for (size_t d = 0; d < b.table.v.size(); ++d) {
                *q++ = vec4(vec3(b.table.v[d]), 0.f);
                *q++ = vec4(b.table.T[d]);
            }
        }
    }
    // The shared views: the top entry's directions taken back to the pattern frame, checked on every entry.
    if (dirs > 0 && !p.level.empty()) {
        const ClothBrdf& top = p.level.back()[0];
        const glm::dmat3 Ft = glm::transpose(p.frame.back()[0]);
        std::vector<dvec3> views;
        for (const dvec3& v : top.table.v) views.push_back(Ft * v);
        bool shared = views.size() == dirs;
        for (size_t k = 0; k < p.level.size() && shared; ++k)
            for (size_t i = 0; i < p.level[k].size() && shared; ++i) {
                const auto& tv = p.level[k][i].table.v;
                shared = tv.size() == views.size();
                for (size_t d = 0; d < tv.size() && shared; ++d) shared = glm::length(p.frame[k][i] * views[d] - tv[d]) < 1e-6;
            }
        if (shared)
            for (const dvec3& v : views) out.shared_views.push_back(vec4(vec3(v), 0.f));
    }
    return out;
}

// [SECTION] Footprint
double uv_footprint(const GBuffer& gb, size_t pixel) {
    return double(std::max(glm::length(gb.uv_dx[pixel]), glm::length(gb.uv_dy[pixel])));
}

namespace {

// [SECTION] Fitting commands: option values
int parse_int_option(const std::map<std::string, std::string>& a, const std::string& key, int def, int lo, int hi) {
    auto it = a.find(key);
    if (it == a.end()) return def;
    try {
        size_t used = 0;
        const int v = std::stoi(it->second, &used);
        if (used == it->second.size() && v >= lo && v <= hi) return v;
    } catch (const std::exception&) {
    }
    throw InputError("--" + key + " " + it->second + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

double parse_float_option(const std::map<std::string, std::string>& a, const std::string& key, double def) {
    auto it = a.find(key);
    if (it == a.end()) return def;
    try {
        size_t used = 0;
        const double v = std::stod(it->second, &used);
        if (used == it->second.size() && std::isfinite(v) && v > 0.0) return v;
    } catch (const std::exception&) {
    }
    throw InputError("--" + key + " " + it->second + ": expected a positive number");
}

std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

// [SECTION] The technique
class ClothTechnique final : public Technique {
public:
    ClothTechnique() : Technique("cloth", "Cloth (Daubert et al. 2001)") {
        auto& p = params_;
        p.add_enum("stitch", stitch_names(), "knit")
            .doc("Stitch pattern: plain knit, purl loops, knit loops in two colours, plain weave, 2/1 twill");
        p.add_float("yarn_radius", 0.12).range(0.02, 0.45).in("yarn spacings").doc("Radius of the yarn's tube around its skeleton");
        p.add_float("loop_height", 1.0).range(0.5, 3.0).in("yarn spacings")
            .used_when("stitch", {"knit", "purl", "loops2"}).doc("Course height of knitted loops");
        p.add_color("color_a", {0.75, 0.12, 0.10}).doc("Yarn colour (the weave's warp; loops2: every other course)");
        p.add_color("color_b", {0.90, 0.85, 0.70}).doc("Second yarn colour (the weave's weft; loops2: the other courses)");
        p.add_int("stitch_resolution", 48).range(8, 256).more_accurate(Accuracy::Higher, int64_t(128))
            .doc("Marching-cubes cells per tile side of the stitch mesh");
        p.add_int("spatial", 32).range(1, 256).more_accurate(Accuracy::Higher, int64_t(64))
            .doc("Sample points per side of the pattern (a power of two): 32 gives 6 mip levels and 1365 BRDFs");
        p.add_int("directions", 32).range(4, 128).more_accurate(Accuracy::Higher, int64_t(64))
            .doc("Light directions, and as many view directions, over the hemisphere (32: the paper's 32 x 32 pairs)");
        p.add_int("visibility_rays", 64).range(0, 1024).more_accurate(Accuracy::Higher, int64_t(256))
            .doc("Rays per vertex of the precomputed visibility for the indirect bounce (0: direct light only)");
        p.add_path("samples", "")
            .doc("Acquired samples to fit instead of acquiring (mesolab export cloth-samples writes them); relative to the preset's folder");
        p.add_int("lobes", 2).range(1, 3).more_accurate(Accuracy::Higher, int64_t(3)).doc("Lafortune lobes per channel");
        p.add_bool("lookup_table", true).doc("Fit the view-dependent table T(v) (colour and alpha); off: the lobes alone (Fig. 5)");
        p.add_float("tolerance", 0.1).range(1e-4, 10.0).log().more_accurate(Accuracy::Lower, 0.01)
            .used_when("lookup_table", {"true"}).doc("Stop alternating when the table changes less than this on average");
        p.add_enum("garment", {"curtain", "sleeve", "geometry"}, "curtain")
            .doc("What wears the fabric: a folded curtain, a bent sleeve, or the object's own mesh (geometry.*, with uv)");
        p.add_int("garment_resolution", 64).range(4, 2048).used_when("garment", {"curtain", "sleeve"})
            .doc("Quads along each side of the procedural garment");
        p.add_float("repeat", 8.0).range(0.01, 1e4).log().in("tiles").doc("Pattern tiles across the garment's uv square");
        p.add_enum("mip", {"off", "nearest", "blend"}, "blend")
            .doc("Mip level from the screen-space uv derivatives: off (level 0, aliases), nearest, blend between the two levels around it");
        p.add_float("mip_bias", 0.0).range(-4.0, 4.0).in("levels").used_when("mip", {"nearest", "blend"}).doc("Added to the mip level (positive: blurrier)");
        params_.section("Stitch", {"stitch", "yarn_radius", "loop_height", "color_a", "color_b", "stitch_resolution"});
        params_.section("Acquisition", {"spatial", "directions", "visibility_rays", "samples"});
        params_.section("Fit", {"lobes", "lookup_table", "tolerance"});
        params_.section("Garment and mip blending", {"garment", "garment_resolution", "repeat", "mip", "mip_bias"});
        aovs_ = {{"alpha", 1, "The table's alpha: 1 yarn, 0 a hole (the background shows through)"},
                 {"mip_level", 1, "Mip level read (fractional when blending): 0 = one BRDF per sample point"},
                 {"brdf_index", 1, "Index of the BRDF read (the finer level when blending), counting level by level from level 0"}};
    }

    void declare_stages(StageGraph& g) const override;
    std::vector<StageName> frame_stages() const override { return {stages::fit, stages::garment}; }
    void shade_cpu(const ShadeContext& ctx) const override;
    std::shared_ptr<const TriMesh> object_mesh(const Scene&, const Evaluation& ev, int object) const override {
        return ev.get(stages::garment, object);
    }
    std::vector<ExportDecl> exports() const override;
    std::vector<CommandDecl> commands() const override;
    std::vector<BenchTable> bench_tables() const override;
    // Both paths evaluate the same continuous functions of the pixel's uv, normal and view: the
    // lobes, the view table (continuous in v), the mip level from uv's differences across the
    // pixel's 2 x 2 quad on its own triangle (GL's fine derivatives on both), the blend between
    // levels. Their inputs agree closely: the GPU draws its vertices on the CPU rasteriser's
    // 1/256-pixel grid (mesh.vert, MESOLAB_SNAP_VERTICES), so both interpolate uv, normals and
    // positions from the same window positions, and the rest is float rounding: off edges the
    // stitch presets agree to 8e-6 (llvmpipe, 2 cores). tight 2e-3 and interior_max 1e-2 leave
    // room for the GPU's float evaluation of steeper lobes (NVIDIA: fused multiply-adds).
    // One choice is discrete: the sample point under the pixel (the paper's BRDF array, read
    // nearest within a level), and a pixel whose uv lies within rounding of a border between two
    // points may read a neighbouring entry on one path: 3 of 108,189 interior values beyond
    // interior_max on fig5, 2 of 173,976 on the near garment, none on the stitch patches:
    // interior_outliers 1e-4. On the far garment with mip off (about 3 points per pixel) 0.01% of
    // the values differ by more than tight, all on edges.
    FrameAgreement agreement() const override {
        return {.tight = 2e-3, .frac_tight = 0.99, .loose = 3e-2, .frac_loose = 0.995, .interior_max = 1e-2, .interior_outliers = 1e-4,
                .why = "a pixel whose uv lies within rounding of a border between two sample points reads a neighbouring entry"};
    }
    std::vector<SweepMetricDecl> sweep_metrics() const override;
    bool uses_uv_derivatives() const override { return true; }  // the mip level's footprint
};

// [SECTION] Stages
const std::vector<std::string> kStitchKeys = {"cloth.stitch", "cloth.yarn_radius", "cloth.loop_height", "cloth.color_a", "cloth.color_b",
                                              "cloth.stitch_resolution"};

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
    acquire_keys.insert(acquire_keys.end(), {"cloth.spatial", "cloth.directions", "cloth.visibility_rays", "cloth.samples"});
    g.add(stages::acquire, {.help = "Virtual acquisition (Embree): lighting by precomputed visibility, parallax samples per light x view pair, alpha per view",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = acquire_keys,
           .inputs = {stages::stitch},
           .paper = PaperFigure{45.0 * 60e3, "Daubert 2001, §4: acquisition 15-45 min (Athlon 1 GHz)"},
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
           }});
    g.add(stages::fit, {.help = "Lafortune x view-table fits (Ceres) of every mip level's entries, coarse to fine",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = {"cloth.lobes", "cloth.lookup_table", "cloth.tolerance"},
           .inputs = {stages::acquire},
           .paper = PaperFigure{2.5 * 3600e3, "Daubert 2001, §5: fitting ~2.5 h (Athlon 1 GHz)"},
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
           }});
    g.add(stages::garment, {.help = "The procedural garment (folded curtain, bent sleeve) drawn instead of the object's geometry",
           .scope = StageScope::Object,
           .technique = "cloth",
           .params = {"cloth.garment", "cloth.garment_resolution"},
           .applies = [](const Scene&, const SceneObject& o) { return o.material.get_string("garment") != "geometry"; },
           .when_text = "cloth.garment is curtain or sleeve",
           .run = [](StageContext& ctx) -> std::any {
               return stage_result(stages::garment, make_garment(ctx.material().get_string("garment"), int(ctx.material().get_int("garment_resolution"))));
           }});
}

// [SECTION] Shading
void ClothTechnique::shade_cpu(const ShadeContext& ctx) const {
    struct Obj {
        Settings s;
        std::shared_ptr<const BrdfPyramid> pyr;
    };
    std::vector<Obj> objs(ctx.scene.objects.size());
    for (int o : ctx.objects) {
        objs[size_t(o)] = {Settings::from(ctx.scene, ctx.scene.objects[size_t(o)]), ctx.eval.get(stages::fit, o)};
        if (!objs[size_t(o)].pyr) throw std::logic_error("cloth: the evaluation lacks cloth.fit for object " + std::to_string(o));
    }
    const int out_alpha = ctx.out.index("alpha"), out_level = ctx.out.index("mip_level"), out_index = ctx.out.index("brdf_index");
    const bool constant_env = ctx.lighting.env.constant();
    const vec3 env_const = ctx.lighting.env.color * ctx.lighting.env.intensity;
    const GBuffer& gb = ctx.gbuffer;
    if (gb.uv_dx.size() != gb.uv.size()) throw std::logic_error("cloth: the G-buffer lacks uv derivatives (DrawItem::uv_derivatives)");
    tbb::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const int object = gb.object[px];
            const Obj& b = objs[size_t(object)];
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame tf = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            dvec3 v = dvec3(tf.to_local(wo));
            v.z = std::max(v.z, 1e-4);
            v = glm::normalize(v);
            const double footprint = uv_footprint(gb, px) * b.s.repeat;
            const dvec2 uv = dvec2(gb.uv[px]) * b.s.repeat;
            dvec3 L(0.0);
            ClothSample last;
            bool lit = false;
            for (const Light& light : ctx.lighting.lights) {
                vec3 wi, E;
                light.sample(p, wi, E);
                const dvec3 l = dvec3(tf.to_local(wi));
                if (l.z <= 0.0) continue;  // behind the garment's surface
                last = shade(*b.pyr, uv, footprint, b.s.mip, b.s.mip_bias, l, v, dvec3(E));
                L += last.radiance;
                lit = true;
            }
            if (!lit) last = shade(*b.pyr, uv, footprint, b.s.mip, b.s.mip_bias, dvec3(0, 0, 1), v, dvec3(0.0));
            // Holes show the background along the pixel's ray (nothing in texture mode).
            vec3 bg(0.f);
            if (!ctx.camera.texture_mode) bg = constant_env ? env_const : ctx.lighting.env.radiance(ctx.camera.ray_dir(x, y));
            const float a = float(std::clamp(last.alpha, 0.0, 1.0));
            ctx.out.put(AovWriter::kRadiance, x, y, a * vec3(L) + (1.f - a) * bg);
            ctx.out.put(AovWriter::kNormal, x, y, tf.N);
            ctx.out.put(out_alpha, x, y, a);
            ctx.out.put(out_level, x, y, float(last.level));
            ctx.out.put(out_index, x, y, float(last.index));
        }
    });
}

// [SECTION] Export: the acquired samples
std::vector<ExportDecl> ClothTechnique::exports() const {
    ExportDecl e;
    e.name = "cloth-samples";
    e.help = "The acquired samples of a fabric (binary, read back by cloth.samples): acquire once, fit and render many times";
    e.options_help = "(none)";
    e.stages = {stages::stitch, stages::acquire};
    e.run = [](const Scene&, const Evaluation& ev, int object, const std::map<std::string, std::string>& options, const std::string& path,
               const ProgressFn&) {
        for (const auto& kv : options) throw InputError("--option " + kv.first + ": export cloth-samples takes no options");
        const auto g = ev.get(stages::acquire, object);
        if (!g) throw std::logic_error("cloth-samples: cloth.acquire did not run");
        write_sample_grid(path, *g);
        return std::to_string(g->res) + " x " + std::to_string(g->res) + " points, " + std::to_string(g->l.size()) + " light x view pairs, " +
               std::to_string(g->views.size()) + " views; read it back with --set cloth.samples=" + path;
    };
    return {e};
}

// [SECTION] Commands: fit and evaluate measured samples
std::vector<CommandDecl> ClothTechnique::commands() const {
    CommandDecl fit;
    fit.name = "fit";
    fit.help = "Fit the cloth model (Lafortune lobes x view table) to measured BRDF samples, one model per point";
    fit.positionals = {{"samples", "CSV rows [point,]lx,ly,lz,vx,vy,vz,r,g,b: directions in the local frame (z = normal), f_r in 1/sr", true}};
    fit.options = {{"-o,--output", "Model file to write (JSON)", true},
                   {"--lobes", "Lafortune lobes per channel, 1-3 (default 2)", false},
                   {"--lookup-table", "on or off (default on): fit the view-dependent table", false},
                   {"--tolerance", "Stop when the table changes less than this (default 0.1)", false}};
    fit.run = [](const std::map<std::string, std::string>& a, const ProgressFn& progress) {
        FitOptions o;
        o.lobes = parse_int_option(a, "lobes", 2, 1, 3);
        if (auto it = a.find("lookup-table"); it != a.end()) {
            if (it->second != "on" && it->second != "off") throw InputError("--lookup-table " + it->second + ": expected on or off");
            o.lookup_table = it->second == "on";
        }
        o.tolerance = parse_float_option(a, "tolerance", 0.1);
        const SampleSet set = read_samples_csv(a.at("samples"));
        ClothModel m;
        m.lobes = o.lobes;
        m.lookup_table = o.lookup_table;
        m.names = set.names;
        m.brdfs.resize(set.points.size());
        m.reports.resize(set.points.size());
        std::atomic<size_t> done{0};
        std::mutex progress_mutex;
        tbb::parallel_for(size_t(0), set.points.size(), [&](size_t i) {
            m.brdfs[i] = fit_brdf(set.points[i], o, &m.reports[i]);
            const size_t d = ++done;
            if (progress) {
                std::lock_guard<std::mutex> lock(progress_mutex);
                progress(std::string(stages::fit.name), double(d) / double(set.points.size()));
            }
        });
        write_model(a.at("output"), m);
        std::vector<double> rel;
        for (const FitReport& r : m.reports) rel.push_back(r.rel_rms);
        std::sort(rel.begin(), rel.end());
        return "fitted " + std::to_string(m.brdfs.size()) + " point(s) from " + std::to_string(set.rows) + " samples (" + std::to_string(o.lobes) +
               " lobes, lookup table " + (o.lookup_table ? "on" : "off") + "): relative RMS median " + fmt("%.3g", rel[rel.size() / 2]) + ", max " +
               fmt("%.3g", rel.back()) + "\nwrote " + a.at("output");
    };
    CommandDecl eval;
    eval.name = "eval";
    eval.help = "Evaluate a fitted cloth model at given directions: f_r per channel";
    eval.positionals = {{"model", "Model file (JSON) written by mesolab cloth fit", true},
                        {"directions", "CSV rows [point,]lx,ly,lz,vx,vy,vz (point: when the model has several)", true}};
    eval.options = {{"-o,--output", "CSV file to write: rows r,g,b (f_r in 1/sr)", true}};
    eval.run = [](const std::map<std::string, std::string>& a, const ProgressFn&) {
        const ClothModel m = read_model(a.at("model"));
        const std::vector<DirectionRow> rows = read_directions_csv(a.at("directions"), m.names);
        std::ostringstream out;
        char line[128];
        for (const DirectionRow& r : rows) {
            const dvec3 f = m.brdfs[size_t(r.point)].f(r.l, r.v);
            std::snprintf(line, sizeof line, "%.9g,%.9g,%.9g\n", f.x, f.y, f.z);
            out << line;
        }
        write_text_atomic(a.at("output"), out.str());
        return "evaluated " + std::to_string(rows.size()) + " direction pair(s) of " + std::to_string(m.brdfs.size()) + " point(s)\nwrote " +
               a.at("output");
    };
    return {fit, eval};
}

// [SECTION] Timing table
// The paper's figures (Daubert 2001, §7; Athlon 1 GHz, GeForce 2 GTS).
constexpr double kPaperAcquireMs = 45.0 * 60e3;  // "15-45 min": the upper end
constexpr double kPaperFitMs = 2.5 * 3600e3;     // "about 2.5 h"
constexpr double kPaperFrameMs = 1000.0;         // "about 1 fps" at 730 x 400

std::vector<BenchTable> ClothTechnique::bench_tables() const {
    BenchTable t;
    t.name = "cloth";
    t.title = "Daubert et al. 2001: acquisition, fitting (32 x 32 points, 32 x 32 directions, 1365 BRDFs), memory and frames";
    t.paper_machine = "Athlon 1 GHz / GeForce 2 GTS";
    BenchColumn brdfs{"BRDFs"}, memory{"memory (fitted)"}, error{"fit rel. RMS (level 0, median)"};
    brdfs.info = [](const Scene&, const Evaluation& ev) {
        const auto p = ev.get(stages::fit, 0);
        return p ? std::to_string(p->count()) + " in " + std::to_string(p->level.size()) + " levels" : std::string("—");
    };
    memory.info = [](const Scene&, const Evaluation& ev) {
        const auto p = ev.get(stages::fit, 0);
        return p ? fmt("%.2f MB (paper 4 MB)", double(p->bytes()) / 1048576.0) : std::string("—");
    };
    error.info = [](const Scene&, const Evaluation& ev) {
        const auto p = ev.get(stages::fit, 0);
        if (!p || p->report.empty()) return std::string("—");
        std::vector<double> r;
        for (const FitReport& f : p->report[0]) r.push_back(f.rel_rms);
        std::sort(r.begin(), r.end());
        return fmt("%.2f", r[r.size() / 2]);
    };
    t.columns = {brdfs,
                 memory,
                 error,
                 {"stitch mesh", stages::stitch},
                 {"acquisition", stages::acquire},
                 {"fitting", stages::fit},
                 {"frame 730x400", {}, 730, 400, true, true},
                 {"frame 1920x1080", {}, 1920, 1080, true, true}};
    auto row = [](const std::string& stitch) {
        BenchRow r;
        r.name = stitch + " curtain";
        r.scene = [=] {
            Scene s = default_scene("cloth");
            s.name = "cloth-" + stitch;
            apply_set(s, "cloth.stitch", stitch);
            apply_set(s, "light.direction", "50,-60");
            apply_set(s, "light.intensity", "3");
            return s;
        };
        r.paper_ms = {std::nullopt, std::nullopt, std::nullopt, std::nullopt, kPaperAcquireMs, kPaperFitMs, kPaperFrameMs, std::nullopt};
        return r;
    };
    t.rows = {row("knit"), row("weave")};
    return {t};
}

// [SECTION] Sweep metric: the fitted model against a reference acquisition
// Each setting's level-0 BRDFs are evaluated at the reference's samples (the reference grid's
// points mapped to the setting's nearest point, its light x view pairs), as reflected radiance per
// unit irradiance (f_r cos θ_l, the quantity the fit minimises); the error is the RMS over all of
// them relative to the reference's RMS. It includes what the model cannot represent, what fewer
// directions miss between their samples, and what fewer points average away.
std::vector<SweepMetricDecl> ClothTechnique::sweep_metrics() const {
    auto first = [](const Scene& s) {
        for (size_t i = 0; i < s.objects.size(); ++i)
            if (s.objects[i].technique == "cloth") return int(i);
        throw InputError("no object uses technique cloth (the metric cloth.fit measures the first one's fitted BRDFs)");
    };
    SweepMetricDecl m;
    m.name = "cloth.fit";
    m.label = "fit rel. RMS vs reference samples";
    m.unit = "fraction of the RMS";
    m.help = "RMS of f_r cos(theta_l) of the fitted level-0 BRDFs against the reference setting's acquired samples, over their RMS";
    m.check = [first](const Scene& s) { first(s); };
    m.prepare = [first](const Scene& ref, const Evaluation& ref_eval) {
        const auto g = ref_eval.get(stages::acquire, first(ref));
        if (!g) throw std::logic_error("cloth.fit metric: the reference has no cloth.acquire");
        SweepMeasure out;
        out.error = [first, g](const Scene& s, const Evaluation& ev) {
            const auto p = ev.get(stages::fit, first(s));
            if (!p) throw std::logic_error("cloth.fit metric: the setting has no cloth.fit");
            double se = 0.0, sr = 0.0;
            for (int y = 0; y < g->res; ++y)
                for (int x = 0; x < g->res; ++x) {
                    const size_t rp = size_t(y) * size_t(g->res) + size_t(x);
                    const int px = x * p->res / g->res, py = y * p->res / g->res;
                    const size_t e = size_t(py) * size_t(p->res) + size_t(px);
                    const ClothBrdf& b = p->level[0][e];
                    const glm::dmat3& F = p->frame[0][e];
                    for (size_t i = 0; i < g->l.size(); ++i) {
                        const dvec3 model = entry_reflectance(b, F, g->l[i], g->v[i]);
                        const dvec3 r = g->f[rp][i] * g->l[i].z;
                        const dvec3 d = model - r;
                        se += glm::dot(d, d), sr += glm::dot(r, r);
                    }
                }
            return sr > 0.0 ? std::sqrt(se / sr) : 0.0;
        };
        out.notes = "Every setting's level-0 BRDFs against the reference setting's acquired samples (f_r cos theta_l per channel).";
        return out;
    };
    return {m};
}
}  // namespace
}  // namespace mesolab::cloth

namespace mesolab {
void register_cloth(Registry& r) { r.add(std::make_unique<cloth::ClothTechnique>()); }
}  // namespace mesolab
