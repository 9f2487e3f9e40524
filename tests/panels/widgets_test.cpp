// Widgets come from the declarations: every declared parameter gets a widget, and editing one
// through simulated mouse input sets its value within the declared range and the dirty flag of
// its declared cost.
#include "core/scene.h"
#include "core/technique.h"
#include "panels/panel.h"
#include "support/headless_imgui.h"

#include <gtest/gtest.h>
#include <imgui.h>
#include <functional>

using namespace mesolab;
using namespace mesolab::panels;
using mesolab::test::HeadlessImGui;

namespace {

// Press and release the mouse at (x, y) over the widget drawn by `draw`.
void click(HeadlessImGui& ui, const std::function<void()>& draw, float fx) {
    float r[4], frame_width = 0;
    ui.frame([&] {
        frame_width = ImGui::CalcItemWidth();  // the widget's frame, without its label
        draw();
    });
    last_widget_rect(r);
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(r[0] + fx * frame_width, 0.5f * (r[1] + r[3]));
    ui.frame(draw);
    io.MouseDown[0] = true;
    ui.frame(draw);
    io.MouseDown[0] = false;
    ui.frame(draw);
}
}  // namespace

TEST(Widgets, EveryDeclaredParameterGetsAWidget) {
    HeadlessImGui ui;
    Dirty dirty;
    int drawn = 0;
    for (const ParamGroup* g : Registry::instance().groups()) {
        ParamTable t = g->defaults();
        ui.frame([&] {
            float before[4] = {-1, -1, -1, -1};
            for (const auto& d : g->decls()) {
                float after[4];
                param_widget(d, t, dirty);
                last_widget_rect(after);
                EXPECT_GT(after[2] - after[0], 0.f) << g->name() << "." << d.name;
                EXPECT_GT(after[1], before[1]) << g->name() << "." << d.name << " drew nothing new";
                std::copy(after, after + 4, before);
                ++drawn;
            }
        });
        EXPECT_FALSE(dirty.any()) << "drawing alone must not mark anything dirty";
    }
    EXPECT_GT(drawn, 20);
}

TEST(Widgets, BoolEditSetsTheDeclaredCost) {
    HeadlessImGui ui;
    ParamTable t = Registry::instance().effects().defaults();  // effects cost a recompute
    Dirty dirty;
    const ParamDecl& d = *t.group().find("environment");
    click(ui, [&] { param_widget(d, t, dirty); }, 0.05f);
    EXPECT_FALSE(t.get_bool("environment"));
    EXPECT_TRUE(dirty.recompute);
}

TEST(Widgets, SliderClampsToTheDeclaredRangeAndCost) {
    HeadlessImGui ui;
    ParamTable cam = Registry::instance().camera().defaults();
    Dirty dirty;
    const ParamDecl& fov = *cam.group().find("fov");
    click(ui, [&] { param_widget(fov, cam, dirty); }, 0.001f);  // the slider's left end
    EXPECT_DOUBLE_EQ(cam.get_float("fov"), fov.min);
    EXPECT_TRUE(dirty.redraw);
    EXPECT_FALSE(dirty.recompute) << "camera.fov is declared as redraw";

    ParamTable geo = Registry::instance().geometry().defaults();
    Dirty dirty2;
    const ParamDecl& res = *geo.group().find("resolution");
    click(ui, [&] { param_widget(res, geo, dirty2); }, 0.999f);  // the right end
    EXPECT_EQ(geo.get_int("resolution"), int64_t(res.max));
    EXPECT_TRUE(dirty2.recompute) << "geometry.resolution is declared as recompute";
}

// Clicking the hemisphere disc at a point sets the direction the point projects from: the
// centre is the zenith, half the radius to the right is theta = 30 degrees, phi = 0; the top
// of the rim is the horizon at phi = 90; the edit marks the declared cost.
TEST(Widgets, HemisphereClickSetsTheProjectedDirection) {
    HeadlessImGui ui;
    ParamTable light = Registry::instance().light().defaults();
    const ParamDecl& d = *light.group().find("direction");
    auto press_at = [&](float fx, float fy) {
        Dirty dirty;
        float r[4];
        auto draw = [&] { hemisphere_widget(d, light, dirty, 200.f); };
        ui.frame(draw);
        last_widget_rect(r);
        ImGuiIO& io = ImGui::GetIO();
        io.MousePos = ImVec2(r[0] + fx * (r[2] - r[0]), r[1] + fy * (r[3] - r[1]));
        ui.frame(draw);
        io.MouseDown[0] = true;
        ui.frame(draw);
        ui.frame(draw);
        io.MouseDown[0] = false;
        ui.frame(draw);
        return dirty;
    };
    Dirty dirty = press_at(0.75f, 0.5f);  // half way from the centre to the right rim
    EXPECT_NEAR(light.get_vec2("direction").x, 30.0, 0.5);
    EXPECT_NEAR(light.get_vec2("direction").y, 0.0, 0.5);
    EXPECT_TRUE(dirty.redraw);
    EXPECT_EQ(dirty.recompute, d.cost == Cost::Recompute) << "the edit marks the declared cost";
    press_at(0.5f, 0.0f);  // top of the rim: the horizon towards +y
    EXPECT_NEAR(light.get_vec2("direction").x, 90.0, 0.5);
    EXPECT_NEAR(light.get_vec2("direction").y, 90.0, 0.5);
    press_at(0.999f, 0.999f);  // outside the disc (corner): clamped to the rim, phi = -45
    EXPECT_NEAR(light.get_vec2("direction").x, 90.0, 0.5);
    EXPECT_NEAR(light.get_vec2("direction").y, -45.0, 0.5);
}
