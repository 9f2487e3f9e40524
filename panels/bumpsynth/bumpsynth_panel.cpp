// Panel of technique bumpsynth: the generated widgets for the selected object's material.
#include "panels/panel.h"

#include <imgui.h>

namespace mesolab::panels {

void register_bumpsynth_panel(PanelRegistry& r) {
    r.add("bumpsynth", "Bump map synthesis (Kautz et al. 2001)", [](PanelContext& ctx) {
        bool any = false;
        for (size_t i = 0; i < ctx.scene.objects.size(); ++i) {
            SceneObject& o = ctx.scene.objects[i];
            if (o.technique != "bumpsynth") continue;
            any = true;
            ImGui::PushID(int(i));
            if (ImGui::TreeNodeEx(o.name.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) {
                param_table_widgets(o.material, ctx.dirty);
                ImGui::TreePop();
            }
            ImGui::PopID();
        }
        if (!any) ImGui::TextDisabled("No object in this scene uses bumpsynth.");
    });
}
}  // namespace mesolab::panels
