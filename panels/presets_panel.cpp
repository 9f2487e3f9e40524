// Presets panel: the *.json files under presets/, load / save / save as / clipboard.
#include "panels/app_panels.h"

#include <imgui.h>
#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>

namespace fs = std::filesystem;

namespace mesolab::panels {
namespace {

bool contains_nocase(const std::string& text, const char* needle) {
    if (!*needle) return true;
    const std::string n(needle);
    auto it = std::search(text.begin(), text.end(), n.begin(), n.end(),
                          [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b)); });
    return it != text.end();
}
}  // namespace

void PresetBrowser::rescan() {
    last_scan = ImGui::GetTime();
    const std::string keep = selected >= 0 && selected < int(files.size()) ? files[size_t(selected)] : "";
    files.clear();
    std::error_code ec;
    if (fs::is_directory(root, ec)) {
        for (auto it = fs::recursive_directory_iterator(root, fs::directory_options::skip_permission_denied, ec);
             !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
            std::error_code ec2;
            if (it->is_regular_file(ec2) && it->path().extension() == ".json") files.push_back(it->path().generic_string());
        }
    }
    std::sort(files.begin(), files.end());
    auto found = std::find(files.begin(), files.end(), keep);
    selected = found == files.end() ? -1 : int(found - files.begin());
}

PresetRequest preset_list(PresetBrowser& b, float height) {
    PresetRequest req;
    if (ImGui::GetTime() - b.last_scan > 2.0) b.rescan();
    ImGui::SetNextItemWidth(-ImGui::GetFrameHeight() - ImGui::GetStyle().ItemSpacing.x);
    ImGui::InputTextWithHint("##filter", "Filter presets (or drop a .json on the window)", b.filter, sizeof b.filter);
    ImGui::SameLine();
    if (ImGui::Button("R", ImVec2(ImGui::GetFrameHeight(), 0))) b.rescan();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Rescan %s/", b.root.c_str());
    if (ImGui::BeginChild("##preset_files", ImVec2(0, height), true)) {
        int shown = 0;
        for (size_t i = 0; i < b.files.size(); ++i) {
            const std::string& f = b.files[i];
            if (!contains_nocase(f, b.filter)) continue;
            ++shown;
            const std::string rel = f.size() > b.root.size() + 1 && f.compare(0, b.root.size(), b.root) == 0 ? f.substr(b.root.size() + 1) : f;
            if (ImGui::Selectable(rel.c_str(), b.selected == int(i), ImGuiSelectableFlags_AllowDoubleClick)) {
                b.selected = int(i);
                if (ImGui::IsMouseDoubleClicked(0)) req = {PresetRequest::Kind::Load, f};
            }
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s\nDouble-click to load", f.c_str());
        }
        ImGui::PushTextWrapPos(0.f);
        if (b.files.empty()) ImGui::TextDisabled("No preset under %s/ (relative to the working directory)", b.root.c_str());
        else if (!shown) ImGui::TextDisabled("No preset matches the filter");
        ImGui::PopTextWrapPos();
    }
    ImGui::EndChild();
    return req;
}

PresetRequest presets_panel(PresetBrowser& b, const std::string& current_file, bool modified) {
    PresetRequest req;
    ImGui::TextDisabled("File");
    ImGui::SameLine();
    ImGui::TextUnformatted(current_file.empty() ? "(untitled)" : current_file.c_str());
    if (modified) {
        ImGui::SameLine();
        ImGui::TextColored(ImVec4(0.95f, 0.7f, 0.3f, 1.f), "modified");
    }

    const float list_h = std::max(ImGui::GetTextLineHeightWithSpacing() * 3.f,
                                  ImGui::GetContentRegionAvail().y - ImGui::GetFrameHeightWithSpacing() * 3.f);
    PresetRequest picked = preset_list(b, list_h);
    if (picked.kind != PresetRequest::Kind::None) req = picked;

    const bool has_sel = b.selected >= 0 && b.selected < int(b.files.size());
    ImGui::BeginDisabled(!has_sel);
    if (ImGui::Button("Load")) req = {PresetRequest::Kind::Load, b.files[size_t(b.selected)]};
    ImGui::EndDisabled();
    ImGui::SameLine();
    if (ImGui::Button("Save")) req = {PresetRequest::Kind::Save, current_file};
    if (ImGui::IsItemHovered()) ImGui::SetTooltip(current_file.empty() ? "Untitled: give it a path below" : "Overwrite %s (atomic)", current_file.c_str());
    ImGui::SameLine();
    if (ImGui::Button("Copy JSON")) req = {PresetRequest::Kind::Copy, ""};
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Copy the preset JSON to the clipboard");
    ImGui::SameLine();
    if (ImGui::Button("Paste")) req = {PresetRequest::Kind::Paste, ""};
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Replace the scene with preset JSON from the clipboard");

    if (!b.save_as[0]) {
        const std::string def = current_file.empty() ? b.root + "/untitled.json" : current_file;
        std::strncpy(b.save_as, def.c_str(), sizeof b.save_as - 1);
    }
    ImGui::SetNextItemWidth(-ImGui::CalcTextSize("Save as").x - ImGui::GetStyle().FramePadding.x * 2.f - ImGui::GetStyle().ItemSpacing.x);
    const bool enter = ImGui::InputText("##save_as", b.save_as, sizeof b.save_as, ImGuiInputTextFlags_EnterReturnsTrue);
    ImGui::SameLine();
    if (ImGui::Button("Save as") || enter) req = {PresetRequest::Kind::SaveAs, b.save_as};
    return req;
}
}  // namespace mesolab::panels
