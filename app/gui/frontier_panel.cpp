// The window's Frontier view: the current scene's accuracy-time frontier (FrontierRunner,
// app/gui/frontier_view.h) measured in the background with progress and cancel, drawn as a
// log-log plot of error against frame time as the points arrive; hovering a point says its
// setting and figures, clicking it (or its row) loads its knobs into the scene.
#include "app/gui/app.h"

#include <algorithm>
#include <cmath>
#include <imgui.h>

namespace mesolab::gui {

namespace {
// Log-scale axis from the values (a decade of margin at most).
struct LogAxis {
    double lo = 1, hi = 10;
    void fit(const std::vector<double>& v) {
        double a = 1e300, b = 0;
        for (double x : v)
            if (x > 0 && std::isfinite(x)) a = std::min(a, x), b = std::max(b, x);
        if (b <= 0) return;
        lo = std::pow(10.0, std::floor(std::log10(a) * 4.0) / 4.0);
        hi = std::pow(10.0, std::ceil(std::log10(b) * 4.0) / 4.0);
        if (hi <= lo) hi = lo * 10.0;
    }
    float at(double x, float p0, float p1) const { return p0 + (p1 - p0) * float((std::log10(std::max(x, lo)) - std::log10(lo)) / (std::log10(hi) - std::log10(lo))); }
};

std::string settings_text(const FrontierPoint& p) {
    std::string t;
    for (const auto& [k, v] : p.settings) t += (t.empty() ? "" : "\n") + k + " = " + v;
    return t;
}
}  // namespace

void Gui::start_frontier() {
    const UiState::FrontierView& fv = state_.ui.frontier;
    FrontierOptions o;
    o.width = o.height = fv.size;
    o.budget_s = double(fv.budget_min) * 60.0;
    o.truth.spp = fv.spp;
    o.truth.seed = uint64_t(state_.ui.truth.seed);
    o.repeat = 3;
    frontier_.start(state_.doc.scene, o);
}

void Gui::frontier_window() {
    UiState::FrontierView& fv = state_.ui.frontier;
    if (!fv.open) return;
    ImGui::SetNextWindowSize(ImVec2(ImGui::GetFontSize() * 34.f, ImGui::GetFontSize() * 30.f), ImGuiCond_FirstUseEver);
    if (!ImGui::Begin("Frontier", &fv.open)) {
        ImGui::End();
        return;
    }
    const FrontierRunner::Status st = frontier_.status();
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 7.f);
    ImGui::SliderFloat("budget", &fv.budget_min, 0.f, 60.f, "%.1f min", ImGuiSliderFlags_Logarithmic);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("No new setting starts after this long (the truth's time included)");
    ImGui::SameLine();
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 6.f);
    ImGui::SliderInt("size", &fv.size, 16, 512, "%d px");
    ImGui::SameLine();
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 6.f);
    ImGui::SliderInt("truth spp", &fv.spp, 4, 4096, "%d", ImGuiSliderFlags_Logarithmic);
    if (ImGui::Button(st.running ? "Restart" : "Measure")) {
        attempt([&] { start_frontier(); });
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("Every accuracy knob of the scene on a grid around its settings and all together, each timed on the CPU reference and measured "
                          "against the truth at the camera's distance (`mesolab frontier` measures the GPU and several distances)");
    ImGui::SameLine();
    ImGui::BeginDisabled(!st.running);
    if (ImGui::Button("Cancel")) frontier_.cancel();
    ImGui::EndDisabled();
    ImGui::SameLine();
    if (st.running) ImGui::ProgressBar(float(st.fraction), ImVec2(-1.f, 0.f), st.stage.c_str());
    else if (!st.error.empty()) ImGui::TextColored(ImVec4(0.92f, 0.4f, 0.35f, 1.f), "%s", st.error.c_str());
    else if (st.cancelled) ImGui::TextDisabled("cancelled: the points so far");
    else if (st.budget_reached) ImGui::TextDisabled("the budget ended it before every setting");
    else if (!st.scene.empty()) ImGui::TextDisabled("%s: %zu settings", st.scene.c_str(), frontier_.points().size());
    else ImGui::TextDisabled("not measured yet");

    const std::vector<FrontierPoint> pts = frontier_.points();
    // [SECTION] The plot
    const ImVec2 avail = ImGui::GetContentRegionAvail();
    const ImVec2 size(avail.x, std::max(ImGui::GetFontSize() * 10.f, avail.y * 0.6f));
    const ImVec2 p0 = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton("plot", size);
    const bool hovered = ImGui::IsItemHovered();
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const float m = ImGui::GetFontSize() * 2.5f;  // margin for the labels
    const ImVec2 a(p0.x + m, p0.y + 4.f), b(p0.x + size.x - 6.f, p0.y + size.y - m * 0.6f);
    dl->AddRectFilled(a, b, IM_COL32(250, 250, 250, 255));
    dl->AddRect(a, b, IM_COL32(120, 120, 120, 255));
    std::vector<double> xs, ys;
    for (const auto& p : pts) xs.push_back(p.frame_ms), ys.push_back(p.rmse_rel);
    if (st.truth_noise > 0) ys.push_back(2.0 * st.truth_noise);
    LogAxis ax, ay;
    ax.fit(xs), ay.fit(ys);
    auto X = [&](double x) { return ax.at(x, a.x, b.x); };
    auto Y = [&](double y) { return ay.at(y, b.y, a.y); };
    char label[64];
    for (const LogAxis* axis : {&ax, &ay})
        for (double t = std::pow(10.0, std::floor(std::log10(axis->lo))); t <= axis->hi * 1.0001; t *= 10.0) {
            if (t < axis->lo * 0.9999) continue;
            std::snprintf(label, sizeof label, "%g", t);
            if (axis == &ax) {
                dl->AddLine(ImVec2(X(t), a.y), ImVec2(X(t), b.y), IM_COL32(220, 220, 220, 255));
                dl->AddText(ImVec2(X(t) - 8.f, b.y + 2.f), IM_COL32(200, 200, 200, 255), label);
            } else {
                dl->AddLine(ImVec2(a.x, Y(t)), ImVec2(b.x, Y(t)), IM_COL32(220, 220, 220, 255));
                dl->AddText(ImVec2(p0.x + 2.f, Y(t) - 7.f), IM_COL32(200, 200, 200, 255), label);
            }
        }
    dl->AddText(ImVec2(a.x, b.y + ImGui::GetFontSize()), IM_COL32(200, 200, 200, 255), "x: frame ms (stages cached)   y: rmse_rel vs the truth");
    if (st.truth_noise > 0) dl->AddLine(ImVec2(a.x, Y(2.0 * st.truth_noise)), ImVec2(b.x, Y(2.0 * st.truth_noise)), IM_COL32(60, 160, 60, 255), 1.5f);
    std::vector<const FrontierPoint*> front;
    for (const auto& p : pts)
        if (p.on_frontier) front.push_back(&p);
    std::sort(front.begin(), front.end(), [](auto* x, auto* y) { return x->frame_ms < y->frame_ms; });
    for (size_t i = 1; i < front.size(); ++i)
        dl->AddLine(ImVec2(X(front[i - 1]->frame_ms), Y(front[i - 1]->rmse_rel)), ImVec2(X(front[i]->frame_ms), Y(front[i]->rmse_rel)), IM_COL32(40, 90, 200, 255), 2.f);
    const FrontierPoint* nearest = nullptr;
    float best = ImGui::GetFontSize() * 0.6f;
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    for (const auto& p : pts) {
        const ImVec2 c(X(p.frame_ms), Y(p.rmse_rel));
        const ImU32 col = p.on_frontier ? IM_COL32(40, 90, 200, 255) : p.below_noise ? IM_COL32(60, 160, 60, 255) : IM_COL32(230, 120, 30, 255);
        dl->AddRectFilled(ImVec2(c.x - 3.f, c.y - 3.f), ImVec2(c.x + 3.f, c.y + 3.f), col);
        const float d = std::hypot(c.x - mouse.x, c.y - mouse.y);
        if (hovered && d < best) best = d, nearest = &p;
    }
    auto apply = [&](const FrontierPoint& p) {
        attempt([&] {
            for (const auto& [k, v] : p.settings) set(k + "=" + v);
            toast("Loaded the setting " + p.varied + " of the frontier");
        });
    };
    if (nearest) {
        ImGui::SetTooltip("%s\nframe %.3f ms, precompute %.1f ms\nrmse_rel %.4f%s%s\n(click: load its knobs)\n%s", nearest->varied.c_str(), nearest->frame_ms,
                          nearest->precompute_ms, nearest->rmse_rel, nearest->below_noise ? " (below the truth's noise)" : "",
                          nearest->on_frontier ? "\non the frontier" : "", settings_text(*nearest).c_str());
        if (ImGui::IsItemClicked()) apply(*nearest);
    }
    // [SECTION] The frontier's points as rows
    if (ImGui::BeginTable("frontier points", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingStretchProp)) {
        ImGui::TableSetupColumn("setting");
        ImGui::TableSetupColumn("frame ms");
        ImGui::TableSetupColumn("precompute ms");
        ImGui::TableSetupColumn("rmse_rel");
        ImGui::TableHeadersRow();
        for (const FrontierPoint* p : front) {
            ImGui::TableNextRow();
            ImGui::TableNextColumn();
            ImGui::PushID(p);
            if (ImGui::Selectable(p->varied.c_str(), false, ImGuiSelectableFlags_SpanAllColumns)) apply(*p);
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s\n(click: load its knobs)", settings_text(*p).c_str());
            ImGui::PopID();
            ImGui::TableNextColumn();
            ImGui::Text("%.3f", p->frame_ms);
            ImGui::TableNextColumn();
            ImGui::Text("%.1f", p->precompute_ms);
            ImGui::TableNextColumn();
            ImGui::Text(p->below_noise ? "%.4f (noise)" : "%.4f", p->rmse_rel);
        }
        ImGui::EndTable();
    }
    ImGui::End();
}
}  // namespace mesolab::gui
