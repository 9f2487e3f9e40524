// The cloth panel draws for a cloth object (stitch preview, stage lines, BRDF slice, mip views)
// without editing anything; the window draws it only for its own objects.
#include "app/workbench.h"
#include "core/scene.h"
#include "panels/panel.h"
#include "support/headless_imgui.h"

#include <gtest/gtest.h>
#include <string>

using namespace mesolab;

namespace {
// A panel of the technique's own, as a window makes it.
std::unique_ptr<panels::TechniquePanel> cloth_panel() {
    panels::PanelRegistry reg;
    panels::register_technique_panels(reg);
    const panels::PanelEntry* e = reg.find("cloth");
    if (!e) throw std::logic_error("no cloth panel");
    return e->make();
}
}  // namespace

TEST(ClothPanel, DrawsTheStitchPreviewAndTheBrdfSliceWithoutEditing) {
    test::HeadlessImGui ui;
    Scene s = default_scene("cloth");
    apply_set(s, "cloth.stitch_resolution", "16");
    apply_set(s, "cloth.spatial", "4");
    apply_set(s, "cloth.directions", "8");
    apply_set(s, "cloth.visibility_rays", "4");
    Workbench wb;
    const Evaluation ev = wb.evaluate(s, Registry::instance().frame_stages(s));
    const auto panel = cloth_panel();
    panels::Dirty dirty;
    std::string aov = "radiance";
    panels::PanelContext ctx{s, dirty, &ev, 0};
    ctx.aov = &aov;
    size_t without_eval = 0;
    {
        panels::PanelContext bare{s, dirty, nullptr, 0};
        for (int k = 0; k < 2; ++k) ui.frame([&] { panel->draw(bare); });
        without_eval = size_t(ImGui::GetDrawData()->TotalVtxCount);
    }
    for (int k = 0; k < 3; ++k) ui.frame([&] { panel->draw(ctx); });
    EXPECT_FALSE(dirty.any());
    EXPECT_EQ(aov, "radiance");
    ASSERT_NE(ImGui::GetDrawData(), nullptr);
    // The stitch's triangles and the slice's points and lines come on top of the widgets.
    EXPECT_GT(size_t(ImGui::GetDrawData()->TotalVtxCount), without_eval + 1000);
}

// The window draws a technique's panel only for that technique's objects: the selected one, or else
// the first; none in a scene without one.
TEST(ClothPanel, IsDrawnOnlyForObjectsOfItsTechnique) {
    Scene s = default_scene("basic");
    EXPECT_EQ(panels::panel_object(s, "cloth", 0), -1);
    s.objects.push_back(default_scene("cloth").objects[0]);
    EXPECT_EQ(panels::panel_object(s, "cloth", 0), 1) << "the basic object is selected: the panel shows the first cloth object";
    EXPECT_EQ(panels::panel_object(s, "cloth", 1), 1);
}
