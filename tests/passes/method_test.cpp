// What a new method gets from its registration alone (the probe method `microgeom/flat-probe`,
// tests/passes/probe_method.cpp, one class, one pass, one call): a value of microgeom.method, its
// key used only under it, only the stages it reads, both render paths agreeing, the frontier
// measuring it beside the paper's method and pom against one truth.
#include "app/api.h"
#include "core/error.h"
#include "core/microgeom/pom.h"
#include "core/microgeom/stages.h"
#include "core/scene.h"
#include "core/technique.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <set>

using namespace mesolab;

namespace {
Scene probe_scene(const std::string& material) {
    const std::string text = R"({"schema": 1, "name": "method-probe", "camera": {"mode": "orbit", "distance": 3, "orbit": [40, -90], "fov": 40},
        "lights": [{"type": "directional", "direction": [40, 30], "intensity": 3}], "env": {"color": [0, 0, 0]}, "effects": {"environment": false},
        "objects": [{"name": "field", "geometry": {"type": "plane", "resolution": 4},
                     "material": {"technique": "microgeom", "heightfield": "bricks", "resolution": 32, "directions": 32, "depth": 1)" + material + "}}]}";
    return scene_from_json(nlohmann::json::parse(text), "method-probe", test::source_path("presets"));
}
}  // namespace

TEST(Methods, ANewMethodIsOneRegistrationAndRunsOnBothPaths) {
    const Technique* t = Registry::instance().technique("microgeom");
    EXPECT_EQ(t->method_names(), (std::vector<std::string>{"heidrich", "pom", "horizon", "flat-probe"}));
    Scene s = probe_scene("");
    apply_set(s, "microgeom.method=flat-probe");
    apply_set(s, "microgeom.probe_gain=0.5");
    Workbench wb;
    const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 64, 64, {"radiance", "normal"});
    test::expect_frames_agree(s, cpu, gpu, {"radiance", "normal"});
    // Only what it reads ran: the heightfield, none of the paper's or pom's stages.
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 16;
    const RenderResult r = wb.render(s, req);
    EXPECT_TRUE(r.eval.get(microgeom::stages::heightfield, 0));
    EXPECT_FALSE(r.eval.get(microgeom::stages::visibility, 0));
    EXPECT_FALSE(r.eval.get(microgeom::stages::pom_field, 0));
    // Its key is used only under it.
    EXPECT_THROW(probe_scene(R"(, "probe_gain": 2)"), InputError);
}

TEST(Methods, TheFrontierMeasuresEveryMethodAgainstOneTruth) {
    FrontierOptions o;
    o.width = o.height = 24;
    o.truth = truth_sampling(4, 0.0, 0.0, 1);
    o.budget_s = 0;  // each method's preset setting only
    o.repeat = 1;
    o.quiet = true;
    const FrontierResult r = frontier_scene(probe_scene(""), o, false);
    std::set<std::string> methods;
    for (const FrontierPoint& p : r.points) {
        methods.insert(p.method);
        EXPECT_EQ(p.settings.front(), (std::pair<std::string, std::string>{"microgeom.method", p.method})) << "its settings load its method";
        EXPECT_GT(p.rmse_rel, 0.0);
    }
    EXPECT_EQ(methods, (std::set<std::string>{"heidrich", "pom", "horizon", "flat-probe"}));
    EXPECT_EQ(r.points.size(), 4u);
    EXPECT_EQ(r.truth_noise.size(), 1u) << "one truth for the distance";
}
