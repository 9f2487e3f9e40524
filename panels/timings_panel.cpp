// Timings panel: stage statuses of the last evaluation and the profiler's history per path.
#include "panels/app_panels.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/technique.h"

#include <imgui.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace mesolab::panels {

unsigned status_color(StageStatus s) {
    switch (s) {
        case StageStatus::Ran: return IM_COL32(120, 200, 120, 255);
        case StageStatus::Cached: return IM_COL32(110, 170, 235, 255);
        case StageStatus::Stored: return IM_COL32(150, 140, 235, 255);
        case StageStatus::Skipped: return IM_COL32(140, 140, 140, 255);
        case StageStatus::Failed: return IM_COL32(235, 95, 85, 255);
        case StageStatus::Cancelled: return IM_COL32(230, 170, 80, 255);
    }
    return IM_COL32_WHITE;
}

namespace {

constexpr ImGuiTableFlags kTableFlags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV | ImGuiTableFlags_BordersOuterH |
                                        ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingFixedFit | ImGuiTableFlags_Resizable;

void right_aligned(const char* fmt, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, v);
    const float w = ImGui::CalcTextSize(buf).x;
    const float avail = ImGui::GetContentRegionAvail().x;
    if (avail > w) ImGui::SetCursorPosX(ImGui::GetCursorPosX() + avail - w);
    ImGui::TextUnformatted(buf);
}

const char* ms_format(double ms) { return ms < 10.0 ? "%.3f" : ms < 1000.0 ? "%.2f" : "%.0f"; }

const PaperFigure* paper_of(const std::string& profiler_path) {
    static const std::string prefix = "stage/";
    if (profiler_path.rfind(prefix, 0) != 0) return nullptr;
    const StageDecl* d = Registry::instance().stages().find(profiler_path.substr(prefix.size()));
    return d && d->paper ? &*d->paper : nullptr;
}

void stages_table(const Scene& scene, const std::vector<StageRun>& runs, const std::vector<FrameStepRun>& steps) {
    if (!ImGui::BeginTable("##stages", 4, kTableFlags)) return;
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("Stage", ImGuiTableColumnFlags_WidthStretch);
    const float num = ImGui::CalcTextSize("00000.00").x;
    ImGui::TableSetupColumn("Status", ImGuiTableColumnFlags_WidthFixed, ImGui::CalcTextSize("cancelled (?)").x);
    ImGui::TableSetupColumn("ms", ImGuiTableColumnFlags_WidthFixed, num);
    ImGui::TableSetupColumn("Paper ms", ImGuiTableColumnFlags_WidthFixed, ImGui::CalcTextSize("Paper ms").x);
    ImGui::TableHeadersRow();
    for (const StageRun& r : runs) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(r.label(scene).c_str());
        if (ImGui::IsItemHovered()) {
            const StageDecl* d = Registry::instance().stages().find(r.name);
            if (d) ImGui::SetTooltip("%s\nkey %016llx", d->help.c_str(), static_cast<unsigned long long>(r.key));
        }
        ImGui::TableNextColumn();
        ImGui::PushStyleColor(ImGuiCol_Text, status_color(r.status));
        ImGui::TextUnformatted(to_string(r.status));
        ImGui::PopStyleColor();
        if (!r.reason.empty() && ImGui::IsItemHovered()) {
            ImGui::BeginTooltip();
            ImGui::PushTextWrapPos(ImGui::GetFontSize() * 30.f);
            ImGui::TextUnformatted(r.reason.c_str());
            ImGui::PopTextWrapPos();
            ImGui::EndTooltip();
        }
        if (!r.reason.empty()) {
            ImGui::SameLine(0, 2);
            ImGui::TextDisabled("(?)");
        }
        for (const auto& w : r.warnings) {
            // Warnings (e.g. curvature folding the direction triangulation) stay visible.
            ImGui::SameLine(0, 4);
            ImGui::TextColored(ImVec4(1.f, 0.75f, 0.2f, 1.f), "warning");
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", w.c_str());
        }
        ImGui::TableNextColumn();
        if (r.status == StageStatus::Ran || r.status == StageStatus::Cached || r.status == StageStatus::Stored || r.status == StageStatus::Failed) right_aligned(ms_format(r.ms), r.ms);
        ImGui::TableNextColumn();
        const StageDecl* d = Registry::instance().stages().find(r.name);
        if (d && d->paper) {
            right_aligned(ms_format(d->paper->ms), d->paper->ms);
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", d->paper->source.c_str());
        }
    }
    // Frame steps: offscreen work before the last frame, each its own row.
    for (const FrameStepRun& st : steps) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::Text("frame step %s", st.name.c_str());
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("Offscreen work before the frame; reused while its declared inputs are unchanged");
        ImGui::TableNextColumn();
        ImGui::PushStyleColor(ImGuiCol_Text, status_color(st.status));
        ImGui::TextUnformatted(to_string(st.status));
        ImGui::PopStyleColor();
        ImGui::TableNextColumn();
        if (st.status == StageStatus::Ran && std::isfinite(st.ms)) right_aligned(ms_format(st.ms), st.ms);
        ImGui::TableNextColumn();
    }
    if (runs.empty()) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextDisabled("no evaluation yet");
    }
    ImGui::EndTable();
}

void profiler_table(const std::vector<TimingStat>& stats) {
    if (!ImGui::BeginTable("##profiler", 9, kTableFlags)) return;
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("Path", ImGuiTableColumnFlags_WidthStretch);
    const float num = ImGui::CalcTextSize("00000.00").x;
    ImGui::TableSetupColumn("Dev", ImGuiTableColumnFlags_WidthFixed, ImGui::CalcTextSize("GPU").x);
    for (const char* c : {"Last", "Median", "Min", "Max"}) ImGui::TableSetupColumn(c, ImGuiTableColumnFlags_WidthFixed, num);
    ImGui::TableSetupColumn("n", ImGuiTableColumnFlags_WidthFixed, ImGui::CalcTextSize("000").x);
    ImGui::TableSetupColumn("Paper", ImGuiTableColumnFlags_WidthFixed, num);
    ImGui::TableSetupColumn("Ratio", ImGuiTableColumnFlags_WidthFixed, ImGui::CalcTextSize("x0.000").x);
    ImGui::TableHeadersRow();
    for (const TimingStat& s : stats) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(s.path.c_str());
        ImGui::TableNextColumn();
        if (s.device == Device::Gpu) ImGui::TextColored(ImVec4(0.75f, 0.6f, 0.95f, 1.f), "GPU");
        else ImGui::TextUnformatted("CPU");
        for (double v : {s.last, s.median, s.min, s.max}) {
            ImGui::TableNextColumn();
            right_aligned(ms_format(v), v);
        }
        ImGui::TableNextColumn();
        right_aligned("%.0f", double(s.count));
        const PaperFigure* p = paper_of(s.path);
        ImGui::TableNextColumn();
        if (p) {
            right_aligned(ms_format(p->ms), p->ms);
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", p->source.c_str());
        }
        ImGui::TableNextColumn();
        if (p && p->ms > 0) {
            right_aligned("x%.3g", s.median / p->ms);
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("our median / the paper's figure\n%s", p->source.c_str());
        }
    }
    if (stats.empty()) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextDisabled("no samples");
    }
    ImGui::EndTable();
}
}  // namespace

void timings_panel(const Scene& scene, const std::vector<StageRun>& runs, const std::vector<FrameStepRun>& steps, Profiler& profiler,
                   const std::string& note) {
    if (ImGui::Button("Reset")) profiler.clear();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Clear the profiler's history");
    ImGui::SameLine();
    ImGui::TextDisabled("all times in ms; medians over the last %zu samples", profiler.history);
    if (!note.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, IM_COL32(235, 120, 110, 255));
        ImGui::PushTextWrapPos(0.f);
        ImGui::TextUnformatted(note.c_str());
        ImGui::PopTextWrapPos();
        ImGui::PopStyleColor();
    }
    const ImVec2 avail = ImGui::GetContentRegionAvail();
    const float left_w = std::clamp(avail.x * 0.44f, 300.f, 620.f);  // object stages carry their object's name
    if (ImGui::BeginChild("##stages_child", ImVec2(left_w, 0))) {
        ImGui::TextDisabled("Stages of the last evaluation");
        stages_table(scene, runs, steps);
    }
    ImGui::EndChild();
    ImGui::SameLine();
    if (ImGui::BeginChild("##profiler_child", ImVec2(0, 0))) {
        ImGui::TextDisabled("Profiler");
        profiler_table(profiler.stats());
    }
    ImGui::EndChild();
}
}  // namespace mesolab::panels
