// microgeom's method horizon (core/microgeom/horizon.h): horizon mapping with GTAO's multi-bounce
// ambient visibility. Its angles are the exact horizons of the bilinear surface along the axes (and
// along the diagonals where the field is linear along them: the V-groove); under a light straight
// above and without the environment it is the paper's bump level; its shadows follow the angles;
// the ambient visibility and the multi-bounce fit have their closed-form values; the CPU and GPU
// frames agree; the paper's stages never run for it, and its keys are errors under the others.
#include "core/error.h"
#include "core/heightfield/heightfield.h"
#include "core/microgeom/horizon.h"
#include "core/microgeom/stages.h"
#include "core/scene.h"
#include "core/technique.h"
#include "microgeom/agreement.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {
// A plane of microgeom `material`, camera `camera`, one directional light from (θ, φ) `light`.
Scene scene(const std::string& material, const std::string& camera, const std::string& light = "[50, 30]", bool env = false) {
    const std::string text = R"({"schema": 1, "name": "microgeom-horizon", "camera": )" + camera +
                             R"(, "lights": [{"type": "directional", "direction": )" + light + R"(, "intensity": 3}], "env": {"color": [0.3, 0.35, 0.4]},
                              "effects": {"environment": )" + std::string(env ? "true" : "false") +
                             R"(, "indirect": false}, "objects": [{"name": "field", "geometry": {"type": "plane", "resolution": 4}, "material": {"technique": "microgeom", )" +
                             material + "}}]}";
    return scene_from_json(nlohmann::json::parse(text), "microgeom-horizon", test::source_path("presets"));
}

PomField vgrooves(int n) {
    ProceduralParams p;
    p.name = "vgrooves";
    p.resolution = n;
    p.vgroove_angle = 90.f;
    return PomField::from(make_procedural(p));
}

// The exact horizon of the bilinear surface from texel (x, y) along the grid direction (sx, sy)
// (one of the 8 axes and diagonals), within R texels: the surface sampled every 1/64 of a step.
double exact_sin_horizon(const PomField& f, int x, int y, int sx, int sy, int R) {
    const double step = std::sqrt(double(sx * sx + sy * sy));
    const double z0 = f.z[size_t(y) * size_t(f.width) + size_t(x)];
    double best = -1e30;
    for (int k = 1; k * step / 64.0 <= R + 1e-9; ++k) {
        const double s = k / 64.0;
        best = std::max(best, (double(f.at(float(x + s * sx), float(y - s * sy))) - z0) / (s * step));
    }
    return best / std::sqrt(1.0 + best * best);
}
}  // namespace

// Along the axes the bilinear surface is piecewise linear between texel centres, and (z - z0)/t is
// monotonic between them: the samples at the centres give the exact horizon. On the V-groove (which
// varies along x only) the diagonals are linear between centres too. Every texel, 8 directions.
TEST(MicrogeomHorizon, AnglesAreTheExactHorizonsOnTheVGroove) {
    const PomField f = vgrooves(64);
    ASSERT_GT(f.z_max - f.z_min, 4.f);
    const int R = 40;
    const HorizonMap m = make_horizon_map(f, 8, R);
    const int dirs[8][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
    int raised = 0;
    double worst = 0;
    for (int j = 0; j < 8; ++j)
        for (int y = 0; y < f.height; y += 5)
            for (int x = 0; x < f.width; ++x) {
                const double want = exact_sin_horizon(f, x, y, dirs[j][0], dirs[j][1], R);
                const double d = std::fabs(double(m.at(j, x, y)) - want);
                EXPECT_LT(d, 1e-5) << "direction " << j << " texel " << x << ", " << y << ": " << m.at(j, x, y) << " against " << want;
                worst = std::max(worst, d);
                raised += want > 0.1;
            }
    EXPECT_LT(worst, 1e-5);
    EXPECT_GT(raised, 200) << "the grooves' flanks see the rims";
    // Across the grooves (±x) a flank's horizon is the opposite rim; along them (±y) the field is flat.
    for (int x = 0; x < f.width; ++x) {
        EXPECT_NEAR(m.at(2, x, 7), 0.f, 1e-6);
        EXPECT_NEAR(m.at(6, x, 7), 0.f, 1e-6);
    }
}

// The ambient visibility is 1 - mean(max(0, sin θ_j)²); GTAO's fit leaves full visibility near 1
// and brightens partial visibility more for brighter albedos.
TEST(MicrogeomHorizon, AmbientVisibilityAndTheMultiBounceFitHaveTheirClosedForms) {
    const PomField f = vgrooves(32);
    const HorizonMap m = make_horizon_map(f, 16, 32);
    for (int x = 0; x < 32; x += 5) {
        double s = 0;
        for (int j = 0; j < 16; ++j) s += std::pow(std::max(0.f, m.at(j, x, 3)), 2.f);
        EXPECT_NEAR(m.ambient(float(x), 3.f), 1.0 - s / 16.0, 1e-6);
    }
    EXPECT_NEAR(gtao_multibounce(1.f, 0.8f), 1.f, 1e-3);
    EXPECT_FLOAT_EQ(gtao_multibounce(0.f, 0.8f), 0.f);
    EXPECT_GT(gtao_multibounce(0.5f, 0.8f), gtao_multibounce(0.5f, 0.2f));
    EXPECT_GE(gtao_multibounce(0.5f, 0.0f), 0.5f);
    const PomField flat = PomField::from(test::procedural_field("flat", 16));
    EXPECT_FLOAT_EQ(make_horizon_map(flat, 8, 8).ambient(3.5f, 2.25f), 1.f);
}

// Under a light straight above, nothing on the field rises above 90°: every texel is lit, and
// without the environment horizon mapping is the bump level's shading (the same bilinear normal and albedo).
TEST(MicrogeomHorizon, UnderALightStraightAboveItIsTheBumpLevel) {
    for (const char* field : {"bricks", "gaussian", "vgrooves"}) {
        SCOPED_TRACE(field);
        const std::string common = std::string(R"("heightfield": ")") + field + R"(", "resolution": 64, "height_scale": 2)";
        const std::string camera = R"({"mode": "texture", "orbit": [0, 0]})";
        Workbench wb;
        RenderRequest req;
        req.renderer = "cpu";
        const Frame a = wb.render(scene(common + R"(, "depth": 0, "shadows": "none")", camera, "[0, 0]"), req).frame;
        const Frame b = wb.render(scene(common + R"(, "method": "horizon")", camera, "[0, 0]"), req).frame;
        double most = 0, sum = 0;
        for (size_t i = 0; i < a.aov("radiance").data.size(); ++i) {
            most = std::max(most, double(std::fabs(a.aov("radiance").data[i] - b.aov("radiance").data[i])));
            sum += a.aov("radiance").data[i];
        }
        EXPECT_GT(sum, 0.0) << "content in the frames";
        EXPECT_LT(most, 1e-5);
        // A low light is not: the V-groove's and bricks' flanks fall into their neighbours' shadows.
        if (std::string(field) != "gaussian") {
            const Frame low = wb.render(scene(common + R"(, "method": "horizon")", camera, "[75, 0]"), req).frame;
            size_t shadowed = 0;
            for (float v : low.aov("shadow").data) shadowed += v < 0.5f;
            EXPECT_GT(shadowed, low.aov("shadow").data.size() / 20);
        }
    }
}

// The CPU reference and the GPU pass agree, with content in both frames: a plane at a grazing view
// with the environment, a sphere, Blinn-Phong.
TEST(MicrogeomHorizon, CpuAndGpuFramesAgree) {
    const std::vector<std::pair<std::string, Scene>> cases = {
        {"plane at 70 degrees", scene(R"("method": "horizon", "heightfield": "bricks", "resolution": 64, "height_scale": 2, "tiling": 2)",
                                      R"({"mode": "orbit", "distance": 2.6, "orbit": [70, -90], "fov": 40})", "[60, 30]", true)},
        {"blinn-phong, 7 directions", scene(R"("method": "horizon", "heightfield": "bumps", "resolution": 64, "brdf": "blinn-phong", "horizon_directions": 7, "horizon_radius": 12)",
                                            R"({"mode": "orbit", "distance": 2.6, "orbit": [55, -90], "fov": 40})", "[65, 200]", true)},
    };
    Workbench wb;
    for (const auto& [name, s] : cases) {
        SCOPED_TRACE(name);
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 160, 160, {"radiance", "normal", "shadow"});
        test::expect_frames_agree(s, cpu, gpu, {"radiance", "normal", "shadow"});
    }
}

// Only the stages a method reads run: the horizon map (and the texel heights it is found on) for
// horizon objects, the paper's visibility for the paper's.
TEST(MicrogeomHorizon, EachMethodRunsOnlyItsStages) {
    Scene s = scene(R"("heightfield": "bricks", "resolution": 32, "directions": 32, "depth": 1)", R"({"mode": "orbit", "distance": 3, "orbit": [40, -90], "fov": 40})");
    SceneObject second = s.objects[0];
    second.name = "horizon";
    second.material.set("method", std::string("horizon"));
    second.geometry.set("position", std::array<double, 3>{1.0, 0.0, 0.0});
    s.objects.push_back(second);
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 32;
    const Evaluation& ev = wb.render(s, req).eval;
    EXPECT_TRUE(ev.get(stages::visibility, 0));
    EXPECT_FALSE(ev.get(stages::visibility, 1)) << "the paper's visibility for the horizon object";
    EXPECT_FALSE(ev.get(stages::horizon_map, 0)) << "a horizon map for the paper's object";
    EXPECT_TRUE(ev.get(stages::horizon_map, 1));
}

TEST(MicrogeomHorizon, KeysOfAnotherMethodAreErrors) {
    const std::string camera = R"({"mode": "orbit", "distance": 3, "orbit": [40, -90], "fov": 40})";
    for (const auto& [material, key] : std::vector<std::pair<std::string, std::string>>{
             {R"("heightfield": "bricks", "horizon_radius": 8)", "horizon_radius"},
             {R"("heightfield": "bricks", "method": "pom", "horizon_directions": 8)", "horizon_directions"},
             {R"("heightfield": "bricks", "method": "horizon", "pom_steps": 8)", "pom_steps"},
             {R"("heightfield": "bricks", "method": "horizon", "directions": 200)", "directions"}}) {
        try {
            scene(material, camera);
            ADD_FAILURE() << key << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
        }
    }
}
