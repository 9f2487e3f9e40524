// The translucency panel draws for a translucent object (R_d plot, what the stages hold, views),
// switches the viewport's AOV from its view buttons, and measures the error against the reference.
#include "app/workbench.h"
#include "core/scene.h"
#include "core/translucency/translucency.h"
#include "panels/panel.h"
#include "support/headless_imgui.h"

#include <gtest/gtest.h>
#include <string>

using namespace mesolab;

namespace {
Scene small_sphere() {
    Scene s = default_scene("translucency");
    apply_set(s, "geometry.resolution", "24");
    apply_set(s, "translucency.atlas_size", "128");
    apply_set(s, "translucency.mm_per_unit", "10");
    return s;
}
// A panel of the technique's own, as a window makes it.
std::unique_ptr<panels::TechniquePanel> translucency_panel() {
    panels::PanelRegistry reg;
    panels::register_technique_panels(reg);
    const panels::PanelEntry* e = reg.find("translucency");
    if (!e) throw std::logic_error("no translucency panel");
    return e->make();
}
}  // namespace

TEST(TranslucencyPanel, DrawsAndItsViewButtonsPickTheAov) {
    test::HeadlessImGui ui;
    Scene s = small_sphere();
    Workbench wb;
    const Evaluation ev = wb.evaluate(s, Registry::instance().frame_stages(s));
    const auto panel = translucency_panel();
    panels::Dirty dirty;
    std::string aov = "radiance";
    panels::PanelContext ctx{s, dirty, &ev, 0};
    ctx.aov = &aov;
    for (int k = 0; k < 3; ++k) ui.frame([&] { panel->draw(ctx); });
    EXPECT_FALSE(dirty.any());
    ASSERT_NE(ImGui::GetDrawData(), nullptr);
    EXPECT_GT(ImGui::GetDrawData()->TotalVtxCount, 1000) << "the R_d plot and the widgets";
    // The R_d-independent parts of the scene are untouched, and so is the AOV until a button is pressed.
    EXPECT_EQ(aov, "radiance");
    // The error against the brute force, as the panel's button measures it.
    const double e = translucency::radiosity_error(s, ev, 0);
    EXPECT_GT(e, 0.0);
    EXPECT_LT(e, 0.5);
}

// The window draws a technique's panel only for that technique's objects: the selected one, or else
// the first; none in a scene without one.
TEST(TranslucencyPanel, IsDrawnOnlyForObjectsOfItsTechnique) {
    Scene s = default_scene("basic");
    EXPECT_EQ(panels::panel_object(s, "translucency", 0), -1);
    s.objects.push_back(default_scene("translucency").objects[0]);
    EXPECT_EQ(panels::panel_object(s, "translucency", 0), 1) << "the basic object is selected: the panel shows the first translucency object";
    EXPECT_EQ(panels::panel_object(s, "translucency", 1), 1);
}
