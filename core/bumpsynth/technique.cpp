// Technique bumpsynth: its parameters and AOVs, what a frame needs, how closely the GPU follows the
// CPU, its sweep metric and registration (see technique.h for the other files).
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/sweep_metric.h"
#include "core/bumpsynth/technique.h"

#include <algorithm>
#include <cmath>

namespace mesolab::bumpsynth {

BumpsynthTechnique::BumpsynthTechnique() : Technique("bumpsynth", "Bump map synthesis (Kautz et al. 2001)") {
    paper_method_ = "kautz";
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
    p.add_int("ndf_resolution", 128).used_when("method", {"kautz", "kautz-consistent"}).range(64, 512).in("cells").more_accurate(Accuracy::Higher, int64_t(512))
        .doc("Cells per side of the tabulated NDF");
    p.add_int("lut_size", 256).used_when("method", {"kautz", "kautz-consistent"}).range(16, 4096).in("entries").more_accurate(Accuracy::Higher, int64_t(4096))
        .doc("Entries per side of the normal look-up table L(r1, r2) (the paper: 256)");
    p.add_int("octaves_max", 8).range(1, 16)
        .doc("Octaves of noise at full detail (K); one more octave fades in at every halving of the eye distance");
    p.add_float("detail_distance", 4.0).used_when("method", {"kautz", "kautz-consistent"}).range(1e-6, 1e6).log().in("scene units")
        .doc("Eye distance beyond which there are no bumps (shading with the NDF alone)");
    p.add_enum("noise", {"procedural", "texture"}, "procedural").used_when("method", {"kautz", "kautz-consistent"})
        .doc("Perlin noise evaluated per pixel, or the paper's mip-mapped noise texture (one octave less per level)");
    p.add_int("noise_frequency", 8).range(1, 4096).in("cells per uv unit")
        .doc("Lattice cells of the first octave across the uv square (an integer, so the noise tiles uv)");
    p.add_float("noise_gain", 0.5).range(0.01, 1.0).doc("Amplitude ratio between successive octaves");
    p.add_int("noise_seed", 1).range(0, 1 << 30).doc("Seed of the noise (both channels)");
    p.add_int("noise_texture_size", 1024).range(16, 4096).power_of_two().in("texels").used_when("noise", {"texture"})
        .doc("Size of the finest level of the noise texture (a power of two)");
    p.add_color("ks", {0.9, 0.9, 0.9}).doc("Specular colour (F0 with fresnel on)");
    p.add_color("kd", {0.1, 0.1, 0.1}).doc("Separate diffuse albedo, bump-mapped with the synthesised normal (0: NDF only, as in the paper)");
    p.add_bool("fresnel", false).doc("Schlick's Fresnel with F0 = ks");
    p.add_bool("masking", false).doc("Smith masking-shadowing of the same NDF (off: the paper's implicit term)");
    p.add_path("albedo_map", "")
        .doc("Image multiplying kd at the surface's (u, v) (8-bit images are sRGB); relative to the preset's folder");
    p.section("NDF", {"ndf", "alpha_x", "alpha_y", "rotation", "exponent", "lobes", "ndf_image", "ndf_resolution"});
    p.section("Bump map (§7)", {"normal_map", "normal_map_encoding", "normal_map_y", "heightfield", "resolution", "height_scale", "texel_size", "periodic",
                                "vgroove_angle", "rms_slope", "correlation", "seed", "index_map", "index_noise"});
    p.section("Synthesis", {"lut_size", "octaves_max", "detail_distance", "noise", "noise_frequency", "noise_gain", "noise_seed", "noise_texture_size"});
    p.section("Shading", {"ks", "kd", "fresnel", "masking", "albedo_map"});
    aovs_ = {{"octaves", 1, "Octaves of noise at the pixel (0: NDF alone; fractional while an octave fades in)"},
             {"entry", 3, "Look-up-table entry (a, b) of the pixel's microfacet of k octaves, and k ((-1, -1, 0): no bumps)"},
             {"entry_fine", 3, "The same for k + 1 octaves while an octave fades in (else the same as entry)"}};
}

std::vector<StageName> BumpsynthTechnique::pipeline_stages() {
    return {stages::ndf, stages::lut, stages::index_map, stages::noise_cdf, stages::noise_texture, stages::masking, stages::albedo, stages::consistent};
}
std::vector<StageName> BumpsynthTechnique::frame_stages() const { return pipeline_stages(); }

// Texture mode: the uv square at one pixel per cell of the finest octave (at least 512, at most 4096).
// Index map: one pixel per cell of the finest detail octave (the bump map's texels at K = 1).
std::optional<ivec2> BumpsynthTechnique::texture_size(const Scene& s, const Evaluation& ev) const {
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
FrameAgreement BumpsynthTechnique::agreement() const {
    return {.tight = 1e-3, .frac_tight = 0.99, .loose = 1e-2, .frac_loose = 0.999, .interior_max = 1e-3, .interior_outliers = 0,
            .choices = {"entry", "entry_fine"}, .interior_flips = 1e-2,
            .why = "uv a few ULP apart; a look-up-table entry flips where its inputs straddle a cell edge"};
}

// The distance of the synthesised normals' histogram from the NDF (sweep_metric.h).
std::vector<SweepMetricDecl> BumpsynthTechnique::sweep_metrics() const { return {ndf_histogram_metric()}; }
}  // namespace mesolab::bumpsynth

namespace mesolab {
void register_bumpsynth(Registry& r) { r.add(std::make_unique<bumpsynth::BumpsynthTechnique>()); }
}  // namespace mesolab
