// Technique microgeom: its parameters, effect and AOVs, the stages a frame needs, and registration
// (see microgeom.h; the stages, shading, export and timing tables are in the files technique.h lists).
#include "core/heightfield/params.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/technique.h"

namespace mesolab::microgeom {

// [SECTION] The technique
MicrogeomTechnique::MicrogeomTechnique() : Technique("microgeom", "Micro-geometry (Heidrich et al. 2000)") {
    paper_method_ = "heidrich";
    auto& p = params_;
    declare_heightfield_params(p);
    p.add_color("albedo", {0.8, 0.8, 0.8})
        .doc("Albedo of the micro-surface (Lambert); procedural fields modulate it (triangles: red/white faces, bricks: brick and mortar)");
    p.add_path("albedo_map", "")
        .doc("Per-texel albedo image (8/16-bit sRGB or float linear), resampled bilinearly (wrapping) onto the heightfield's texels and "
             "multiplied by albedo; empty: the procedural rule");
    p.add_int("directions", 100).used_when("method", {"heidrich"}).range(16, 1024).more_accurate(Accuracy::Higher, int64_t(1024))
        .doc("N: directions over the whole sphere for the visibility textures S_i (and their triangulation)");
    p.add_int("depth", 2).used_when("method", {"heidrich"}).range(0, 8).more_accurate(Accuracy::Higher, int64_t(8))
        .doc("K: bounces of light scattered inside the heightfield (direct light is added at every scattering point)");
    p.add_enum("sampling", {"all", "random"}, "all").used_when("method", {"heidrich"})
        .doc("Directions gathered per bounce: all N (deterministic quadrature) or a random subset (dependent tests)");
    p.add_int("paths", 64).range(1, 4096).used_when("sampling", {"random"}).doc("Random directions per bounce");
    p.add_int("scatter_seed", 1).range(0, 2147483647).used_when("sampling", {"random"}).doc("Seed of the random subsets");
    p.add_float("curvature_u", 0.0).range(-360.0, 360.0).in("degrees")
        .doc("Curvature of the base geometry along u, as the total bend across the field (+ convex, - concave): bends the "
             "scattering directions and reweights paths by the triangle-fan area importance (§5); S_i are not recomputed");
    p.add_float("curvature_v", 0.0).range(-360.0, 360.0).in("degrees").doc("Curvature along v (see curvature_u)");
    p.add_enum("device", {"cpu", "gpu"}, "cpu").used_when("method", {"heidrich"})
        .doc("Where the precomputations run: cpu (all cores) or gpu (OpenGL compute shaders on a context of their own): S_i, the scattering "
             "bounces, the curvature importance, the ellipse fits and the goniometer's and BTF's light images; without OpenGL a stage runs on "
             "the CPU and says so. Both agree to float rounding (tests/microgeom/*_gpu_test.cpp)");
    p.add_enum("shadows", {"none", "exact", "ellipse"}, "exact").used_when("method", {"heidrich"})
        .doc("none; exact: the visibility of the 3 directions of the spherical triangle containing the light, interpolated; "
             "ellipse: the paper's per-texel ellipse fitted to the unshadowed directions (§4)");
    p.add_float("ellipse_bend", 90.0).range(1.0, 360.0).in("degrees").used_when("shadows", {"ellipse"})
        .doc("Curved bases with ellipse shadows (§5): ellipses are fitted once at 5 curvatures (flat, +-this bend along u, +-along v) and "
             "interpolated linearly for the current curvature, so moving the curvature sliders never refits; curvatures beyond it are clamped");
    p.add_enum("brdf", {"lambert", "blinn-phong"}, "lambert").doc("Micro-BRDF seen by the viewer for direct light (recomputes only the simulated BRDF of lod = brdf)");
    p.add_color("ks", {0.04, 0.04, 0.04}).used_when("brdf", {"blinn-phong"}).doc("Specular albedo of the normalised Blinn-Phong lobe");
    p.add_float("shininess", 32.0).range(1.0, 10000.0).log().used_when("brdf", {"blinn-phong"}).doc("Blinn-Phong exponent");
    p.add_float("tiling", 4.0).range(0.01, 1e4).log().doc("Repeats of the heightfield across the object's (u,v) (texture mode: always 1:1); recomputes only the displaced geometry of lod = geometry");
    p.add_enum("lod", {"geometry", "bump", "brdf"}, "bump").used_when("method", {"heidrich"})
        .doc("Level of detail: geometry (the base re-tessellated at one vertex per texel and displaced by the heights; parallax and "
             "silhouettes), bump (bump map with precomputed visibility), brdf (smooth surface with the heightfield's simulated BRDF "
             "from the virtual goniometer, §6)");
    p.add_enum("brdf_fit", {"table", "sh"}, "table").used_when("lod", {"brdf"})
        .doc("Simulated BRDF: a dense table of goniometer images (resolution^4), or a few hundred random images projected into "
             "spherical harmonics (the paper's suggestion), tabulated for rendering");
    p.add_int("brdf_resolution", 8).range(2, 32).used_when("lod", {"brdf"}).more_accurate(Accuracy::Higher, int64_t(16))
        .doc("Table nodes per angle (theta 0..90 degrees, phi 0..360) for the light and the view: the paper's 16^4 is 16");
    p.add_int("brdf_samples", 300).range(1, 100000).used_when("brdf_fit", {"sh"}).more_accurate(Accuracy::Higher, int64_t(4000))
        .doc("SH fit: random (light, view) goniometer images");
    p.add_int("sh_bands", 3).range(1, 8).used_when("brdf_fit", {"sh"})
        .doc("SH fit: bands per direction (bands^2 coefficients for the light times bands^2 for the view)");

    p.section("Heightfield", {"heightfield", "resolution", "height_scale", "texel_size", "periodic", "vgroove_angle", "rms_slope", "correlation", "seed",
                              "albedo", "albedo_map", "tiling"});
    p.section("Visibility and scattering", {"directions", "depth", "sampling", "paths", "scatter_seed", "shadows", "ellipse_bend", "device"});
    p.section("Curvature of the base (§5)", {"curvature_u", "curvature_v"});
    p.section("Level of detail", {"lod", "brdf_fit", "brdf_resolution", "brdf_samples", "sh_bands"});
    p.section("Shading", {"brdf", "ks", "shininess"}, false);

    effects_.push_back({"indirect", true, "Light scattered inside micro-geometry (microgeom.depth bounces)"});
    aovs_ = {{"direct", 3, "Direct light reflected towards the eye (with shadows)"},
             {"indirect", 3, "Scattered and environment light reflected towards the eye"},
             {"shadow", 1, "Fraction of the first light reaching each point (0..1)"},
             {"folded", 1, "1 where the curvature folds the direction triangulation over (visibility would change; §5)"}};
}

// Both paths interpolate the same attributes from the same window positions (the GPU draws its
// vertices on the CPU rasteriser's 1/256-pixel grid: gpu/shaders/mesh.vert), so what differs is
// float evaluation: off edges the presets agree to 5e-4 and 99.99% of the values to 1e-3
// (llvmpipe, 2 cores); interior_max 2e-3 leaves room for another GPU's arithmetic. The
// visibility bits S_i, the direction triangle a view falls in and the heightfield texel under a
// pixel are discrete choices; none flips off edges on llvmpipe, a few may where another GPU rounds
// differently (interior_outliers 1e-4).
FrameAgreement MicrogeomTechnique::agreement() const {
    return {.tight = 1e-3, .frac_tight = 0.999, .loose = 1e-2, .frac_loose = 0.9995, .interior_max = 2e-3, .interior_outliers = 1e-4,
            .why = "float evaluation; S_i bits, direction triangles and texels are discrete choices"};
}

// [SECTION] What a frame needs
std::vector<StageName> MicrogeomTechnique::frame_stages() const {
    return {stages::heightfield, stages::directions, stages::visibility, stages::importance, stages::ellipses_curved, stages::ellipses,
            stages::scatter_env, stages::scatter, stages::scatter_directions, stages::displaced, stages::brdf};
}

std::shared_ptr<const TriMesh> MicrogeomTechnique::object_mesh(const Scene&, const Evaluation& ev, int object) const {
    return ev.get(microgeom::stages::displaced, object);
}

std::optional<ivec2> MicrogeomTechnique::texture_size(const Scene& s, const Evaluation& ev) const {
    for (size_t i = 0; i < s.objects.size(); ++i)
        if (const auto h = ev.get(microgeom::stages::heightfield, int(i))) return ivec2(h->width, h->height);
    return std::nullopt;
}
}  // namespace mesolab::microgeom

namespace mesolab {
void register_microgeom(Registry& r) { r.add(std::make_unique<microgeom::MicrogeomTechnique>()); }
}  // namespace mesolab
