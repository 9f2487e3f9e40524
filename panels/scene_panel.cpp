// Scene panel: every widget generated from the scene-level declarations (core/technique.cpp).
#include "panels/app_panels.h"
#include "core/technique.h"

#include <imgui.h>
#include <algorithm>
#include <string>

namespace mesolab::panels {
namespace {

constexpr int kMaxGpuLights = 8;  // gpu::Renderer::set_lighting_uniforms

bool section(const char* title) { return ImGui::CollapsingHeader(title, ImGuiTreeNodeFlags_DefaultOpen); }

// Label column: widgets take what is left after the longest parameter name and the (?) marker.
void push_widths() { ImGui::PushItemWidth(-ImGui::GetFontSize() * 8.5f); }

std::string object_label(const SceneObject& o, size_t i) {
    return (o.name.empty() ? "object" + std::to_string(i) : o.name) + "  (" + o.technique + ")";
}
}  // namespace

void scene_panel(PanelContext& ctx, const Scene* reference) {
    Scene& s = ctx.scene;
    push_widths();
    if (!s.description.empty()) {
        ImGui::PushTextWrapPos(0.f);
        ImGui::TextDisabled("%s", s.description.c_str());
        ImGui::PopTextWrapPos();
        ImGui::Spacing();
    }

    if (section("Camera")) {
        ImGui::PushID("camera");
        param_table_widgets(s.camera, ctx.dirty);
        if (reference && reference->camera.valid()) {
            ImGui::BeginDisabled(reference->camera == s.camera);
            if (ImGui::SmallButton("Reset camera")) {
                s.camera = reference->camera;
                ctx.dirty.mark(Cost::Redraw);
            }
            ImGui::EndDisabled();
            if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("Back to the camera of the loaded preset");
            ImGui::SameLine();
        }
        ImGui::TextDisabled("(?)");
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("In the viewport:\n  left-drag          orbit (theta, phi)\n  right/middle-drag  pan the target\n  wheel              zoom (distance x 1.1 per notch)");
        ImGui::PopID();
    }

    const std::string lights_title = "Lights (" + std::to_string(s.lights.size()) + ")###lights";
    if (section(lights_title.c_str())) {
        int remove = -1;
        for (size_t i = 0; i < s.lights.size(); ++i) {
            ImGui::PushID(int(i));
            const std::string title = "Light " + std::to_string(i) + " (" + s.lights[i].get_string("type") + ")###light";
            const bool open = ImGui::TreeNodeEx(title.c_str(), ImGuiTreeNodeFlags_DefaultOpen | ImGuiTreeNodeFlags_SpanAvailWidth | ImGuiTreeNodeFlags_AllowItemOverlap);
            ImGui::SameLine(ImGui::GetWindowContentRegionMax().x - ImGui::CalcTextSize("Remove").x - ImGui::GetStyle().FramePadding.x * 2.f);
            if (ImGui::SmallButton("Remove")) remove = int(i);
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("Remove light %d (key lights.%d.*)", int(i), int(i));
            if (open) {
                param_table_widgets(s.lights[i], ctx.dirty);
                ImGui::TreePop();
            }
            ImGui::PopID();
        }
        if (remove >= 0) {
            s.lights.erase(s.lights.begin() + remove);
            ctx.dirty.mark(Cost::Redraw);
        }
        if (s.lights.empty()) ImGui::TextDisabled("No light: only the environment lights the scene.");
        const bool full = s.lights.size() >= size_t(kMaxGpuLights);
        ImGui::BeginDisabled(full);
        if (ImGui::Button("Add light")) {
            s.lights.push_back(Registry::instance().light().defaults());
            ctx.dirty.mark(Cost::Redraw);
        }
        ImGui::EndDisabled();
        if (full && ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("The GPU renderer draws up to %d lights", kMaxGpuLights);
    }

    if (section("Environment")) {
        ImGui::PushID("env");
        param_table_widgets(s.env, ctx.dirty);
        ImGui::PopID();
    }

    if (section("Effects")) {
        ImGui::PushID("effects");
        param_table_widgets(s.effects, ctx.dirty);
        ImGui::PopID();
    }

    if (section("Object")) {
        if (s.objects.empty()) {
            ImGui::TextDisabled("The scene has no object.");
        } else {
            ctx.object = std::clamp(ctx.object, 0, int(s.objects.size()) - 1);
            const std::string current = object_label(s.objects[size_t(ctx.object)], size_t(ctx.object));
            if (ImGui::BeginCombo("object", current.c_str())) {
                for (size_t i = 0; i < s.objects.size(); ++i) {
                    const bool sel = int(i) == ctx.object;
                    if (ImGui::Selectable(object_label(s.objects[i], i).c_str(), sel)) ctx.object = int(i);
                    if (sel) ImGui::SetItemDefaultFocus();
                }
                ImGui::EndCombo();
            }
            help_marker("The object whose geometry is edited below (objects.N.geometry.*). Its material is in the technique's panel.");
            ImGui::PushID(ctx.object);
            param_table_widgets(s.objects[size_t(ctx.object)].geometry, ctx.dirty);
            ImGui::PopID();
        }
    }
    ImGui::PopItemWidth();
}
}  // namespace mesolab::panels
