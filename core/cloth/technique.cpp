// Technique cloth: its parameters and AOVs, the settings read from them, the agreement between
// the CPU and GPU paths, the samples export and the fit-error sweep metric (technique.h).
#include "core/cloth/technique.h"
#include "core/cloth/samples.h"
#include "core/cloth/stages.h"
#include "core/error.h"

#include <cmath>
#include <string>

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
        s.acquire.bounces = int(t.get_int("bounces"));
        s.samples = sc.resolve(t.get_string("samples"));
    }
    if (parts & Fit) {
        s.fit.sheen = t.get_string("method") == "sheen";
        if (!s.fit.sheen) s.fit.lobes = int(t.get_int("lobes"));
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

// [SECTION] Parameters and AOVs
ClothTechnique::ClothTechnique() : Technique("cloth", "Cloth (Daubert et al. 2001)") {
    paper_method_ = "daubert";
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
        .doc("Rays per vertex of the precomputed visibility for the indirect bounces (0: direct light only)");
    p.add_int("bounces", 1).range(0, 64).more_accurate(Accuracy::Higher, int64_t(32))
        .doc("Bounces of light between the yarns in the acquisition (the paper: 1; each gathers the previous one through the same "
             "visibility rays; the truth keeps every bounce); 0: direct light only");
    p.add_path("samples", "")
        .doc("Acquired samples to fit instead of acquiring (mesolab export cloth-samples writes them); relative to the preset's folder");
    p.add_int("lobes", 2).range(1, 3).more_accurate(Accuracy::Higher, int64_t(3)).used_when("method", {"daubert"}).doc("Lafortune lobes per channel");
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
    params_.section("Acquisition", {"spatial", "directions", "visibility_rays", "bounces", "samples"});
    params_.section("Fit", {"lobes", "lookup_table", "tolerance"});
    params_.section("Garment and mip blending", {"garment", "garment_resolution", "repeat", "mip", "mip_bias"});
    aovs_ = {{"alpha", 1, "The table's alpha: 1 yarn, 0 a hole (the background shows through)"},
             {"mip_level", 1, "Mip level read (fractional when blending): 0 = one BRDF per sample point"},
             {"brdf_index", 1, "Index of the BRDF read (the finer level when blending), counting level by level from level 0"}};
}

std::vector<StageName> ClothTechnique::pipeline_stages() { return {stages::fit, stages::garment}; }
std::vector<StageName> ClothTechnique::frame_stages() const { return pipeline_stages(); }

std::shared_ptr<const TriMesh> ClothTechnique::object_mesh(const Scene&, const Evaluation& ev, int object) const {
    return ev.get(stages::garment, object);
}

// [SECTION] Agreement between the CPU and GPU paths
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
FrameAgreement ClothTechnique::agreement() const {
    return {.tight = 2e-3, .frac_tight = 0.99, .loose = 3e-2, .frac_loose = 0.995, .interior_max = 1e-2, .interior_outliers = 1e-4,
            .why = "a pixel whose uv lies within rounding of a border between two sample points reads a neighbouring entry"};
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
}  // namespace mesolab::cloth

namespace mesolab {
void register_cloth(Registry& r) { r.add(std::make_unique<cloth::ClothTechnique>()); }
}  // namespace mesolab
