// Panel of technique basic: the generated widgets of the object's material, and its AOV buttons.
#include "panels/panel.h"

#include <imgui.h>

namespace mesolab::panels {
namespace {

class BasicPanel final : public TechniquePanel {
public:
    void draw(PanelContext& ctx) override {
        SceneObject& o = ctx.scene.objects[size_t(ctx.object)];
        ImGui::TextDisabled("%s", o.name.c_str());
        param_sections(o.material, ctx.dirty);
        aov_buttons(ctx, "basic");
    }
};
}  // namespace

void register_basic_panel(PanelRegistry& r) { r.add<BasicPanel>("basic", "Basic (Lambert + Blinn-Phong)"); }
}  // namespace mesolab::panels
