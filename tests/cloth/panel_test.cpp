// The cloth panel draws for a cloth object (stitch preview, stage lines, BRDF slice, mip views)
// without editing anything, and says so for an object of another technique.
#include "app/workbench.h"
#include "core/scene.h"
#include "panels/panel.h"
#include "support/headless_imgui.h"

#include <gtest/gtest.h>
#include <string>

using namespace mesolab;

namespace {
const panels::PanelEntry& cloth_panel(panels::PanelRegistry& reg) {
    panels::register_technique_panels(reg);
    for (const auto& e : reg.entries)
        if (e.technique == "cloth") return e;
    throw std::logic_error("no cloth panel");
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
    panels::PanelRegistry reg;
    const panels::PanelEntry& panel = cloth_panel(reg);
    panels::Dirty dirty;
    std::string aov = "radiance";
    panels::PanelContext ctx{s, dirty, &ev, 0};
    ctx.aov = &aov;
    size_t without_eval = 0;
    {
        panels::PanelContext bare{s, dirty, nullptr, 0};
        for (int k = 0; k < 2; ++k) ui.frame([&] { panel.draw(bare); });
        without_eval = size_t(ImGui::GetDrawData()->TotalVtxCount);
    }
    for (int k = 0; k < 3; ++k) ui.frame([&] { panel.draw(ctx); });
    EXPECT_FALSE(dirty.any());
    EXPECT_EQ(aov, "radiance");
    ASSERT_NE(ImGui::GetDrawData(), nullptr);
    // The stitch's triangles and the slice's points and lines come on top of the widgets.
    EXPECT_GT(size_t(ImGui::GetDrawData()->TotalVtxCount), without_eval + 1000);
}

TEST(ClothPanel, SaysSoForAnObjectOfAnotherTechnique) {
    test::HeadlessImGui ui;
    Scene s = default_scene("basic");
    panels::PanelRegistry reg;
    const panels::PanelEntry& panel = cloth_panel(reg);
    panels::Dirty dirty;
    panels::PanelContext ctx{s, dirty, nullptr, 0};
    ui.frame([&] { panel.draw(ctx); });
    EXPECT_FALSE(dirty.any());
}
