// microgeom's method pom (core/microgeom/pom.h): parallax occlusion mapping with self-shadowing.
// Seen from straight above it is the paper's bump level (parallax vanishes); its shadows are the
// exact visibility of the surface it marches on the V-groove, and its hits lie on that surface;
// the CPU and GPU frames agree on a plane and on a sphere, near and at grazing views; the paper's
// stages never run for it, and its keys are errors under the paper's method.
#include "core/error.h"
#include "core/heightfield/heightfield.h"
#include "core/microgeom/pom.h"
#include "core/microgeom/stages.h"
#include "core/scene.h"
#include "core/technique.h"
#include "microgeom/agreement.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <random>
#include <string>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {
// A plane (or `type`) of microgeom `material` (JSON members added to the technique's), camera `camera`.
Scene scene(const std::string& material, const std::string& camera, const std::string& type = "plane", bool env = false) {
    const std::string text = R"({"schema": 1, "name": "microgeom-pom", "camera": )" + camera +
                             R"(, "lights": [{"type": "directional", "direction": [50, 30], "intensity": 3}], "env": {"color": [0.3, 0.35, 0.4]},
                              "effects": {"environment": )" + std::string(env ? "true" : "false") +
                             R"(, "indirect": false}, "objects": [{"name": "field", "geometry": {"type": ")" + type +
                             R"(", "resolution": )" + std::string(type == "plane" ? "4" : "64") + R"(}, "material": {"technique": "microgeom", )" + material + "}}]}";
    return scene_from_json(nlohmann::json::parse(text), "microgeom-pom", test::source_path("presets"));
}

// The exact visibility of the bilinear surface along a row (l.y = 0: the ray stays on row `row`,
// where the surface is the piecewise-linear interpolation of the row's texel heights): the ray's
// height minus the surface's is linear between texel centres, so its least value beyond the start
// is at a centre or where the ray has risen to z_max. Returns that clearance (negative: blocked).
double row_clearance(const PomField& f, int row, double c, double z, vec3 l) {
    const double dc = double(l.x) / double(l.z);  // texels across per texel up
    const double reach = (double(f.z_max) - z) * std::fabs(dc);
    const auto texel = [&](int x) { return double(f.z[size_t(row) * size_t(f.width) + size_t(((x % f.width) + f.width) % f.width)]); };
    const auto surface = [&](double x) {
        const double x0 = std::floor(x);
        return texel(int(x0)) + (x - x0) * (texel(int(x0) + 1) - texel(int(x0)));
    };
    const auto clearance_at = [&](double x) { return z + std::fabs(x - c) / std::fabs(dc) - surface(x); };
    const double dir = dc > 0 ? 1.0 : -1.0, end = c + dir * reach;
    double least = clearance_at(end);
    for (double x = dir > 0 ? std::floor(c) + 1.0 : std::ceil(c) - 1.0; (end - x) * dir > 0; x += dir) least = std::min(least, clearance_at(x));
    return least;
}
}  // namespace

// Straight above, the view ray meets the field where the base point is: pom is then the bump
// level's shading (the same bilinear normal and albedo, no shadows, no scattering, no environment).
TEST(MicrogeomPom, StraightAboveItIsTheBumpLevel) {
    for (const char* field : {"bricks", "gaussian", "vgrooves"}) {
        SCOPED_TRACE(field);
        const std::string common = std::string(R"("heightfield": ")") + field + R"(", "resolution": 64, "height_scale": 2)";
        const std::string camera = R"({"mode": "texture", "orbit": [0, 0]})";
        const Scene bump = scene(common + R"(, "depth": 0, "shadows": "none")", camera);
        const Scene pom = scene(common + R"(, "method": "pom", "pom_shadow_steps": 0, "pom_steps": 8)", camera);
        Workbench wb;
        RenderRequest req;
        req.renderer = "cpu";
        const Frame a = wb.render(bump, req).frame, b = wb.render(pom, req).frame;
        ASSERT_EQ(a.width, 64);
        ASSERT_EQ(b.width, 64);
        double most = 0, sum = 0;
        for (size_t i = 0; i < a.aov("radiance").data.size(); ++i) {
            most = std::max(most, double(std::fabs(a.aov("radiance").data[i] - b.aov("radiance").data[i])));
            sum += a.aov("radiance").data[i];
        }
        EXPECT_GT(sum, 0.0) << "content in the frames";
        EXPECT_LT(most, 1e-5);
    }
}

// Seen at an angle it is not: parallax moves what a pixel shows (the test above can fail).
TEST(MicrogeomPom, AtAnAngleParallaxMovesWhatAPixelShows) {
    const std::string common = R"("heightfield": "bricks", "resolution": 64, "height_scale": 2)";
    const std::string camera = R"({"mode": "texture", "orbit": [60, 0]})";
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    const Frame a = wb.render(scene(common + R"(, "depth": 0, "shadows": "none")", camera), req).frame;
    const Frame b = wb.render(scene(common + R"(, "method": "pom", "pom_shadow_steps": 0)", camera), req).frame;
    size_t differ = 0;
    for (size_t i = 0; i < a.aov("radiance").data.size(); i += 3) differ += std::fabs(a.aov("radiance").data[i] - b.aov("radiance").data[i]) > 1e-3f;
    EXPECT_GT(differ, a.aov("radiance").data.size() / 3 / 20) << "at least 5% of the pixels show another point of the field";
}

// The hit lies on the surface it marches (the bilinear heights) and is the ray's first crossing:
// every height the ray passes on its way down from z_max is above the field.
TEST(MicrogeomPom, TheHitIsTheRaysFirstCrossingOfTheSurface) {
    const PomField f = PomField::from(test::procedural_field("gaussian", 64));
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int checked = 0;
    for (int i = 0; i < 400; ++i) {
        const float c0 = 64.f * u(rng), r0 = 64.f * u(rng);
        const float theta = 1.2f * u(rng), phi = 6.2831853f * u(rng);
        const vec3 v(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        const PomHit h = pom_march(f, c0, r0, v, 512, 16);
        EXPECT_NEAR(h.z, f.at(h.c, h.r), 1e-3f * (f.z_max - f.z_min)) << "on the surface";
        // On the ray: (c, r) = base + z (vx, -vy) / vz.
        EXPECT_NEAR(h.c, c0 + h.z * v.x / v.z, 1e-3f);
        EXPECT_NEAR(h.r, r0 - h.z * v.y / v.z, 1e-3f);
        // Above the field at 4096 heights between z_max and the hit (but the last step's width).
        const float step = (f.z_max - h.z) / 4096.f;
        for (int k = 0; k < 4096 - 8; ++k) {
            const float z = f.z_max - float(k) * step;
            ASSERT_GE(z - f.at(c0 + z * v.x / v.z, r0 - z * v.y / v.z), -1e-3f * (f.z_max - f.z_min)) << "crossed earlier, at z " << z;
        }
        ++checked;
    }
    EXPECT_EQ(checked, 400);
}

// Shadows on the V-groove: along a row the surface is the piecewise-linear profile of the
// grooves, whose exact visibility is known segment by segment; pom's hard shadows with 512 steps
// agree wherever the ray clears the profile (or dips under it) by more than the march resolves.
TEST(MicrogeomPom, ShadowsAreTheExactVisibilityOnTheVGroove) {
    ProceduralParams p;
    p.name = "vgrooves";
    p.resolution = 64;
    p.vgroove_angle = 90.f;
    const PomField f = PomField::from(make_procedural(p));
    ASSERT_GT(f.z_max - f.z_min, 4.f);
    int agree = 0, decided = 0, lit = 0, shadowed = 0;
    for (float elevation_deg : {10.f, 25.f, 40.f, 55.f, 70.f})
        for (float side : {1.f, -1.f}) {
            const float e = elevation_deg * 3.14159265f / 180.f;
            const vec3 l(side * std::cos(e), 0.f, std::sin(e));
            for (int q = 0; q < 256; ++q) {
                const float c = 0.25f * float(q) + 0.125f;
                const int row = 5;
                const float z = f.at(c, float(row));
                const double clearance = row_clearance(f, row, double(c), double(z), l);
                if (std::fabs(clearance) < 0.02 * double(f.z_max - f.z_min)) continue;  // grazing: within the march's resolution and bias
                ++decided;
                const float V = pom_visibility(f, c, float(row), z, l, 512);
                const bool exact = clearance > 0;
                agree += (V > 0.5f) == exact;
                (exact ? lit : shadowed)++;
            }
        }
    EXPECT_GT(lit, 100);
    EXPECT_GT(shadowed, 100);
    EXPECT_EQ(agree, decided);
}

// With one step and no refinement, the march still ends on the surface's bracket (the secant
// step), and no step count or refinement leaves the field's height range.
TEST(MicrogeomPom, CoarseMarchesStayWithinTheField) {
    const PomField f = PomField::from(test::procedural_field("bricks", 32));
    for (int steps : {1, 2, 7, 64})
        for (int refine : {0, 1, 8})
            for (float theta : {0.f, 0.7f, 1.4f, 1.5707f}) {
                const vec3 v(std::sin(theta), 0.f, std::cos(theta));
                const PomHit h = pom_march(f, 3.3f, 7.1f, v, steps, refine);
                EXPECT_TRUE(std::isfinite(h.c) && std::isfinite(h.r) && std::isfinite(h.z));
                EXPECT_GE(h.z, f.z_min - 1e-4f);
                EXPECT_LE(h.z, f.z_max + 1e-4f);
            }
    // A flat field: the base point itself.
    const PomField flat = PomField::from(test::procedural_field("flat", 16));
    const PomHit h = pom_march(flat, 2.5f, 3.5f, glm::normalize(vec3(1.f, 1.f, 0.2f)), 8, 4);
    EXPECT_FLOAT_EQ(h.c, 2.5f);
    EXPECT_FLOAT_EQ(h.r, 3.5f);
}

// The CPU reference and the GPU pass agree, with content in both frames: a plane at a grazing
// view, a sphere (curved base, every view angle), the environment on.
TEST(MicrogeomPom, CpuAndGpuFramesAgree) {
    const std::vector<std::pair<std::string, Scene>> cases = {
        {"plane at 75 degrees", scene(R"("method": "pom", "heightfield": "bricks", "resolution": 64, "height_scale": 2, "tiling": 2)",
                                      R"({"mode": "orbit", "distance": 2.6, "orbit": [75, -90], "fov": 40})", "plane", true)},
        {"sphere", scene(R"("method": "pom", "heightfield": "gaussian", "resolution": 64, "height_scale": 3, "tiling": 4, "pom_steps": 16, "pom_refine": 2)",
                         R"({"mode": "orbit", "distance": 3.2, "orbit": [60, -90], "fov": 40})", "sphere", true)},
        {"blinn-phong, fine steps", scene(R"("method": "pom", "heightfield": "bumps", "resolution": 64, "brdf": "blinn-phong", "pom_steps": 128, "pom_shadow_steps": 128)",
                                          R"({"mode": "orbit", "distance": 2.6, "orbit": [55, -90], "fov": 40})")},
    };
    Workbench wb;
    for (const auto& [name, s] : cases) {
        SCOPED_TRACE(name);
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 160, 160, {"radiance", "normal", "shadow"});
        test::expect_frames_agree(s, cpu, gpu, {"radiance", "normal", "shadow"});
    }
}

// Only the stages a method reads run: pom's field for pom objects, the paper's visibility and
// scattering for the paper's; in one scene with both, each for its own object.
TEST(MicrogeomPom, EachMethodRunsOnlyItsStages) {
    Scene s = scene(R"("heightfield": "bricks", "resolution": 32, "directions": 32, "depth": 1)", R"({"mode": "orbit", "distance": 3, "orbit": [40, -90], "fov": 40})");
    SceneObject second = s.objects[0];
    second.name = "pom";
    second.material.set("method", std::string("pom"));
    second.geometry.set("position", std::array<double, 3>{1.0, 0.0, 0.0});
    s.objects.push_back(second);
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 32;
    const RenderResult r = wb.render(s, req);
    const Evaluation& ev = r.eval;
    EXPECT_TRUE(ev.get(stages::visibility, 0));
    EXPECT_FALSE(ev.get(stages::visibility, 1)) << "the paper's visibility for the pom object";
    EXPECT_FALSE(ev.get(stages::pom_field, 0)) << "pom's field for the paper's object";
    EXPECT_TRUE(ev.get(stages::pom_field, 1));
    EXPECT_TRUE(ev.get(stages::heightfield, 0) && ev.get(stages::heightfield, 1)) << "both read the heightfield";
}

// The method's keys are used only under it and the paper's under the paper's: a preset that sets
// one under the other method is refused, naming the key; the method's values are listed.
TEST(MicrogeomPom, KeysOfAnotherMethodAreErrors) {
    const std::string camera = R"({"mode": "orbit", "distance": 3, "orbit": [40, -90], "fov": 40})";
    try {
        scene(R"("heightfield": "bricks", "pom_steps": 64)", camera);
        FAIL() << "pom_steps under heidrich was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("pom_steps"), std::string::npos) << e.what();
    }
    try {
        scene(R"("heightfield": "bricks", "method": "pom", "directions": 200)", camera);
        FAIL() << "directions under pom was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("directions"), std::string::npos) << e.what();
    }
    try {
        scene(R"("heightfield": "bricks", "method": "relief")", camera);
        FAIL() << "an unknown method was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("pom"), std::string::npos) << e.what();
    }
    const Technique* t = Registry::instance().technique("microgeom");
    EXPECT_EQ(t->method_names(), (std::vector<std::string>{"heidrich", "pom", "horizon"}));
    for (const Technique* each : Registry::instance().techniques())
        if (each->name() != "basic") {
            EXPECT_TRUE(each->params().find("method")) << each->name() << " has a method key";
        }
}
