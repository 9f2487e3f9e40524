// Panel of technique bumpsynth: the NDF editor (panels/bumpsynth/ndf_editor.h) for the selected
// object (or the first object using bumpsynth), and the generated widgets for each object's material.
#include "panels/bumpsynth/ndf_editor.h"
#include "panels/panel.h"

#include <imgui.h>

namespace mesolab::panels {

void register_bumpsynth_panel(PanelRegistry& r) {
    r.add("bumpsynth", "Bump map synthesis (Kautz et al. 2001)", [](PanelContext& ctx) {
        static ndf_editor::NdfEditor editor;
        int edited = -1;
        if (size_t(ctx.object) < ctx.scene.objects.size() && ctx.scene.objects[size_t(ctx.object)].technique == "bumpsynth") edited = ctx.object;
        for (size_t i = 0; edited < 0 && i < ctx.scene.objects.size(); ++i)
            if (ctx.scene.objects[i].technique == "bumpsynth") edited = int(i);
        if (edited < 0) {
            ImGui::TextDisabled("No object in this scene uses bumpsynth.");
            return;
        }
        for (size_t i = 0; i < ctx.scene.objects.size(); ++i) {
            SceneObject& o = ctx.scene.objects[i];
            if (o.technique != "bumpsynth") continue;
            ImGui::PushID(int(i));
            if (ImGui::TreeNodeEx(o.name.c_str(), ImGuiTreeNodeFlags_DefaultOpen)) {
                if (int(i) == edited) {
                    const bool open = ImGui::TreeNodeEx("NDF editor", ImGuiTreeNodeFlags_DefaultOpen);
                    help_marker("The normal density function over the normal's (x, y) disk (+x right, +y up, the rim is the horizon, rings at "
                                "30 and 60 degrees): the last evaluation's table. Drag the lobe handles, or paint an NDF image.");
                    if (open) {
                        editor.draw(ctx, int(i));
                        ImGui::TreePop();
                    }
                }
                param_table_widgets(o.material, ctx.dirty);
                ImGui::TreePop();
            }
            ImGui::PopID();
        }
    });
}
}  // namespace mesolab::panels
