// Panel of technique microgeom: the generated widgets for each object's heightfield, direction
// set, scattering and shading parameters, grouped, plus what the stages hold.
#include "core/microgeom/microgeom.h"
#include "panels/panel.h"

#include <imgui.h>

namespace mesolab::panels {
namespace {

void group(ParamTable& t, Dirty& dirty, const char* title, std::initializer_list<const char*> names, bool open) {
    if (!ImGui::TreeNodeEx(title, open ? ImGuiTreeNodeFlags_DefaultOpen : 0)) return;
    for (const char* n : names) {
        const ParamDecl* d = t.group().find(n);
        if (d && t.is_used(*d)) param_widget(*d, t, dirty);
    }
    ImGui::TreePop();
}
}  // namespace

void register_microgeom_panel(PanelRegistry& r) {
    r.add("microgeom", "Micro-geometry (Heidrich et al. 2000)", [](PanelContext& ctx) {
        for (size_t i = 0; i < ctx.scene.objects.size(); ++i) {
            SceneObject& o = ctx.scene.objects[i];
            if (o.technique != "microgeom") continue;
            ImGui::PushID(int(i));
            ImGui::TextDisabled("%s", o.name.c_str());
            group(o.material, ctx.dirty, "Heightfield", {"heightfield", "resolution", "height_scale", "periodic", "vgroove_angle", "rms_slope", "correlation", "seed", "albedo", "tiling"}, true);
            group(o.material, ctx.dirty, "Visibility and scattering", {"directions", "depth", "sampling", "paths", "scatter_seed", "shadows"}, true);
            group(o.material, ctx.dirty, "Shading", {"brdf", "ks", "shininess"}, false);
            if (ctx.eval) {
                if (auto vis = ctx.eval->get<microgeom::PerObject<microgeom::Visibility>>("microgeom.visibility"))
                    if (const auto* v = vis->get(int(i)))
                        ImGui::TextDisabled("S_i: %d directions x %dx%d texels, %.1f MB", v->count, v->width, v->height, double(v->bytes()) / (1 << 20));
            }
            ImGui::PopID();
        }
    });
}
}  // namespace mesolab::panels
