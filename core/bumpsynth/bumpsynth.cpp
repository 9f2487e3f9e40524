// Technique bumpsynth: declarations, stages, CPU shading and the timing table (see bumpsynth.h).
#include "core/bumpsynth/bumpsynth.h"
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/sweep_metric.h"
#include "core/error.h"
#include "core/heightfield/params.h"
#include "core/image.h"
#include "core/render.h"
#include "core/technique.h"

#include <tbb/parallel_for.h>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mesolab::bumpsynth {
namespace {

// The bump map an NDF may come from (ndf = normal_map | heightfield, §7): the normal map and the
// heightfield's own keys (core/heightfield/params.h: the same surface as in microgeom).
std::vector<std::string> source_keys() {
    std::vector<std::string> k{"ndf", "normal_map", "normal_map_encoding", "normal_map_y"};
    for (const auto& h : heightfield_keys()) k.push_back(h);
    return k;
}
const std::vector<std::string> kSourceKeys = source_keys();
const std::vector<std::string> kNdfKeys = [] {
    std::vector<std::string> k{"alpha_x", "alpha_y", "rotation", "exponent", "lobes", "ndf_image", "ndf_resolution"};
    k.insert(k.begin(), kSourceKeys.begin(), kSourceKeys.end());
    return k;
}();
const std::vector<std::string> kNoiseKeys{"noise_frequency", "noise_gain", "noise_seed", "octaves_max"};

std::vector<std::string> keys(const std::vector<std::string>& names) {
    std::vector<std::string> out;
    for (const auto& n : names) out.push_back("bumpsynth." + n);
    return out;
}
bool from_bump_map(const SceneObject& o) {
    const std::string& n = o.material.get_string("ndf");
    return n == "normal_map" || n == "heightfield";
}
// §7: the bump map's own normals through the index texture instead of noise.
bool index_mode(const SceneObject& o) { return from_bump_map(o) && o.material.get_bool("index_map"); }
bool noise_inputs_needed(const SceneObject& o) { return !index_mode(o); }
bool texture_noise(const SceneObject& o) { return !index_mode(o) && o.material.get_string("noise") == "texture"; }
bool masking(const SceneObject& o) { return o.material.get_bool("masking"); }
}  // namespace

// [SECTION] Materials
BumpNormals bump_normals_from_material(const Scene& s, const ParamTable& m) {
    const std::string& kind = m.get_string("ndf");
    if (kind == "heightfield") return normals_of(heightfield_from_material(s, m));
    if (kind != "normal_map") throw std::logic_error("bumpsynth: ndf " + kind + " has no bump map");
    const std::string path = s.resolve(m.get_string("normal_map"));
    if (path.empty()) throw InputError("bumpsynth.normal_map: ndf is normal_map but no image is given");
    NormalMapFormat f;
    f.encoding = m.get_string("normal_map_encoding") == "signed" ? NormalEncoding::signed_unit : NormalEncoding::unsigned_unit;
    f.y_down = m.get_string("normal_map_y") == "down";
    return read_normal_map(path, f);
}

Ndf ndf_from_material(const Scene& s, const ParamTable& m, const BumpNormals* normals) {
    const std::string kind = m.get_string("ndf");
    const int R = int(m.get_int("ndf_resolution"));
    if (kind == "normal_map" || kind == "heightfield") {
        BumpNormals own;
        if (!normals) own = bump_normals_from_material(s, m), normals = &own;
        return Ndf::from_normals(normals->m, R);
    }
    const vec2 alpha(float(m.get_float("alpha_x")), float(m.get_float("alpha_y")));
    const float rotation = float(m.get_float("rotation"));
    if (kind == "phong") return Ndf::from_lobe(Lobe::blinn_phong(float(m.get_float("exponent"))), R);
    if (kind == "lobes") {
        try {
            return Ndf::from_lobes(parse_lobes(m.get_string("lobes")), R);
        } catch (const InputError& e) {
            throw InputError("bumpsynth.lobes: " + std::string(e.what()));
        }
    }
    if (kind == "image") {
        const std::string path = s.resolve(m.get_string("ndf_image"));
        if (path.empty()) throw InputError("bumpsynth.ndf_image: ndf is image but no image is given");
        const Image img = read_image(path, false, true);
        std::vector<float> px(size_t(img.width) * size_t(img.height));
        const int c = std::min(img.channels, 3);
        for (size_t i = 0; i < px.size(); ++i) {
            float v = 0.f;
            for (int k = 0; k < c; ++k) v += img.data[i * size_t(img.channels) + size_t(k)];
            px[i] = v / float(c);
        }
        try {
            return Ndf::from_image(px, img.width, img.height, R);
        } catch (const InputError& e) {
            throw InputError(path + ": " + e.what());
        }
    }
    LobeKind k = LobeKind::beckmann;
    lobe_kind(kind, k);  // beckmann, ggx or ward: the enum's remaining choices
    return Ndf::from_lobe(Lobe::anisotropic(k, alpha.x, alpha.y, rotation), R);
}

NoiseParams noise_from_material(const ParamTable& m) {
    NoiseParams n;
    n.base_frequency = int(m.get_int("noise_frequency"));
    n.gain = float(m.get_float("noise_gain"));
    n.seed = uint32_t(m.get_int("noise_seed"));
    n.octaves_max = int(m.get_int("octaves_max"));
    n.validate();
    return n;
}

ShadingModel shading_from_material(const ParamTable& m) {
    ShadingModel s;
    s.ks = m.get_vec3("ks");
    s.kd = m.get_vec3("kd");
    s.fresnel = m.get_bool("fresnel");
    s.masking = m.get_bool("masking");
    return s;
}

Synthesis synthesis_for(const Scene& s, const Evaluation& ev, int object) {
    Synthesis syn;
    syn.ndf = ev.get(stages::ndf, object).get();
    syn.lut = ev.get(stages::lut, object).get();
    const SceneObject& o = s.objects[size_t(object)];
    const ParamTable& m = o.material;
    syn.octaves_max = int(m.get_int("octaves_max"));
    syn.detail_distance = float(m.get_float("detail_distance"));
    if (index_mode(o)) {
        syn.index_map = ev.get(stages::index_map, object).get();
        if (syn.index_map) syn.index_detail = index_detail(*syn.index_map, noise_from_material(m), float(m.get_float("index_noise")));
    } else {
        syn.cdfs = ev.get(stages::noise_cdf, object).get();
        if (texture_noise(o)) syn.noise_texture = ev.get(stages::noise_texture, object).get();
    }
    syn.model = shading_from_material(m);
    if (syn.model.masking) syn.smith = ev.get(stages::masking, object).get();
    syn.albedo = ev.get(stages::albedo, object).get();
    return syn;
}

float pixel_octaves(const Synthesis& syn, bool texture_mode, vec3 eye, vec3 p) {
    const int K = syn.octaves_max;
    return texture_mode ? float(K) : octaves_at_distance(glm::length(eye - p), syn.detail_distance, K);
}

namespace {

class BumpsynthTechnique final : public Technique {
public:
    BumpsynthTechnique() : Technique("bumpsynth", "Bump map synthesis (Kautz et al. 2001)") {
        auto& p = params_;
        const std::vector<std::string> lobed{"beckmann", "ggx", "ward"};
        p.add_enum("ndf", {"phong", "beckmann", "ggx", "ward", "lobes", "image", "normal_map", "heightfield"}, "beckmann")
            .doc("Normal density function: an analytic lobe, a weighted sum of lobes (bumpsynth.lobes), an image of D over the normal's (x, y) disk, or the "
                 "histogram of an existing bump map's normals (a normal map, or a heightfield as in microgeom; §7)");
        p.add_float("alpha_x", 0.3).range(1e-4, 1.0).log().used_when("ndf", lobed)
            .doc("Roughness along the lobe's x axis (RMS slope for Beckmann)");
        p.add_float("alpha_y", 0.3).range(1e-4, 1.0).log().used_when("ndf", lobed)
            .doc("Roughness along the lobe's y axis (alpha_x != alpha_y: anisotropic)");
        p.add_float("rotation", 0.0).range(-360.0, 360.0).in("degrees").used_when("ndf", lobed)
            .doc("Rotation of the lobe's x axis from the surface tangent towards the bitangent");
        p.add_float("exponent", 50.0).range(0.0, 2e8).log().used_when("ndf", {"phong"})
            .doc("Blinn-Phong exponent e: D = (e + 2)/(2 pi) cos^e");
        p.add_text("lobes", "beckmann(0.3) + 0.5 * ggx(0.05, 0.5, 45)").checked(lobes_syntax_error).used_when("ndf", {"lobes"})
            .doc("A weighted sum of any number of lobes, e.g. 'beckmann(0.08, 0.3) + 0.5 * ggx(0.3, 0.05, 45)': phong(exponent), "
                 "beckmann | ggx | ward(alpha) or (alpha_x, alpha_y) or (alpha_x, alpha_y, rotation in degrees), each optionally "
                 "times a weight (default 1; the sum is normalised)");
        p.add_path("ndf_image", "").used_when("ndf", {"image"})
            .doc("Image of D over [-1, 1]^2 (x right, y up; any positive scale; channels averaged; pixels outside the disk ignored)");
        p.add_path("normal_map", "").used_when("ndf", {"normal_map"})
            .doc("Tangent-space normal map (RGB = x along u, y along v, z out of the surface; row 0 at v = 1); relative to the preset's folder");
        p.add_enum("normal_map_encoding", {"unsigned", "signed"}, "unsigned").used_when("ndf", {"normal_map"})
            .doc("unsigned: components stored as (v + 1)/2 in [0, 1] (8/16-bit maps); signed: stored as they are (float maps)");
        p.add_enum("normal_map_y", {"up", "down"}, "up").used_when("ndf", {"normal_map"})
            .doc("Green channel convention: up (OpenGL, Blender) or down (DirectX, Unreal: y negated)");
        declare_heightfield_params(p, [](ParamDecl& d) {
            d.used_when("ndf", {"heightfield"});
            d.help += " (the same surface as microgeom." + d.name + ")";
        });
        p.add_bool("index_map", false).used_when("ndf", {"normal_map", "heightfield"})
            .doc("§7: render the bump map's own normals through an index texture into the look-up table (instead of noise), "
                 "adding index_noise detail when zooming in past its texels");
        p.add_float("index_noise", 0.03).range(0.0, 0.5).used_when("index_map", {"true"})
            .doc("Amplitude of the detail noise added to the index texture's inputs (uniform units) per octave beyond the bump map");
        p.add_int("ndf_resolution", 128).range(64, 512).in("cells").more_accurate(Accuracy::Higher, int64_t(512))
            .doc("Cells per side of the tabulated NDF");
        p.add_int("lut_size", 256).range(16, 4096).in("entries").more_accurate(Accuracy::Higher, int64_t(4096))
            .doc("Entries per side of the normal look-up table L(r1, r2) (the paper: 256)");
        p.add_int("octaves_max", 8).range(1, 16)
            .doc("Octaves of noise at full detail (K); one more octave fades in at every halving of the eye distance");
        p.add_float("detail_distance", 4.0).range(1e-6, 1e6).log().in("scene units")
            .doc("Eye distance beyond which there are no bumps (shading with the NDF alone)");
        p.add_enum("noise", {"procedural", "texture"}, "procedural")
            .doc("Perlin noise evaluated per pixel, or the paper's mip-mapped noise texture (one octave less per level)");
        p.add_int("noise_frequency", 8).range(1, 4096).in("cells per uv unit")
            .doc("Lattice cells of the first octave across the uv square (an integer, so the noise tiles uv)");
        p.add_float("noise_gain", 0.5).range(0.01, 1.0).doc("Amplitude ratio between successive octaves");
        p.add_int("noise_seed", 1).range(0, 1 << 30).doc("Seed of the noise (both channels)");
        p.add_int("noise_texture_size", 1024).range(16, 4096).in("texels").used_when("noise", {"texture"})
            .doc("Size of the finest level of the noise texture (a power of two)");
        p.add_color("ks", {0.9, 0.9, 0.9}).doc("Specular colour (F0 with fresnel on)");
        p.add_color("kd", {0.1, 0.1, 0.1}).doc("Separate diffuse albedo, bump-mapped with the synthesised normal (0: NDF only, as in the paper)");
        p.add_bool("fresnel", false).doc("Schlick's Fresnel with F0 = ks");
        p.add_bool("masking", false).doc("Smith masking-shadowing of the same NDF (off: the paper's implicit term)");
        p.add_path("albedo_map", "")
            .doc("Image multiplying kd at the surface's (u, v) (8-bit images are sRGB); relative to the preset's folder");
        aovs_ = {{"octaves", 1, "Octaves of noise at the pixel (0: NDF alone; fractional while an octave fades in)"},
                 {"entry", 3, "Look-up-table entry (a, b) of the pixel's microfacet of k octaves, and k ((-1, -1, 0): no bumps)"},
                 {"entry_fine", 3, "The same for k + 1 octaves while an octave fades in (else the same as entry)"}};
    }

    void declare_stages(StageGraph& g) const override {
        // Every stage is an object stage: one result per object, shared by objects with equal keys.
        const auto object = [](StageDecl d) {
            d.scope = StageScope::Object;
            d.technique = "bumpsynth";
            return d;
        };
        const auto when = [](bool (*f)(const SceneObject&)) { return [f](const Scene&, const SceneObject& o) { return f(o); }; };
        g.add(stages::bump_normals, object({.help = "Read the bump map (a normal map, or a heightfield's normals) whose histogram is the NDF (§7)",
                      .params = keys(kSourceKeys),
                      .applies = when(from_bump_map),
                      .when_text = "bumpsynth.ndf is normal_map or heightfield",
                      .run = [](StageContext& ctx) { return stage_result(stages::bump_normals, bump_normals_from_material(ctx.scene, ctx.material())); }}));
        g.add(stages::ndf, object({.help = "Tabulate the normal density function over the normal's (x, y) disk",
                      .params = keys(kNdfKeys),
                      .inputs = {stages::bump_normals},
                      .memory = [](const StageContext& ctx) {
                          const double R = double(ctx.material().get_int("ndf_resolution"));
                          return MemoryEstimate{R * R * 2.0 * sizeof(double), "NDF: " + std::to_string(int(R)) + "^2 cells", {"bumpsynth.ndf_resolution"}};
                      },
                      .run = [](StageContext& ctx) {
                          const auto n = ctx.input(stages::bump_normals);
                          const ParamTable& m = ctx.material();
                          if (n) {
                              // A histogram with fewer normals than cells is spiky: highlights sparkle.
                              const double R = double(m.get_int("ndf_resolution")), cells = 0.785398 * R * R;
                              const double per_cell = double(n->m.size()) / cells;
                              if (per_cell < 2.0) {
                                  char msg[320];
                                  std::snprintf(msg, sizeof msg,
                                                "the NDF of a %dx%d bump map at %dx%d cells has %.2g normals per cell of the disk, so it is "
                                                "spiky (highlights sparkle); lower bumpsynth.ndf_resolution (to %d or less) or use a larger map",
                                                n->width, n->height, int(R), int(R), per_cell,
                                                std::max(64, int(std::sqrt(double(n->m.size()) / (2.0 * 0.785398)))));
                                  ctx.warn(msg);
                              }
                          }
                          return stage_result(stages::ndf, ndf_from_material(ctx.scene, m, n.get()));
                      }}));
        g.add(stages::lut, object({.help = "Invert the NDF's marginal and conditional CDFs into the normal look-up table L(r1, r2) with tangent frames (§4)",
                      .params = keys({"lut_size"}),
                      .inputs = {stages::ndf},
                      .memory = [](const StageContext& ctx) {
                          const double n = double(ctx.material().get_int("lut_size"));
                          return MemoryEstimate{n * n * double(sizeof(LutEntry)), "look-up table: " + std::to_string(int(n)) + "^2 entries",
                                                {"bumpsynth.lut_size"}};
                      },
                      .run = [](StageContext& ctx) {
                          return stage_result(stages::lut, build_lut(*ctx.input(stages::ndf), int(ctx.material().get_int("lut_size"))));
                      }}));
        g.add(stages::index_map, object({.help = "Turn the bump map's normals into an index texture of look-up-table inputs (§7)",
                      .params = keys({"index_map"}),
                      .inputs = {stages::bump_normals, stages::lut},
                      .applies = when(index_mode),
                      .when_text = "bumpsynth.index_map is on",
                      .run = [](StageContext& ctx) {
                          return stage_result(stages::index_map, make_index_map(*ctx.input(stages::bump_normals), *ctx.input(stages::lut)));
                      }}));
        g.add(stages::noise_cdf, object({.help = "Measure the CDF G_k of the fractal noise for every octave count k (§4)",
                      .params = keys(kNoiseKeys),
                      .applies = when(noise_inputs_needed),
                      .when_text = "an object synthesises its bumps from noise (bumpsynth.index_map off)",
                      .run = [](StageContext& ctx) { return stage_result(stages::noise_cdf, measure_noise_cdfs(noise_from_material(ctx.material()))); }}));
        g.add(stages::noise_texture, object({.help = "Bake the mip-mapped noise texture: each coarser level one octave less (§5.2.2)",
                      .params = keys({"noise", "noise_texture_size"}),
                      .inputs = {stages::noise_cdf},
                      .applies = when(texture_noise),
                      .when_text = "bumpsynth.noise is texture",
                      .memory = [](const StageContext& ctx) {
                          const double n = double(ctx.material().get_int("noise_texture_size"));
                          // Two channels of floats over the mip chain (4/3 of the finest level).
                          return MemoryEstimate{n * n * 4.0 / 3.0 * 2.0 * sizeof(float), "noise texture: " + std::to_string(int(n)) + "^2 texels with mip levels",
                                                {"bumpsynth.noise_texture_size"}};
                      },
                      .run = [](StageContext& ctx) {
                          return stage_result(stages::noise_texture, make_noise_texture(*ctx.input(stages::noise_cdf), int(ctx.material().get_int("noise_texture_size"))));
                      }}));
        g.add(stages::masking, object({.help = "Tabulate the Smith masking function G1 of the NDF",
                      .params = keys({"masking"}),
                      .inputs = {stages::ndf},
                      .applies = when(masking),
                      .when_text = "bumpsynth.masking is on",
                      .run = [](StageContext& ctx) { return stage_result(stages::masking, SmithTable::build(*ctx.input(stages::ndf))); }}));
        g.add(stages::albedo, object({.help = "Read the object's albedo map",
                      .params = {"bumpsynth.albedo_map"},
                      .run = [](StageContext& ctx) -> std::any {
                          auto img = basic::read_albedo_map(ctx.scene, ctx.material());
                          return img ? stage_result(stages::albedo, std::move(*img)) : std::any();
                      }}));
    }

    std::vector<StageName> frame_stages() const override {
        return {stages::ndf, stages::lut, stages::index_map, stages::noise_cdf, stages::noise_texture, stages::masking, stages::albedo};
    }

    // Texture mode: the uv square at one pixel per cell of the finest octave (at least 512, at most 4096).
    // Index map: one pixel per cell of the finest detail octave (the bump map's texels at K = 1).
    std::optional<ivec2> texture_size(const Scene& s, const Evaluation& ev) const override {
        for (size_t i = 0; i < s.objects.size(); ++i) {
            const SceneObject& o = s.objects[i];
            if (o.technique != "bumpsynth") continue;
            const ParamTable& m = o.material;
            if (index_mode(o)) {
                const auto map = ev.get(stages::index_map, int(i));
                if (!map) return std::nullopt;
                const int K = int(m.get_int("octaves_max"));
                const auto side = [&](int n) { return int(std::min<int64_t>(4096, int64_t(n) << (K - 1))); };
                return ivec2(std::max(map->width, side(map->width)), std::max(map->height, side(map->height)));
            }
            if (texture_noise(o)) return ivec2(int(m.get_int("noise_texture_size")));
            const double cells = double(m.get_int("noise_frequency")) * std::ldexp(1.0, int(m.get_int("octaves_max")) - 1);
            const int side = int(std::clamp(cells, 512.0, 4096.0));
            return ivec2(side);
        }
        return std::nullopt;
    }

    void shade_cpu(const ShadeContext& ctx) const override;
    std::vector<BenchTable> bench_tables() const override;
    // The two paths compute the same inputs bit for bit from the same uv (gpu/bumpsynth/synthesis.glsl,
    // tests/bumpsynth/inputs_gpu_test.cpp), and so the same table entries and facets; what differs is
    // the rasterisers' uv and position (a few ULP, 4e-7, once the GPU's vertices sit on the CPU's
    // sub-pixel grid: gpu/shaders/mesh.vert) and the shading's float evaluation (the GPU's normalize,
    // log2, pow, acos, atan within a few ULP). Hence:
    //  - interior_max 1e-3, no outliers: with the same entries a value moves by the shading's rounding
    //    amplified by the NDF's slope; the tabulated D changes by up to D_max R / 2 per unit of the
    //    half vector (Beckmann 0.08 x 0.35 at R = 128: 730), so ~1e-6 in h gives up to ~5e-4 in
    //    radiance. Measured worst: 3.1e-4 (the §7 index map's spiky histogram NDF), 1.8e-4 with
    //    masking and Fresnel, 2e-5 elsewhere; normals 5e-7.
    //  - the nearest entry cannot be made identical: it is discontinuous in the inputs, and the
    //    inputs of two uv a few ULP apart straddle a cell edge with probability S |du| per input,
    //    |du| = |du/duv| |duv| (teapot, 48 cells, 8 octaves: |du/duv| ~ 300, |duv| ~ 3e-8 on
    //    average, S = 256: ~0.2% per input, ~0.5% of the pixels). Such a pixel shows the
    //    neighbouring entry, a whole facet away (1.4 in radiance at a column jump of the index
    //    map's table): the entries (AOVs entry, entry_fine) tell these flips apart, neighbours in
    //    the table by construction; they may be 1% of the pixels off edges (measured at most
    //    0.41%, the teapot presets, llvmpipe). Entries further apart fail.
    //  - tight and loose over every covered value, edges too: flips (up to 1%) are most of what
    //    exceeds 1e-3 (99.7% within it in every preset), and nearly all are within 1e-2.
    FrameAgreement agreement() const override {
        return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.999, .interior_max = 1e-3, .interior_outliers = 0,
                .choices = {"entry", "entry_fine"}, .interior_flips = 1e-2,
                .why = "uv a few ULP apart; a look-up-table entry flips where its inputs straddle a cell edge"};
    }
    // The distance of the synthesised normals' histogram from the NDF (sweep_metric.h).
    std::vector<SweepMetricDecl> sweep_metrics() const override { return {ndf_histogram_metric()}; }
};

// [SECTION] CPU shading
void BumpsynthTechnique::shade_cpu(const ShadeContext& ctx) const {
    const GBuffer& gb = ctx.gbuffer;
    const int octaves_out = ctx.out.index("octaves"), entry_out = ctx.out.index("entry"), entry_fine_out = ctx.out.index("entry_fine");
    // Materials parsed once per frame into each object's synthesis.
    std::map<int, Synthesis> syns;
    for (int i : ctx.objects) syns[i] = synthesis_for(ctx.scene, ctx.eval, i);
    tbb::parallel_for(0, gb.height, [&](int y) {
        for (int x = 0; x < gb.width; ++x) {
            const size_t px = gb.index(x, y);
            if (!ctx.mine(px)) continue;
            const int obj = gb.object[px];
            const Synthesis& syn = syns.at(obj);
            const vec3 p = gb.position[px];
            const vec3 wo = ctx.camera.wo(p);
            const TangentFrame frame = tangent_frame(gb.normal[px], gb.tangent[px], wo);
            const vec2 uv = gb.uv[px];
            const float o = pixel_octaves(syn, ctx.camera.texture_mode, ctx.camera.eye, p);
            const FacetBlend fb = facets_at(syn, uv, o);
            const vec3 tex = syn.albedo ? basic::sample_albedo(*syn.albedo, uv) : vec3(1.f);
            const vec3 wo_t = frame.to_local(wo);
            auto shade = [&](const LutEntry& f) {
                vec3 L(0.f);
                for (const Light& l : ctx.lighting.lights) {
                    vec3 wi, E;
                    l.sample(p, wi, E);
                    L += shade_facet(syn.model, *syn.ndf, syn.smith, f, wo_t, frame.to_local(wi), E, tex);
                }
                return L + syn.model.kd * tex * kInvPi * ctx.lighting.env_irradiance(frame.to_world(f.m));
            };
            const vec3 L = fb.w > 0.f ? glm::mix(shade(fb.coarse), shade(fb.fine), fb.w) : shade(fb.coarse);
            const vec3 n = fb.w > 0.f ? glm::normalize(glm::mix(fb.coarse.m, fb.fine.m, fb.w)) : fb.coarse.m;
            ctx.out.put(AovWriter::kRadiance, x, y, L);
            ctx.out.put(AovWriter::kNormal, x, y, n);
            ctx.out.put(octaves_out, x, y, o);
            ctx.out.put(entry_out, x, y, vec3(vec2(fb.coarse_entry), float(fb.k)));
            ctx.out.put(entry_fine_out, x, y, vec3(vec2(fb.fine_entry), float(fb.w > 0.f ? fb.k + 1 : fb.k)));
        }
    });
}

// [SECTION] Timing table
// Kautz et al. 2001, §6: the paper's frame time, about 30 Hz (its only timing).
constexpr double kPaperFrameMs = 33.0;

std::vector<BenchTable> BumpsynthTechnique::bench_tables() const {
    auto scene = [](const char* geometry, std::vector<std::pair<const char*, const char*>> extra) {
        return [=] {
            Scene s = default_scene("bumpsynth");
            s.name = std::string("bumpsynth-") + geometry;
            apply_set(s, "geometry.type", geometry);
            apply_set(s, "bumpsynth.alpha_x", "0.1");
            apply_set(s, "bumpsynth.alpha_y", "0.4");
            apply_set(s, "bumpsynth.rotation", "30");
            for (const auto& [k, v] : extra) apply_set(s, k, v);
            return s;
        };
    };
    BenchTable pre;
    pre.name = "bumpsynth";
    pre.title = "Kautz et al. 2001: NDF tabulation, look-up table and noise CDFs (anisotropic Beckmann 0.1 x 0.4, 30 degrees)";
    pre.paper_machine = "the paper gives no precomputation times (\"done once for every NDF in a preprocessing step\")";
    pre.columns = {{"NDF", stages::ndf}, {"LUT L(r1, r2)", stages::lut}, {"noise CDFs G_1..G_8", stages::noise_cdf},
                   {"Smith table", stages::masking}};
    for (const char* size : {"64", "128", "256", "512", "1024"})
        pre.rows.push_back({std::string("LUT ") + size + "^2, NDF 128^2", scene("sphere", {{"bumpsynth.lut_size", size}, {"bumpsynth.masking", "true"}}), {}});
    pre.rows.push_back({"LUT 256^2, NDF 512^2", scene("sphere", {{"bumpsynth.ndf_resolution", "512"}, {"bumpsynth.masking", "true"}}), {}});

    BenchTable frame;
    frame.name = "bumpsynth-frame";
    frame.title = "Kautz et al. 2001, §6 / Fig. 5: frame time at 1280x720 (teapot: ~17,000 triangles in the paper)";
    frame.paper_machine = "AMD Athlon 1 GHz + NVIDIA GeForce 3 (about 30 Hz = " + std::to_string(int(kPaperFrameMs)) + " ms)";
    frame.columns = {{"frame 1280x720", {}, 1280, 720, true, true}};
    // The teapot at 16,384 triangles (the paper's ~17,000) filling the frame; detail_distance puts
    // the camera at full detail (8 octaves) or beyond it (NDF only).
    const auto teapot = [&](std::vector<std::pair<const char*, const char*>> extra) {
        extra.insert(extra.begin(), {{"geometry.resolution", "128"}, {"camera.distance", "3.4"}, {"bumpsynth.noise_frequency", "48"}, {"bumpsynth.detail_distance", "1000"}});
        return scene("teapot", extra);
    };
    frame.rows = {{"teapot, procedural noise, 8 octaves", teapot({}), {kPaperFrameMs}},
                  {"teapot, noise texture (the paper's path)", teapot({{"bumpsynth.noise", "texture"}}), {kPaperFrameMs}},
                  {"teapot, far (NDF only)", teapot({{"bumpsynth.detail_distance", "1"}}), {}},
                  {"teapot, masking + Fresnel", teapot({{"bumpsynth.masking", "true"}, {"bumpsynth.fresnel", "true"}}), {}}};
    return {pre, frame};
}
}  // namespace
}  // namespace mesolab::bumpsynth

namespace mesolab {
void register_bumpsynth(Registry& r) { r.add(std::make_unique<bumpsynth::BumpsynthTechnique>()); }
}  // namespace mesolab
