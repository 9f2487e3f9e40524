// Widgets generated from parameter declarations.
#include "panels/panel.h"
#include "core/technique.h"

#include <imgui.h>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <utility>

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
        case ParamType::Text: {
            // Applied on Enter; a value its syntax check refuses stays in the field, with the reason
            // under it, and changes nothing.
            static std::map<std::string, std::pair<std::string, std::string>> pending;  // label -> (text, error)
            auto& [text, error] = pending[label];
            const std::string cur = std::get<std::string>(v);
            if (error.empty()) text = cur;
            char buf[2048];
            std::strncpy(buf, text.c_str(), sizeof buf - 1);
            buf[sizeof buf - 1] = 0;
            if (ImGui::InputText(label.c_str(), buf, sizeof buf, ImGuiInputTextFlags_EnterReturnsTrue)) {
                text = buf;
                error = d.syntax ? d.syntax(text) : std::string();
                if (error.empty() && text != cur) {
                    v = text;
                    changed = true;
                }
            }
            if (!error.empty()) ImGui::TextColored(ImVec4(1.f, 0.4f, 0.35f, 1.f), "%s", error.c_str());
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
// [SECTION] Hemisphere widget
bool hemisphere_widget(const ParamDecl& d, ParamTable& t, Dirty& dirty, float diameter, const char* id_suffix) {
    if (d.type != ParamType::Vec2) return param_widget(d, t, dirty, id_suffix);
    const vec2 td = t.get_vec2(d.name);
    const float R = 0.5f * diameter;
    const ImVec2 p0 = ImGui::GetCursorScreenPos(), c(p0.x + R, p0.y + R);
    const std::string id = "##hemi" + t.group().name() + d.name + id_suffix;
    ImGui::InvisibleButton(id.c_str(), ImVec2(diameter, diameter));
    g_last_rect[0] = p0.x, g_last_rect[1] = p0.y, g_last_rect[2] = p0.x + diameter, g_last_rect[3] = p0.y + diameter;
    bool changed = false;
    if (ImGui::IsItemActive()) {  // pressed on the disc: follow the mouse while held
        const ImVec2 m = ImGui::GetIO().MousePos;
        float x = (m.x - c.x) / R, y = -(m.y - c.y) / R;
        const float r = std::sqrt(x * x + y * y);
        if (r > 1.f) x /= r, y /= r;
        const double theta = std::asin(std::min(1.0, double(std::sqrt(x * x + y * y)))) * 180.0 / 3.14159265358979323846;
        double phi = std::atan2(double(y), double(x)) * 180.0 / 3.14159265358979323846;
        if (theta < 1e-6) phi = td.y;  // the zenith: keep the azimuth
        const vec2 nv(float(std::round(theta * 100.0) / 100.0), float(std::round(phi * 100.0) / 100.0));
        if (nv != td) {
            t.set(d.name, std::array<double, 2>{double(nv.x), double(nv.y)});
            dirty.mark(d.cost);
            changed = true;
        }
    }
    // Disc, rings at 30 and 60 degrees, axes, the direction.
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const ImU32 rim = ImGui::GetColorU32(ImGuiCol_Border), fill = ImGui::GetColorU32(ImGuiCol_FrameBg), dot = ImGui::GetColorU32(ImGuiCol_SliderGrabActive);
    dl->AddCircleFilled(c, R, fill, 48);
    dl->AddCircle(c, R, rim, 48);
    for (float deg : {30.f, 60.f}) dl->AddCircle(c, R * std::sin(deg * 3.14159265f / 180.f), rim, 48);
    dl->AddLine(ImVec2(c.x - R, c.y), ImVec2(c.x + R, c.y), rim);
    dl->AddLine(ImVec2(c.x, c.y - R), ImVec2(c.x, c.y + R), rim);
    const vec2 now = t.get_vec2(d.name);
    const float th = now.x * 3.14159265f / 180.f, ph = now.y * 3.14159265f / 180.f;
    const bool below = std::cos(th) < 0.f;
    const float rr = std::fabs(std::sin(th)) * R;
    const ImVec2 q(c.x + rr * std::cos(ph), c.y - rr * std::sin(ph));
    dl->AddLine(c, q, dot, 1.5f);
    if (below) dl->AddCircle(q, 5.f, dot, 12, 2.f);
    else dl->AddCircleFilled(q, 5.f, dot, 12);
    ImGui::SameLine();
    ImGui::BeginGroup();
    ImGui::TextUnformatted(d.name.c_str());
    ImGui::Text("theta %.1f", double(now.x));
    ImGui::Text("phi %.1f", double(now.y));
    if (below) ImGui::TextDisabled("below the horizon");
    ImGui::EndGroup();
    if (ImGui::IsItemHovered() || ImGui::IsItemActive()) {
        ImGui::BeginTooltip();
        ImGui::PushTextWrapPos(ImGui::GetFontSize() * 35.0f);
        ImGui::TextUnformatted(tooltip(t.group(), d).c_str());
        ImGui::PopTextWrapPos();
        ImGui::EndTooltip();
    }
    return changed;
}
// [SECTION] Named widgets and AOV buttons
bool param_widgets(ParamTable& t, Dirty& dirty, std::initializer_list<const char*> names, const char* id_suffix) {
    bool changed = false;
    for (const char* n : names) {
        const ParamDecl* d = t.group().find(n);
        if (d && t.is_used(*d)) changed |= param_widget(*d, t, dirty, id_suffix);
    }
    return changed;
}

bool param_sections(ParamTable& t, Dirty& dirty, const char* id_suffix, const std::function<void(const std::string&)>& inside) {
    bool changed = false;
    std::vector<std::string> shown;
    for (const ParamSection& sec : t.group().sections()) {
        shown.insert(shown.end(), sec.names.begin(), sec.names.end());
        const std::string id = sec.title + "##" + t.group().name() + id_suffix;
        if (!ImGui::TreeNodeEx(id.c_str(), sec.open ? ImGuiTreeNodeFlags_DefaultOpen : 0)) continue;
        for (const std::string& n : sec.names) {
            const ParamDecl* d = t.group().find(n);
            if (d && t.is_used(*d)) changed |= param_widget(*d, t, dirty, id_suffix);
        }
        if (inside) inside(sec.title);
        ImGui::TreePop();
    }
    for (const ParamDecl& d : t.group().decls())
        if (std::find(shown.begin(), shown.end(), d.name) == shown.end() && t.is_used(d)) changed |= param_widget(d, t, dirty, id_suffix);
    return changed;
}

void aov_button(PanelContext& ctx, const std::string& aov, const std::string& help) {
    if (!ctx.aov) return;
    const bool on = *ctx.aov == aov;
    if (on) ImGui::PushStyleColor(ImGuiCol_Button, ImGui::GetStyleColorVec4(ImGuiCol_ButtonActive));
    if (ImGui::SmallButton(aov.c_str())) *ctx.aov = aov;
    if (on) ImGui::PopStyleColor();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", help.c_str());
}

void aov_buttons(PanelContext& ctx, const std::string& technique) {
    const Technique* t = Registry::instance().technique(technique);
    if (!t || !ctx.aov) return;
    const float right = ImGui::GetWindowPos().x + ImGui::GetWindowContentRegionMax().x;
    bool first = true;
    for (const AovDecl& a : t->outputs()) {
        if (a.name == "normal") continue;  // the View menu has it for every technique
        // Buttons on a row while they fit.
        if (!first) {
            const float w = ImGui::CalcTextSize(a.name.c_str()).x + 2.f * ImGui::GetStyle().FramePadding.x;
            if (ImGui::GetItemRectMax().x + ImGui::GetStyle().ItemSpacing.x + w < right) ImGui::SameLine();
        }
        aov_button(ctx, a.name, a.help);
        first = false;
    }
}

const PanelEntry* PanelRegistry::find(const std::string& technique) const {
    for (const PanelEntry& e : entries)
        if (e.technique == technique) return &e;
    return nullptr;
}

int panel_object(const Scene& s, const std::string& technique, int selected) {
    if (selected >= 0 && size_t(selected) < s.objects.size() && s.objects[size_t(selected)].technique == technique) return selected;
    for (size_t i = 0; i < s.objects.size(); ++i)
        if (s.objects[i].technique == technique) return int(i);
    return -1;
}
}  // namespace mesolab::panels
