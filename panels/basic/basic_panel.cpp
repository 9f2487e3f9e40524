// Panel of technique basic: the generated widgets for the selected object's material.
#include "panels/panel.h"

#include <imgui.h>

namespace mesolab::panels {

void register_basic_panel(PanelRegistry& r) {
    r.add("basic", "Basic (Lambert + Blinn-Phong)", [](PanelContext& ctx) {
        bool any = false;
        for (size_t i = 0; i < ctx.scene.objects.size(); ++i) {
            SceneObject& o = ctx.scene.objects[i];
            if (o.technique != "basic") continue;
            any = true;
            ImGui::PushID(int(i));
            if (ImGui::TreeNodeEx(o.name.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) {
                param_table_widgets(o.material, ctx.dirty);
                ImGui::TreePop();
            }
            ImGui::PopID();
        }
        if (!any) ImGui::TextDisabled("No object in this scene uses basic.");
    });
}
}  // namespace mesolab::panels
