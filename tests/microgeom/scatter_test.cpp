// Scattering in micro-geometry: furnace tests (energy conservation), the flat-field analytic
// case, and hard cases that must stay finite.
#include "app/workbench.h"
#include "core/microgeom/stages.h"
#include "core/error.h"
#include "core/image.h"
#include "core/microgeom/microgeom.h"
#include "core/scene.h"
#include "agreement.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;
using namespace mesolab::test;

namespace {

// A procedural field with the same albedo everywhere (the procedural colour rules replaced).
Heightfield field(const char* name, int res, float albedo) {
    ProceduralParams p;
    p.name = name;
    p.resolution = res;
    Heightfield hf = make_procedural(p);
    hf.albedo.assign(hf.albedo.size(), vec3(albedo));
    return hf;
}

// Mean outgoing radiance rho/pi * E over the texels, for a white constant environment.
double furnace(const Heightfield& hf, const DirectionSet& dirs, const Visibility& vis, int depth) {
    Environment env;
    env.color = vec3(1.f);
    ScatterSettings s;
    s.env = &env;
    s.depth = depth;
    const ScatterResult r = scatter(hf, dirs, vis, s);
    double sum = 0;
    for (size_t p = 0; p < r.E_indirect.size(); ++p) sum += double(hf.albedo[p].x * kInvPi * r.E_indirect[p].x);
    return sum / double(r.E_indirect.size());
}
}  // namespace

TEST(Furnace, WhiteHeightfieldsConvergeToOne) {
    const DirectionSet dirs = make_direction_set(100);
    for (const char* name : {"bricks", "bumps", "triangles", "vgrooves"}) {
        SCOPED_TRACE(name);
        const Heightfield hf = field(name, 48, 1.f);
        const Visibility vis = compute_visibility(hf, dirs);
        const double l0 = furnace(hf, dirs, vis, 0), l8 = furnace(hf, dirs, vis, 8);
        EXPECT_LT(l0, 0.999) << "occlusion must darken depth 0";
        EXPECT_NEAR(l8, 1.0, 0.01) << "depth 0 gave " << l0;
    }
}

TEST(Furnace, GreyHeightfieldStaysBelowOneAndGrowsWithDepth) {
    const DirectionSet dirs = make_direction_set(100);
    const Heightfield hf = field("bricks", 48, 0.6f);
    const Visibility vis = compute_visibility(hf, dirs);
    double prev = 0;
    for (int k = 0; k <= 8; ++k) {
        const double l = furnace(hf, dirs, vis, k);
        EXPECT_LT(l, 1.0);
        EXPECT_GE(l, prev - 1e-9) << "depth " << k;
        prev = l;
    }
}

TEST(FlatField, NoShadowsNoIndirectAnalyticLambert) {
    // Flat plane, texture mode, one directional light and a constant environment.
    Scene s = default_scene("microgeom");
    for (const char* set : {"camera.mode=texture", "camera.orbit=0,0", "geometry.type=plane", "microgeom.heightfield=flat", "microgeom.resolution=32",
                            "microgeom.albedo=0.5,0.4,0.3", "light.direction=40,25", "light.intensity=2", "env.color=0.2,0.1,0.05", "microgeom.depth=3"})
        apply_set(s, set);
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    const Frame f = wb.render(s, req).frame;
    ASSERT_EQ(f.width, 32);
    const vec3 rho(0.5f, 0.4f, 0.3f), env(0.2f, 0.1f, 0.05f);
    const vec3 want = rho * kInvPi * (2.f * std::cos(radians(40.f)) + kPi * env);
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(f.aov("radiance").at(x, y)[c], want[c], 1e-5f) << x << "," << y;
            ASSERT_FLOAT_EQ(f.aov("shadow").at(x, y)[0], 1.f);
        }
}

// The normalised Blinn-Phong lobe of microgeom.h on a flat field, texture mode: from every view
// (camera.orbit = the view direction wo) and on both backends the radiance is
//   L = (rho/pi + ks (s + 8)/(8 pi) (n.h)^s) E cos(theta_i) + rho/pi * pi L_env,   h = normalize(wi + wo),
// with n = +z; the lobe is on the direct term only (the environment part is Lambert). Tolerance
// 1e-5 (CPU) and 1e-4 (GPU: pow and normalize in GLSL; llvmpipe measures 3e-7 like the CPU),
// relative to the value. The views go from the mirror direction (lobe ~2x the Lambert term) to
// far off it (lobe < 1% of it), so a wrong normalisation, exponent or half vector fails.
TEST(FlatField, BlinnPhongAnalyticLambertPlusLobe) {
    const glm::dvec3 rho(0.5, 0.4, 0.3), ks(0.3, 0.2, 0.1), env(0.2, 0.1, 0.05);
    const double shininess = 20.0, E = 2.0;
    const glm::dvec3 wi(direction_from_degrees(40.f, 25.f));
    double lobe_ratio_max = 0, lobe_ratio_min = 1e30;  // lobe / Lambert term over the views
    Workbench wb;
    for (const vec2 view : {vec2(0.f, 0.f), vec2(40.f, 205.f), vec2(30.f, 215.f), vec2(55.f, 100.f)}) {
        Scene s = default_scene("microgeom");
        for (const char* set : {"camera.mode=texture", "geometry.type=plane", "microgeom.heightfield=flat", "microgeom.resolution=16",
                                "microgeom.albedo=0.5,0.4,0.3", "microgeom.brdf=blinn-phong", "microgeom.ks=0.3,0.2,0.1", "microgeom.shininess=20",
                                "light.direction=40,25", "light.intensity=2", "env.color=0.2,0.1,0.05", "microgeom.depth=3"})
            apply_set(s, set);
        apply_set(s, "camera.orbit", std::to_string(view.x) + "," + std::to_string(view.y));
        const glm::dvec3 wo(direction_from_degrees(view.x, view.y)), h = glm::normalize(wi + wo);
        const glm::dvec3 lobe = ks * (shininess + 8.0) / (8.0 * kPi) * std::pow(std::max(0.0, h.z), shininess);
        const glm::dvec3 direct = (rho / double(kPi) + lobe) * E * wi.z, indirect = rho * env;
        lobe_ratio_max = std::max(lobe_ratio_max, lobe.x / (rho.x / double(kPi)));
        lobe_ratio_min = std::min(lobe_ratio_min, lobe.x / (rho.x / double(kPi)));
        for (std::string backend : {"cpu", "gpu"}) {
            SCOPED_TRACE(std::string(backend == std::string("cpu") ? "cpu" : "gpu") + " view " + std::to_string(view.x) + "," + std::to_string(view.y));
            const double tol = backend == std::string("cpu") ? 1e-5 : 1e-4;
            RenderRequest req;
            req.renderer = backend;
            const Frame f = wb.render(s, req).frame;
            ASSERT_EQ(f.width, 16);
            double worst = 0;
            for (int y = 0; y < f.height; ++y)
                for (int x = 0; x < f.width; ++x)
                    for (int c = 0; c < 3; ++c) {
                        worst = std::max(worst, std::fabs(f.aov("radiance").at(x, y)[c] - (direct[c] + indirect[c])) / (direct[c] + indirect[c]));
                        ASSERT_NEAR(f.aov("radiance").at(x, y)[c], direct[c] + indirect[c], tol * (direct[c] + indirect[c])) << x << "," << y;
                        ASSERT_NEAR(f.aov("direct").at(x, y)[c], direct[c], tol * direct[c]) << x << "," << y;
                        ASSERT_NEAR(f.aov("indirect").at(x, y)[c], indirect[c], tol * indirect[c]) << x << "," << y;
                    }
            std::printf("[ blinn-phong ] %s view (%g, %g): L = %.5f %.5f %.5f, worst relative error %.2e\n", backend == std::string("cpu") ? "cpu" : "gpu",
                        double(view.x), double(view.y), direct.x + indirect.x, direct.y + indirect.y, direct.z + indirect.z, worst);
        }
    }
    EXPECT_GT(lobe_ratio_max, 1.5) << "no view near the mirror direction: the lobe's peak is not tested";
    EXPECT_LT(lobe_ratio_min, 0.01) << "no view far from the mirror direction: the lobe's fall-off is not tested";
}

TEST(HardCases, StayFinite) {
    struct Case {
        const char* sets[4];
    };
    const Case cases[] = {{{"light.direction=89.9,10", "camera.orbit=89.9,200", nullptr, nullptr}},
                          {{"microgeom.directions=16", nullptr, nullptr, nullptr}},
                          {{"microgeom.heightfield=flat", "microgeom.depth=8", nullptr, nullptr}},
                          {{"microgeom.height_scale=10000", nullptr, nullptr, nullptr}},
                          {{"microgeom.height_scale=0", nullptr, nullptr, nullptr}},
                          {{"microgeom.sampling=random", "microgeom.paths=1", nullptr, nullptr}}};
    Workbench wb;
    for (const auto& c : cases) {
        Scene s = default_scene("microgeom");
        apply_set(s, "camera.mode=texture");
        apply_set(s, "geometry.type=plane");
        apply_set(s, "microgeom.resolution=24");
        for (const char* set : c.sets)
            if (set) apply_set(s, set);
        RenderRequest req;
        req.renderer = "cpu";
        const Frame f = wb.render(s, req).frame;
        for (const char* aov : {"radiance", "normal", "direct", "indirect", "shadow"}) {
            ASSERT_TRUE(f.has(aov)) << aov << " with " << c.sets[0];
            ASSERT_FALSE(f.aov(aov).data.empty()) << aov << " with " << c.sets[0];
        }
        for (const auto& [name, img] : f.aovs)
            for (float v : img.data) ASSERT_TRUE(std::isfinite(v)) << name << " with " << c.sets[0];
        for (float v : f.aov("shadow").data) ASSERT_TRUE(v >= 0.f && v <= 1.f);
    }
}

TEST(HardCases, SpikeOfOneTexel) {
    TempDir dir("spike");
    Image img(16, 16, 1, 0.f);
    img.at(5, 7)[0] = 40.f;
    write_exr(dir / "spike.exr", img);
    Scene s = default_scene("microgeom");
    apply_set(s, "camera.mode=texture");
    apply_set(s, "geometry.type=plane");
    apply_set(s, "microgeom.heightfield", dir / "spike.exr");
    apply_set(s, "light.direction=60,0");
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    const Frame f = wb.render(s, req).frame;
    // The spike casts a shadow towards -x: texels left of it, in its row, see less light.
    EXPECT_LT(f.aov("shadow").at(3, 7)[0], 0.5f);
    EXPECT_FLOAT_EQ(f.aov("shadow").at(5, 12)[0], 1.f);
    for (float v : f.aov("radiance").data) ASSERT_TRUE(std::isfinite(v));
}

TEST(HardCases, NanInAnImageIsAClearError) {
    TempDir dir("nanfield");
    Image img(8, 8, 1, 0.f);
    img.at(3, 2)[0] = std::nanf("");
    write_exr(dir / "nan.exr", img);
    write_file(dir / "p.json", R"({"schema":1,"camera":{"mode":"texture"},"objects":[{"geometry":{"type":"plane"},"material":{"technique":"microgeom","heightfield":"nan.exr"}}]})");
    const CliResult r = run_mesolab("capture --backend cpu -o '" + (dir / "out") + "' '" + (dir / "p.json") + "'");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("nan.exr"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("NaN"), std::string::npos) << r.err;
}

TEST(Stages, MovingTheLightNeverRecomputesVisibility) {
    Scene s = default_scene("microgeom");
    apply_set(s, "microgeom.resolution=24");
    const StageGraph& g = Registry::instance().stages();
    const uint64_t vis = g.key(s, microgeom::stages::visibility), env = g.key(s, microgeom::stages::scatter_env);
    apply_set(s, "light.direction=10,300");
    apply_set(s, "microgeom.tiling=2");
    apply_set(s, "camera.orbit=30,30");
    EXPECT_EQ(g.key(s, microgeom::stages::visibility), vis);
    EXPECT_EQ(g.key(s, microgeom::stages::scatter_env), env);
    apply_set(s, "microgeom.depth=0");
    EXPECT_EQ(g.key(s, microgeom::stages::scatter), 0u) << "depth 0: the light's scattering stage is skipped";
    EXPECT_EQ(g.key(s, microgeom::stages::visibility), vis);
}

// "Changing the light or curvature never recomputes S_i", for the curvature: through
// the stage graph, every change of microgeom.curvature_u / curvature_v (including back to 0)
// leaves microgeom.visibility Cached, and with ellipse shadows the five curved ellipse fits too
// (they are interpolated, not refitted); the importance and the interpolated ellipses do rerun,
// and the picture changes (the curvature is not ignored).
TEST(Stages, ChangingTheCurvatureNeverRecomputesVisibility) {
    Scene s = default_scene("microgeom");
    for (const char* set : {"camera.mode=texture", "geometry.type=plane", "microgeom.resolution=24", "microgeom.shadows=ellipse", "microgeom.curvature_u=17"})
        apply_set(s, set);
    const StageGraph& g = Registry::instance().stages();
    const uint64_t vis = g.key(s, microgeom::stages::visibility), fits = g.key(s, microgeom::stages::ellipses_curved);
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    std::vector<float> prev = wb.render(s, req).frame.aov("radiance").data;
    for (const char* set : {"microgeom.curvature_u=-43", "microgeom.curvature_v=29", "microgeom.curvature_u=0", "microgeom.curvature_v=-11"}) {
        SCOPED_TRACE(set);
        apply_set(s, set);
        EXPECT_EQ(g.key(s, microgeom::stages::visibility), vis);
        EXPECT_EQ(g.key(s, microgeom::stages::ellipses_curved), fits);
        const RenderResult r = wb.render(s, req);
        ASSERT_NE(r.eval.run(microgeom::stages::visibility), nullptr);
        EXPECT_EQ(r.eval.run(microgeom::stages::visibility)->status, StageStatus::Cached);
        EXPECT_EQ(r.eval.run(microgeom::stages::ellipses_curved)->status, StageStatus::Cached);
        EXPECT_EQ(r.eval.run(microgeom::stages::importance)->status, StageStatus::Ran);
        EXPECT_EQ(r.eval.run(microgeom::stages::ellipses)->status, StageStatus::Ran);
        const std::vector<float>& now = r.frame.aov("radiance").data;
        EXPECT_NE(now, prev) << "the curvature change did not reach the picture";
        prev = now;
    }
}

// CPU and GPU (llvmpipe) agree on every AOV. Texture space (one pixel per texel): to 1e-4 on
// every value. Orbit views magnify the heightfield (tiling x texels per unit of uv), so float
// rounding in the interpolated uv moves sharp micro-normals: there, the technique's own
// tolerances (MicrogeomTechnique::agreement).
TEST(CpuGpu, AgreeOnEveryAov) {
    Workbench wb;
    const FrameAgreement texture{.tight = 1e-4, .frac_tight = 1.0, .loose = 1e-4, .frac_loose = 1.0, .interior_max = 1e-4};
    for (const auto& [preset, tol] : {std::pair{"presets/microgeom/bricks-texture.json", texture},
                                      std::pair{"presets/microgeom/fig1b-scattering.json", agreement_of("microgeom")},
                                      std::pair{"presets/microgeom/fig10c-environment.json", agreement_of("microgeom")}}) {
        SCOPED_TRACE(preset);
        Scene s = load_preset(source_path(preset));
        const auto [cpu, gpu] = render_cpu_and_gpu(wb, s, 160, 120);
        expect_frames_agree(cpu, gpu, {"radiance", "normal", "direct", "indirect", "shadow"}, tol);
    }
}

// Every light is scattered, not only the first: in texture space, the indirect AOV with two
// lights equals the sum of the two lights alone (to float rounding), on the CPU and on the GPU,
// and the two backends agree.
TEST(CpuGpu, EveryLightIsScattered) {
    const json two = json::parse(R"({ "schema": 1,
      "camera": { "mode": "texture" },
      "lights": [ { "type": "directional", "direction": [60, 0], "intensity": 3 },
                  { "type": "directional", "direction": [45, 200], "intensity": 2, "color": [0.4, 0.6, 1] } ],
      "env": { "color": [0, 0, 0] },
      "effects": { "environment": false, "indirect": true },
      "objects": [ { "name": "ridges", "geometry": { "type": "plane" },
                     "material": { "technique": "microgeom", "heightfield": "triangles", "resolution": 32, "directions": 64, "depth": 2 } } ] })");
    json a = two, b = two;
    a["lights"].erase(1);
    b["lights"].erase(0);
    Workbench wb;
    for (std::string backend : {"cpu", "gpu"}) {
        RenderRequest req;
        req.renderer = backend;
        auto indirect = [&](const json& j) { return wb.render(scene_from_json(j, "test", "."), req).frame.aov("indirect").data; };
        const std::vector<float> both = indirect(two), only_a = indirect(a), only_b = indirect(b);
        ASSERT_EQ(both.size(), only_a.size());
        double max_err = 0, max_b = 0;
        for (size_t k = 0; k < both.size(); ++k) {
            max_err = std::max(max_err, double(std::abs(both[k] - only_a[k] - only_b[k])));
            max_b = std::max(max_b, double(only_b[k]));
        }
        EXPECT_GT(max_b, 1e-3) << "the second light alone must scatter visibly";
        EXPECT_LT(max_err, 1e-5) << (backend == std::string("cpu") ? "cpu" : "gpu");
    }
    const auto [cpu, gpu] = render_cpu_and_gpu(wb, scene_from_json(two, "test", "."));
    expect_frames_agree(cpu, gpu, {"radiance", "direct", "indirect", "shadow"}, {.tight = 1e-4, .frac_tight = 1.0, .loose = 1e-4, .frac_loose = 1.0, .interior_max = 1e-4});
}

// Curved base (§5).
namespace {
struct Ridge {
    Heightfield hf;
    DirectionSet dirs = make_direction_set(100);
    Visibility vis;
    Ridge() {
        ProceduralParams p;
        p.name = "triangles";
        p.resolution = 48;
        hf = make_procedural(p);
        vis = compute_visibility(hf, dirs);
    }
    // Mean indirect irradiance on the red faces (lit only by scattering, as in Fig. 11).
    double red_indirect(float degrees) const {
        const Importance imp = compute_importance(hf, dirs, vis, Bending::from_degrees(degrees, 0.f, hf.width, hf.height));
        ScatterSettings s;
        s.light_dir = glm::normalize(vec3(0.7f, 0.f, 0.7f));
        s.light_E = vec3(1.f);
        s.depth = 4;
        s.importance = imp.empty() ? nullptr : &imp;
        const ScatterResult r = scatter(hf, dirs, vis, s);
        double sum = 0;
        int n = 0;
        for (size_t i = 0; i < r.E_indirect.size(); ++i)
            if (hf.albedo[i].y < 0.2f) sum += r.E_indirect[i].x, ++n;
        return sum / n;
    }
};
}  // namespace

// bent_direction against §5's model written out (curvature.h): the hit q of direction d lies at
// horizontal offset (dx, dy) texels from p (local x = +column, local y = -row, nearest periodic
// image) and at height d.z / |d.xy| * |(dx, dy)| along the ray; bending lowers it by
// (ku dx^2 + kv dy^2) / 2, and the bent direction points from p to it. Directions without a hit,
// or below the horizon, and zero bending leave d as it is. Hits at 1/16-texel positions are stored
// exactly, so the only error is float rounding.
TEST(Curvature, BentDirectionPointsAtTheHitLoweredByTheParaboloid) {
    Heightfield hf = test::procedural_field("flat", 32, true);
    DirectionSet dirs;
    dirs.d = {glm::normalize(vec3(3.f, -4.f, 2.f))};  // |d.xy| : d.z = 5 : 2
    Visibility vis;
    vis.width = vis.height = 32;
    vis.count = 1;
    vis.hit.assign(32 * 32, Visibility::kNoHit);
    auto set = [&](int x, int y, uint32_t v) { vis.hit[size_t(y) * 32 + size_t(x)] = v; };
    // From (10, 10), 1.5 steps of (3, -4) in local units: column 14.5, row 16 (rows grow down).
    set(10, 10, Visibility::encode(14.5f, 16.f));
    // From (30, 2) the same offset crosses the right border: stored wrapped at column 34.5 - 32.
    set(30, 2, Visibility::encode(2.5f, 8.f));
    set(5, 5, Visibility::kBelow);
    const Bending b{0.02f, -0.01f};
    const double dx = 4.5, dy = -6.0, z = 2.0 / 5.0 * std::sqrt(dx * dx + dy * dy);  // z = 3 texels above p
    const glm::dvec3 q(dx, dy, z - 0.5 * (double(b.ku) * dx * dx + double(b.kv) * dy * dy));
    const vec3 want(glm::normalize(q));
    for (const ivec2 p : {ivec2(10, 10), ivec2(30, 2)}) {
        const vec3 got = bent_direction(hf, dirs, vis, b, p.x, p.y, 0);
        EXPECT_NEAR(glm::distance(got, want), 0.f, 1e-6f) << p.x << ", " << p.y;
        EXPECT_EQ(bent_direction(hf, dirs, vis, Bending{}, p.x, p.y, 0), dirs.d[0]) << "no bending";
    }
    EXPECT_GT(glm::distance(want, dirs.d[0]), 1e-3f) << "the bend must move the direction, else the test shows nothing";
    EXPECT_EQ(bent_direction(hf, dirs, vis, b, 3, 3, 0), dirs.d[0]) << "no hit: the environment does not bend";
    EXPECT_EQ(bent_direction(hf, dirs, vis, b, 5, 5, 0), dirs.d[0]) << "below the horizon";
}

TEST(Curvature, ZeroReproducesTheFlatResultExactly) {
    Ridge r;
    const Importance imp = compute_importance(r.hf, r.dirs, r.vis, Bending{});
    EXPECT_TRUE(imp.empty());
    ScatterSettings a;
    a.light_E = vec3(1.f);
    a.light_dir = glm::normalize(vec3(0.5f, 0.2f, 0.8f));
    ScatterSettings b = a;
    b.importance = &imp;
    const ScatterResult ra = scatter(r.hf, r.dirs, r.vis, a), rb = scatter(r.hf, r.dirs, r.vis, b);
    EXPECT_EQ(ra.E_indirect, rb.E_indirect);
    // Through the stage graph: curvature 0 skips the importance stage. Bending the base and then
    // setting the curvature back to 0 renders the flat frame's bytes again (nothing of the bent
    // frame is left in the renderer), while the bent frame differs.
    Scene s = default_scene("microgeom");
    apply_set(s, "camera.mode=texture");
    apply_set(s, "geometry.type=plane");
    apply_set(s, "microgeom.resolution=24");
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    const RenderResult flat = wb.render(s, req);
    ASSERT_NE(flat.eval.run(microgeom::stages::importance), nullptr);
    EXPECT_EQ(flat.eval.run(microgeom::stages::importance)->status, StageStatus::Skipped);
    apply_set(s, "microgeom.curvature_u=40");
    const RenderResult bent = wb.render(s, req);
    EXPECT_EQ(bent.eval.run(microgeom::stages::importance)->status, StageStatus::Ran);
    EXPECT_NE(bent.frame.aov("radiance").data, flat.frame.aov("radiance").data) << "the bend must change the frame";
    apply_set(s, "microgeom.curvature_u=0");
    const RenderResult back = wb.render(s, req);
    EXPECT_EQ(back.eval.run(microgeom::stages::importance)->status, StageStatus::Skipped);
    EXPECT_EQ(back.frame.aov("radiance").data, flat.frame.aov("radiance").data);
}

TEST(Curvature, ImportanceIsPositiveAndNormalised) {
    Ridge r;
    for (float deg : {-60.f, 25.f, 60.f}) {
        const Importance imp = compute_importance(r.hf, r.dirs, r.vis, Bending::from_degrees(deg, 0.3f * deg, r.hf.width, r.hf.height));
        ASSERT_EQ(imp.folded_count, 0u) << deg;
        size_t moved = 0;
        for (size_t p = 0; p < size_t(r.hf.width) * size_t(r.hf.height); ++p) {
            // Fan-area ratios are positive; the gather weights are >= 0 and sum to 1 per texel.
            double total = 0;
            for (int j = 0; j < r.dirs.size(); ++j) {
                ASSERT_GT(imp.importance(p, j), 0.f);
                ASSERT_GE(imp.weight(p, j), 0.f);
                total += double(imp.weight(p, j));
                moved += std::abs(imp.importance(p, j) - 1.f) > 1e-3f;
            }
            ASSERT_NEAR(total, 1.0, 1e-5) << deg << " texel " << p;
        }
        EXPECT_GT(moved, 0u) << "bending changed no importance at " << deg;
    }
}

TEST(Curvature, FurnaceStillConservesEnergyOnACurvedBase) {
    Ridge r;
    r.hf.albedo.assign(r.hf.albedo.size(), vec3(1.f));
    for (float deg : {-60.f, 60.f}) {
        const Importance imp = compute_importance(r.hf, r.dirs, r.vis, Bending::from_degrees(deg, 0.f, r.hf.width, r.hf.height));
        Environment env;
        env.color = vec3(1.f);
        ScatterSettings s;
        s.env = &env;
        s.depth = 8;
        s.importance = &imp;
        const ScatterResult res = scatter(r.hf, r.dirs, r.vis, s);
        double sum = 0;
        for (const vec3& E : res.E_indirect) sum += double(E.x) * kInvPi;
        EXPECT_NEAR(sum / double(res.E_indirect.size()), 1.0, 0.01) << deg;
    }
}

TEST(Curvature, ConvexBasesScatterLessConcaveMore) {
    // Fig. 11: widening valleys (convex) let more of the scattered light escape, so the red faces,
    // lit only by scattering, get darker; narrowing ones (concave) make them brighter. Measured
    // (48^2 ridges, N = 100, K = 4): -120: +29%, -60: +14%, +60: -13%, +120: -26% against flat.
    Ridge r;
    const double flat = r.red_indirect(0.f);
    double prev = 1e30;
    for (float deg : {-120.f, -60.f, -30.f, 0.f, 30.f, 60.f, 120.f}) {
        const double e = r.red_indirect(deg);
        EXPECT_LT(e, prev) << deg;
        prev = e;
    }
    EXPECT_GT(r.red_indirect(-60.f) / flat, 1.08);
    EXPECT_LT(r.red_indirect(60.f) / flat, 0.92);
}

TEST(Curvature, FoldingIsFlaggedNotHidden) {
    Ridge r;
    const Importance imp = compute_importance(r.hf, r.dirs, r.vis, Bending::from_degrees(360.f, 0.f, r.hf.width, r.hf.height));
    EXPECT_GT(imp.folded_count, 0u);
    for (float w : imp.w) ASSERT_TRUE(std::isfinite(w) && w >= 0.f);
}


// Fold-over through the stage graph (texture mode, one pixel per texel): a bend that folds the
// triangulation at some texels reports the microgeom.importance warning, whose texel count is
// exactly the number of 1s in the `folded` AOV (values 0 or 1 only), on both backends; a gentle
// bend and curvature 0 give no warning and an all-zero AOV.
TEST(Curvature, FoldOverIsWarnedAndMaskedThroughTheStages) {
    auto render = [](Workbench& wb, const std::string& backend, const char* curvature) {
        Scene s = default_scene("microgeom");
        for (const char* set : {"camera.mode=texture", "geometry.type=plane", "microgeom.heightfield=bricks", "microgeom.resolution=32"}) apply_set(s, set);
        apply_set(s, curvature);
        RenderRequest req;
        req.renderer = backend;
        return wb.render(s, req);
    };
    auto fold_warnings = [](const Evaluation& ev) {
        std::vector<std::string> found;
        for (const StageRun& run : ev.runs)
            for (const std::string& w : run.warnings)
                if (w.find("folds the direction triangulation over") != std::string::npos) found.push_back(run.name + ": " + w);
        return found;
    };
    Workbench wb;
    for (std::string backend : {"cpu", "gpu"}) {
        SCOPED_TRACE(backend == std::string("cpu") ? "cpu" : "gpu");
        const RenderResult bent = render(wb, backend, "microgeom.curvature_u=200");
        const std::vector<std::string> warnings = fold_warnings(bent.eval);
        ASSERT_EQ(warnings.size(), 1u);
        EXPECT_EQ(warnings[0].rfind("microgeom.importance: ", 0), 0u) << warnings[0];
        EXPECT_NE(warnings[0].find("'folded' AOV"), std::string::npos) << warnings[0];
        const Image& folded = bent.frame.aov("folded");
        ASSERT_EQ(folded.width, 32);
        size_t ones = 0;
        for (float v : folded.data) {
            ASSERT_TRUE(v == 0.f || v == 1.f) << v;
            ones += v == 1.f;
        }
        size_t count = 0, texels = 0;
        const size_t at = warnings[0].find(" at ");
        ASSERT_NE(at, std::string::npos);
        ASSERT_EQ(std::sscanf(warnings[0].c_str() + at, " at %zu of %zu texels", &count, &texels), 2) << warnings[0];
        std::printf("[ fold-over ] %s: %zu of %zu texels folded; warning: %s\n", backend == std::string("cpu") ? "cpu" : "gpu", ones, folded.data.size(),
                    warnings[0].c_str());
        EXPECT_EQ(texels, 32u * 32u);
        EXPECT_EQ(count, ones) << "the warning and the AOV disagree";
        EXPECT_GT(ones, 0u);
        EXPECT_LT(ones, folded.data.size());

        struct Calm {
            const char* set;
            bool importance_runs;
        };
        for (const Calm& calm : {Calm{"microgeom.curvature_u=30", true}, Calm{"microgeom.curvature_u=0", false}}) {
            SCOPED_TRACE(calm.set);
            const RenderResult r = render(wb, backend, calm.set);
            const std::vector<std::string> none = fold_warnings(r.eval);
            EXPECT_TRUE(none.empty()) << none.front();
            const StageStatus st = r.eval.run(microgeom::stages::importance)->status;
            if (calm.importance_runs) {
                EXPECT_TRUE(st == StageStatus::Ran || st == StageStatus::Cached) << to_string(st);
            } else {
                EXPECT_EQ(st, StageStatus::Skipped) << to_string(st);
            }
            for (float v : r.frame.aov("folded").data) ASSERT_EQ(v, 0.f);
        }
    }
}
