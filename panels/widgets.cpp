// Widgets generated from parameter declarations.
#include "panels/panel.h"

#include <imgui.h>
#include <cmath>
#include <cstring>

namespace mesolab::panels {

void help_marker(const char* text) {
    ImGui::SameLine();
    ImGui::TextDisabled("(?)");
    if (ImGui::IsItemHovered()) {
        ImGui::BeginTooltip();
        ImGui::PushTextWrapPos(ImGui::GetFontSize() * 35.0f);
        ImGui::TextUnformatted(text);
        ImGui::PopTextWrapPos();
        ImGui::EndTooltip();
    }
}

namespace {
float g_last_rect[4] = {0, 0, 0, 0};

std::string tooltip(const ParamGroup& g, const ParamDecl& d) {
    std::string s = g.name() + "." + d.name + "\n" + d.help;
    const std::string range = describe_range(d);
    if (!range.empty()) s += "\nrange " + range;
    if (!d.unit.empty()) s += " (" + d.unit + ")";
    s += std::string("\nchange costs: ") + to_string(d.cost);
    return s;
}
}  // namespace

bool param_widget(const ParamDecl& d, ParamTable& t, Dirty& dirty, const char* id_suffix) {
    const std::string label = d.name + "##" + t.group().name() + id_suffix;
    Value v = t.get(d.name);
    bool changed = false;
    const float lo = std::isfinite(d.min) ? float(d.min) : -1e6f, hi = std::isfinite(d.max) ? float(d.max) : 1e6f;
    const ImGuiSliderFlags flags = (d.log_scale ? ImGuiSliderFlags_Logarithmic : 0) | ImGuiSliderFlags_AlwaysClamp;
    switch (d.type) {
        case ParamType::Bool: {
            bool b = std::get<bool>(v);
            if ((changed = ImGui::Checkbox(label.c_str(), &b))) v = b;
            break;
        }
        case ParamType::Int: {
            int i = int(std::get<int64_t>(v));
            const bool bounded = std::isfinite(d.min) && std::isfinite(d.max) && d.max - d.min <= 1e5;
            if (bounded) changed = ImGui::SliderInt(label.c_str(), &i, int(d.min), int(d.max), "%d", flags);
            else changed = ImGui::DragInt(label.c_str(), &i, 1.0f, int(std::max(lo, -1e9f)), int(std::min(hi, 1e9f)), "%d", flags);
            if (changed) v = int64_t(i);
            break;
        }
        case ParamType::Float: {
            float f = float(std::get<double>(v));
            if (std::isfinite(d.min) && std::isfinite(d.max)) changed = ImGui::SliderFloat(label.c_str(), &f, lo, hi, "%.4g", flags);
            else changed = ImGui::DragFloat(label.c_str(), &f, 0.01f, lo, hi, "%.4g", flags);
            if (changed) v = double(f);
            break;
        }
        case ParamType::Vec2: {
            auto a = std::get<std::array<double, 2>>(v);
            float f[2] = {float(a[0]), float(a[1])};
            if ((changed = ImGui::DragFloat2(label.c_str(), f, 0.25f, lo, hi, "%.4g", flags))) v = std::array<double, 2>{f[0], f[1]};
            break;
        }
        case ParamType::Vec3: {
            auto a = std::get<std::array<double, 3>>(v);
            float f[3] = {float(a[0]), float(a[1]), float(a[2])};
            if ((changed = ImGui::DragFloat3(label.c_str(), f, 0.01f, lo, hi, "%.4g", flags))) v = std::array<double, 3>{f[0], f[1], f[2]};
            break;
        }
        case ParamType::Color: {
            auto a = std::get<std::array<double, 3>>(v);
            float f[3] = {float(a[0]), float(a[1]), float(a[2])};
            if ((changed = ImGui::ColorEdit3(label.c_str(), f, ImGuiColorEditFlags_Float))) v = std::array<double, 3>{std::clamp(double(f[0]), d.min, d.max), std::clamp(double(f[1]), d.min, d.max), std::clamp(double(f[2]), d.min, d.max)};
            break;
        }
        case ParamType::Enum: {
            const std::string& cur = std::get<std::string>(v);
            if (ImGui::BeginCombo(label.c_str(), cur.c_str())) {
                for (const auto& c : d.choices) {
                    const bool sel = c == cur;
                    if (ImGui::Selectable(c.c_str(), sel)) {
                        v = c;
                        changed = c != cur;
                    }
                    if (sel) ImGui::SetItemDefaultFocus();
                }
                ImGui::EndCombo();
            }
            break;
        }
        case ParamType::Path: {
            // Built-in names (e.g. procedural heightfields) in a combo; a file path as text,
            // applied on Enter. A missing file is reported by the stage that reads it.
            const std::string cur = std::get<std::string>(v);
            if (!d.choices.empty()) {
                if (ImGui::BeginCombo(label.c_str(), cur.c_str())) {
                    for (const auto& c : d.choices)
                        if (ImGui::Selectable(c.c_str(), c == cur) && c != cur) {
                            v = c;
                            changed = true;
                        }
                    ImGui::EndCombo();
                }
            }
            char buf[1024];
            std::strncpy(buf, d.is_file(t.get(d.name)) || d.choices.empty() ? cur.c_str() : "", sizeof buf - 1);
            buf[sizeof buf - 1] = 0;
            const std::string text_label = d.choices.empty() ? label : "file##" + t.group().name() + d.name + id_suffix;
            if (ImGui::InputTextWithHint(text_label.c_str(), "path (Enter to apply)", buf, sizeof buf, ImGuiInputTextFlags_EnterReturnsTrue)) {
                v = std::string(buf);
                changed = true;
            }
            break;
        }
    }
    const ImVec2 rmin = ImGui::GetItemRectMin(), rmax = ImGui::GetItemRectMax();
    g_last_rect[0] = rmin.x, g_last_rect[1] = rmin.y, g_last_rect[2] = rmax.x, g_last_rect[3] = rmax.y;
    help_marker(tooltip(t.group(), d).c_str());
    if (changed) {
        t.set(d.name, v);
        dirty.mark(d.cost);
    }
    return changed;
}

void last_widget_rect(float out[4]) {
    for (int i = 0; i < 4; ++i) out[i] = g_last_rect[i];
}

bool param_table_widgets(ParamTable& t, Dirty& dirty, const char* id_suffix) {
    bool changed = false;
    for (const auto& d : t.group().decls())
        if (t.is_used(d)) changed |= param_widget(d, t, dirty, id_suffix);
    return changed;
}
}  // namespace mesolab::panels
