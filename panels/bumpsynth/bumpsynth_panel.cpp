// Panel of technique bumpsynth: the NDF editor (panels/bumpsynth/ndf_editor.h) and the generated
// widgets of the object's material, and its AOV buttons.
#include "panels/bumpsynth/ndf_editor.h"
#include "panels/panel.h"

#include <imgui.h>

namespace mesolab::panels {
namespace {

class BumpsynthPanel final : public TechniquePanel {
public:
    void draw(PanelContext& ctx) override {
        SceneObject& o = ctx.scene.objects[size_t(ctx.object)];
        ImGui::TextDisabled("%s", o.name.c_str());
        const bool open = ImGui::TreeNodeEx("NDF editor", ImGuiTreeNodeFlags_DefaultOpen);
        help_marker("The normal density function over the normal's (x, y) disk (+x right, +y up, the rim is the horizon, rings at "
                    "30 and 60 degrees): the last evaluation's table. Drag the lobe handles, or paint an NDF image.");
        if (open) {
            editor_.draw(ctx, ctx.object);
            ImGui::TreePop();
        }
        param_sections(o.material, ctx.dirty);
        aov_buttons(ctx, "bumpsynth");
    }
    void reset() override { editor_ = ndf_editor::NdfEditor(); }

private:
    ndf_editor::NdfEditor editor_;
};
}  // namespace

void register_bumpsynth_panel(PanelRegistry& r) { r.add<BumpsynthPanel>("bumpsynth", "Bump map synthesis (Kautz et al. 2001)"); }
}  // namespace mesolab::panels
