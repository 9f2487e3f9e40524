// microgeom's truth (core/microgeom/truth.cpp): the heightfield as explicit triangles through its
// texel centres, path traced. A flat field is Lambert's closed form; an albedo-1 field of any
// shape under a uniform sky is 1 (every bounce kept); the surface passes through the texel
// centres; the real-time scattering converges towards the truth on a V-groove as its depth grows
// (the paper's claim), to a floor the page states; the truth reads no accuracy knob.
#include "core/truth/cache.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/heightfield/heightfield.h"
#include "core/microgeom/lod.h"
#include "core/scene.h"
#include "core/truth/truth.h"
#include "support/cli.h"
#include "support/truth.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <string>

using namespace mesolab;

namespace {
// A plane of microgeom `material` (JSON members added to the technique's), seen from `orbit`.
Scene scene(const std::string& material, const std::string& lights, float env, const std::string& orbit = "[1, -90]", const std::string& type = "plane") {
    const std::string text = R"({"schema": 1, "name": "microgeom-truth", "camera": {"mode": "orbit", "distance": 3.0, "orbit": )" + orbit +
                             R"(, "fov": 30}, "lights": )" + lights + R"(, "env": {"color": [1, 1, 1], "intensity": )" + std::to_string(env) +
                             R"(}, "effects": {"environment": true}, "objects": [{"name": "field", "geometry": {"type": ")" + type +
                             R"(", "resolution": 4}, "material": {"technique": "microgeom", )" + material + "}}]}";
    return scene_from_json(nlohmann::json::parse(text), "microgeom-truth", test::source_path("presets"));
}

RenderResult render(const Scene& s, const std::string& backend, int size, int spp, std::vector<std::string> aovs = {}) {
    return test::render_uncached(s, test::truth_request(backend, size, spp, std::move(aovs)));
}

using test::shows_object;
}  // namespace

// The surface passes through every texel centre at its height (mean removed, in texel lengths),
// and halfway between two centres along a row at their mean.
TEST(MicrogeomTruth, TheSurfacePassesThroughTheTexelCentres) {
    ProceduralParams p;
    p.name = "gaussian";
    p.resolution = 16;
    const Heightfield hf = make_procedural(p);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            EXPECT_FLOAT_EQ(microgeom::height_through_centres(hf, float(x), float(y)), hf.h[hf.index(x, y)]);
            EXPECT_NEAR(microgeom::height_through_centres(hf, float(x) + 0.5f, float(y)), 0.5f * (hf.h[hf.index(x, y)] + hf.h[hf.index((x + 1) % 16, y)]), 1e-5f);
        }
    const int n = microgeom::truth_surface_resolution(Primitive::Plane, 4, 16, 16, 2.f, nullptr);
    EXPECT_EQ(n, 64);
    const TriMesh m = microgeom::truth_surface(Primitive::Plane, n, 0.35f, hf, 2.f, 0.f, 0.f);
    double mean = 0.0;
    for (float h : hf.h) mean += h;
    mean /= double(hf.h.size());
    // Vertex (i, j) at u = i / 64: texel centre c = u * 32 - 0.5 is an integer for odd i.
    for (int j = 1; j < n; j += 2)
        for (int i = 1; i < n; i += 2) {
            const vec3 pos = m.position[size_t(j) * size_t(n + 1) + size_t(i)];
            const int c = (i - 1) / 2, r = 31 - (j - 1) / 2;
            const float texel = 2.f / 32.f;  // the plane's 2 units over 32 texels
            EXPECT_NEAR(pos.z, (hf.h[hf.index(c % 16, r % 16)] - float(mean)) / hf.texel_size * texel, 1e-5f) << i << "," << j;
        }
}

// A flat field (height_scale 0) under a directional light 60 degrees from its normal, no sky:
// L = albedo / π E cos θ at every pixel, exactly (nothing to bounce off).
TEST(MicrogeomTruth, AFlatFieldIsLambertsClosedForm) {
    const Scene s = scene(R"("heightfield": "gaussian", "resolution": 16, "height_scale": 0, "albedo": [0.5, 0.25, 0.125])",
                          R"([{"type": "directional", "direction": [60, 30], "intensity": 2, "color": [1, 1, 1]}])", 0.f, "[20, -60]");
    const Frame f = render(s, "truth", 32, 2).frame;
    EXPECT_GT(test::expect_object_radiance(f, vec3(0.5f, 0.25f, 0.125f) / kPi, 1e-6f), 500);  // E cos θ = 2 x 0.5
}

// Furnace: albedo 1 V-grooves and a rough Gaussian field under a uniform sky of radiance 1 give
// 1 in expectation, however often light bounces between the facets. The mean over the object's
// pixels within 4.4 standard errors (two tests, two-sided: 1e-5 each).
TEST(MicrogeomTruth, AWhiteFieldOfAnyShapeUnderAUniformSkyIsOne) {
    for (const char* field : {R"("heightfield": "vgrooves", "resolution": 32, "vgroove_angle": 60)",
                              R"("heightfield": "gaussian", "resolution": 32, "rms_slope": 1.5, "correlation": 2)"}) {
        const Scene s = scene(std::string(field) + R"(, "albedo": [1, 1, 1], "tiling": 2)", "[]", 1.f, "[40, -60]");
        const test::ObjectMean m = test::object_mean(render(s, "truth", 32, 16, {"truth_stderr"}).frame);
        ASSERT_GT(m.pixels, 300) << field;
        const double mean = m.mean, se_mean = m.stderr_mean;
        std::printf("%s: mean %.5f, standard error %.5f\n", field, mean, se_mean);
        EXPECT_GT(se_mean, 0.0) << field;
        EXPECT_LT(std::abs(mean - 1.0), 4.4 * se_mean) << field;
    }
}

// Heidrich et al.: scattering K bounces inside the heightfield approaches the light transport as K
// grows. A V-groove (albedo 0.8) seen from above under a uniform sky: the real-time error against
// the truth falls with the depth, to a floor of a few per cent (the bump level's bilinear normals
// and 100 directions; the page gives it), never back up.
TEST(MicrogeomTruth, ScatteringConvergesTowardsTheTruthOnAVGroove) {
    Scene s = scene(R"("heightfield": "vgrooves", "resolution": 32, "albedo": [0.8, 0.8, 0.8], "tiling": 1)", "[]", 1.f);
    Workbench wb;  // one truth for every depth
    wb.set_truth_cache("");
    const RenderRequest req = test::truth_request("cpu", 48, 64, {"truth_error"});
    std::vector<double> err;
    for (int depth : {0, 1, 2, 4}) {
        apply_set(s, "microgeom.depth", std::to_string(depth));
        const RenderResult r = wb.render(s, req);
        ASSERT_TRUE(r.truth);
        std::printf("depth %d: rmse_rel %.4f (truth noise %.4f)\n", depth, r.truth->rmse_rel, r.truth->noise_rel);
        err.push_back(r.truth->rmse_rel);
    }
    EXPECT_GT(err[0], 0.12);  // single scattering misses the light the walls exchange
    EXPECT_LT(err[1], 0.6 * err[0]);
    EXPECT_LE(err[2], err[1]);
    EXPECT_LE(err[3], err[2] + 1e-3);
    EXPECT_LT(err[3], 0.05);
}

// One truth serves a sweep: the truth's key ignores microgeom's accuracy knobs and follows its
// physical description; a mesh base, which the truth cannot displace, is refused by name.
TEST(MicrogeomTruth, ReadsNoAccuracyKnobAndRefusesAMeshBase) {
    const Scene s = scene(R"("heightfield": "bumps", "resolution": 16)", "[]", 1.f);
    test::expect_truth_key(s, {"microgeom.directions=200", "microgeom.depth=5", "microgeom.shadows=ellipse", "microgeom.lod=brdf", "microgeom.device=gpu"},
                           {"microgeom.ks=[0.5,0.5,0.5]", "microgeom.tiling=2", "microgeom.height_scale=2", "microgeom.curvature_u=30", "camera.fov=50"});
    Scene mesh = s;
    apply_set(mesh, "geometry.type", "mesh");
    apply_set(mesh, "geometry.path", test::source_path("presets/translucency/meshes/stanford-bunny.obj"));
    try {
        render(mesh, "truth", 8, 1);
        ADD_FAILURE() << "a mesh base has no truth";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("procedural base"), std::string::npos) << e.what();
    }
}

// `sweep --metric truth` over two knobs: one truth serves the whole grid (the knobs are accuracy
// knobs), every cell has its error against it, and the plot draws the truth's noise floor.
TEST(MicrogeomTruth, SweepOverTwoKnobsAgainstOneTruth) {
    test::TempDir dir("microgeom-truth-sweep");
    const test::CliResult r = test::run_mesolab(
        "sweep presets/microgeom/fig1b-scattering.json --knob microgeom.depth=0,2 --by microgeom.directions=32,64 --metric truth "
        "--spp 4 --size 24x24 --repeat 1 -o '" + dir.path.string() + "'",
        "MESOLAB_CACHE_DIR='" + (dir / "cache") + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string stem = dir / "microgeom-fig1b-scattering.microgeom.depth.microgeom.directions.truth";
    const std::string csv = test::slurp(stem + ".csv");
    EXPECT_EQ(csv.rfind("value,by,time_ms,rmse_rel,below_noise\n", 0), 0u) << csv;
    for (const char* row : {"\n0,32,", "\n2,32,", "\n0,64,", "\n2,64,"}) EXPECT_NE(csv.find(row), std::string::npos) << row << "\n" << csv;
    EXPECT_NE(test::slurp(stem + ".svg").find("noise floor"), std::string::npos);
    size_t truths = 0;
    for (size_t at = r.err.find("truth: 4 spp ("); at != std::string::npos; at = r.err.find("truth: 4 spp (", at + 1)) ++truths;
    EXPECT_EQ(truths, 1u) << r.err;
    // --by without the truth, and a zero-sample truth, are refused by name.
    EXPECT_EQ(test::run_mesolab("sweep presets/microgeom/fig1b-scattering.json --knob microgeom.depth=0,2 --by microgeom.directions=32,64 -o /tmp/mesolab-never").status, 2);
    const test::CliResult zero = test::run_mesolab("sweep presets/microgeom/fig1b-scattering.json --knob microgeom.depth=0,2 --metric truth --spp 0 -o /tmp/mesolab-never");
    EXPECT_EQ(zero.status, 2);
    EXPECT_NE(zero.err.find("--spp 0"), std::string::npos) << zero.err;
}

// Texture mode: a texel is the mean over its patch of the micro-surface, seen from the camera's
// direction. A flat field is Lambert's closed form in every texel; V-grooves (4 across the field,
// period 8 texels) under a uniform sky are periodic in the truth too: the border columns, whose
// light crosses to the neighbouring tile, match the same columns one period in (within 4.4
// standard errors of the difference, Šidák over the 8 phases: 1e-5 each).
TEST(MicrogeomTruth, TextureModeTexelsSeeTheirNeighboursAcrossTheBorder) {
    Scene flat = scene(R"("heightfield": "gaussian", "resolution": 16, "height_scale": 0, "albedo": [0.5, 0.5, 0.5])",
                       R"([{"type": "directional", "direction": [60, 30], "intensity": 2, "color": [1, 1, 1]}])", 0.f);
    apply_set(flat, "camera.mode", "texture");
    const RenderResult f = render(flat, "truth", 64, 2);
    ASSERT_EQ(f.frame.width, 16);  // the field's own size, as the real-time texture mode
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) EXPECT_NEAR(f.frame.aov("radiance").at(x, y)[0], 0.5f / kPi, 1e-6f) << x << "," << y;

    Scene grooves = scene(R"("heightfield": "vgrooves", "resolution": 32, "albedo": [0.8, 0.8, 0.8])", "[]", 1.f);
    apply_set(grooves, "camera.mode", "texture");
    const Frame g = render(grooves, "truth", 32, 256, {"truth_stderr"}).frame;
    ASSERT_EQ(g.width, 32);
    for (int phase = 0; phase < 8; ++phase) {
        double border = 0, inner = 0, var = 0;
        for (int y = 0; y < 32; ++y) {
            border += g.aov("radiance").at(phase, y)[1], inner += g.aov("radiance").at(phase + 8, y)[1];
            var += std::pow(g.aov("truth_stderr").at(phase, y)[1], 2.0) + std::pow(g.aov("truth_stderr").at(phase + 8, y)[1], 2.0);
        }
        const double diff = (border - inner) / 32.0, se = std::sqrt(var) / 32.0;
        std::printf("column %d: %.4f, column %d: %.4f (difference %.4f, standard error %.4f)\n", phase, border / 32.0, phase + 8, inner / 32.0, diff, se);
        EXPECT_LT(std::abs(diff), 4.4 * se) << phase;
        EXPECT_LT(inner / 32.0, 0.79);  // the walls see each other: less than the open plane's albedo 0.8
    }
    // Seen from above, texel by texel, the scattering converges onto the truth: at depth 4 the
    // real-time texture is within the truth's noise (measured: 1.2% against a noise of 1.0%).
    apply_set(grooves, "microgeom.depth", "4");
    const RenderResult rt = render(grooves, "cpu", 32, 256, {"truth_error"});
    ASSERT_TRUE(rt.truth);
    std::printf("texture mode, depth 4: rmse_rel %.4f, truth noise %.4f\n", rt.truth->rmse_rel, rt.truth->noise_rel);
    EXPECT_TRUE(rt.truth->below_noise);
}
