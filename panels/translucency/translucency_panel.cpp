// Panel of technique translucency: material and size, the R_d(r) plot per channel (the paper's
// Fig. 2), accuracy settings with the live factor count and memory, blending and response, and
// one-click views of the atlas, the illumination map, the local and global parts, the reference
// and the error.
#include "core/strings.h"
#include "core/translucency/stages.h"
#include "core/technique.h"
#include "core/translucency/separable.h"
#include "core/translucency/translucency.h"
#include "panels/panel.h"

#include <imgui.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace mesolab::panels {
namespace {

using namespace mesolab::translucency;

// R_d(r) per channel, log scale, over the radius holding 99% of the reflectance (Fig. 2).
void rd_plot(const Medium& m) {
    const Dipole d(m);
    const double r_max = std::max(1e-3, d.radius_holding(0.99));
    constexpr int kN = 160;
    double v[3][kN];
    double lo = 1e300, hi = -1e300;
    for (int i = 0; i < kN; ++i) {
        const dvec3 rd = d.Rd(r_max * double(i) / double(kN - 1));
        for (int c = 0; c < 3; ++c) {
            v[c][i] = std::log10(std::max(rd[c], 1e-30));
            lo = std::min(lo, v[c][i]), hi = std::max(hi, v[c][i]);
        }
    }
    lo = std::max(lo, hi - 8.0);
    const ImVec2 size(ImGui::GetContentRegionAvail().x, ImGui::GetFontSize() * 8.f);
    const ImVec2 p0 = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton("##rd", size);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->AddRectFilled(p0, ImVec2(p0.x + size.x, p0.y + size.y), IM_COL32(24, 25, 28, 255));
    const ImU32 col[3] = {IM_COL32(235, 90, 80, 255), IM_COL32(90, 200, 110, 255), IM_COL32(100, 140, 240, 255)};
    for (int c = 0; c < 3; ++c)
        for (int i = 1; i < kN; ++i) {
            auto pt = [&](int k) {
                const float x = p0.x + size.x * float(k) / float(kN - 1);
                const float y = p0.y + size.y * float(1.0 - (std::max(v[c][k], lo) - lo) / std::max(1e-9, hi - lo));
                return ImVec2(x, y);
            };
            dl->AddLine(pt(i - 1), pt(i), col[c], 1.5f);
        }
    char label[128];
    std::snprintf(label, sizeof label, "R_d(r), mm^-2, log10 %.1f..%.1f; r = 0..%.3g mm", lo, hi, r_max);
    dl->AddText(ImVec2(p0.x + 4, p0.y + 2), IM_COL32(200, 200, 200, 255), label);
    if (ImGui::IsItemHovered()) {
        const float f = (ImGui::GetIO().MousePos.x - p0.x) / size.x;
        const double r = std::clamp(double(f), 0.0, 1.0) * r_max;
        const dvec3 rd = d.Rd(r);
        ImGui::SetTooltip("r = %.4g mm\nR_d = %.4g, %.4g, %.4g mm^-2", r, rd.x, rd.y, rd.z);
    }
    const dvec3 R = d.total_reflectance();
    ImGui::Text("total diffuse reflectance %.3f %.3f %.3f", R.x, R.y, R.z);
    ImGui::SameLine();
    help_marker("Jensen et al. 2001's dipole: the fraction of the power entering the surface that leaves it again, per channel. "
                "The mean free path 1/sigma'_t and sigma_tr set how far light travels: compare the plot's range with the object's size in mm.");
}

class TranslucencyPanel final : public TechniquePanel {
public:
    void draw(PanelContext& ctx) override;
    void reset() override { rmse_.clear(); }

private:
    std::string rmse_;  // the last "measure RMSE" result, for this scene
};

void TranslucencyPanel::draw(PanelContext& ctx) {
    const int i = ctx.object;
    SceneObject& o = ctx.scene.objects[size_t(i)];
    ImGui::TextDisabled("%s", o.name.c_str());
    param_sections(o.material, ctx.dirty, "##tr", [&](const std::string& section) {
        if (section != "Material and size") return;
        try {
            const Settings s = Settings::from(o, Settings::Medium_);
            if (ImGui::TreeNodeEx("R_d(r) (Fig. 2)", ImGuiTreeNodeFlags_DefaultOpen)) {
                rd_plot(s.medium);
                ImGui::TreePop();
            }
        } catch (const std::exception& e) {
            ImGui::TextColored(ImVec4(1.f, 0.45f, 0.4f, 1.f), "%s", e.what());
        }
    });

    // A method outside the atlas and vertex pipeline (separable) has no atlas, stages or brute force.
    const Technique* technique = Registry::instance().technique("translucency");
    const Method* method = technique ? technique->method_of(o) : nullptr;
    if (method && !method->shares_paper_pipeline()) {
        if (ImGui::TreeNodeEx("Separable kernel", ImGuiTreeNodeFlags_DefaultOpen)) {
            try {
                const Settings s = Settings::from(o, Settings::Medium_);
                const SeparableKernel& k =
                    *separable_kernel(s.medium, o.material.get_string("separable_profile") == "burley", int(o.material.get_int("separable_taps")));
                ImGui::Text("%zu taps out to %.3g mm (99.5%% of R_total), per pass", k.offset_mm.size(), double(k.reach_mm));
                ImGui::Text("R_total %.3f %.3f %.3f", k.total.x, k.total.y, k.total.z);
            } catch (const std::exception& e) {
                ImGui::TextColored(ImVec4(1.f, 0.45f, 0.4f, 1.f), "%s", e.what());
            }
            aov_buttons(ctx, "translucency");
            ImGui::TreePop();
        }
        return;
    }

    // What the stages hold for this object.
    if (ctx.eval && ImGui::TreeNodeEx("Precomputed", ImGuiTreeNodeFlags_DefaultOpen)) {
        const auto mesh = ctx.eval->get(translucency::stages::mesh, i);
        const auto atlas = ctx.eval->get(translucency::stages::atlas, i);
        const auto F = ctx.eval->get(translucency::stages::factors, i);
        const auto K = ctx.eval->get(translucency::stages::kernels, i);
        if (mesh) ImGui::Text("mesh: %zu vertices, %zu triangles (from %d)", mesh->vertex_count(), mesh->triangle_count(), mesh->input_vertices);
        if (atlas)
            ImGui::Text("atlas: %d chunks, fill %.1f%%, texel %.3g mm", int(atlas->atlas.chunks.size()), 100.0 * atlas->atlas.fill_ratio,
                        atlas->atlas.scale > 0.f ? Settings::from(o, Settings::Scale).mm_per_unit / double(atlas->atlas.scale) : 0.0);
        if (F) ImGui::Text("form factors: %zu (%s)", F->count(), format_bytes(double(F->bytes())).c_str());
        if (K) ImGui::Text("kernels: %zu texels x %d² (%s)", K->texel.size(), K->K, format_bytes(double(K->bytes())).c_str());
        for (const StageName& st : std::vector<StageName>{translucency::stages::mesh, translucency::stages::atlas, translucency::stages::factors})
            for (const StageRun* run : ctx.eval->runs_of(st))
                if (run->object == i)
                    for (const auto& w : run->warnings) ImGui::TextColored(ImVec4(1.f, 0.8f, 0.4f, 1.f), "%s", w.c_str());
        ImGui::TreePop();
    }

    // Views: the AOV shown and the camera (texture mode shows the atlas, one pixel per texel).
    if (ImGui::TreeNodeEx("Views", ImGuiTreeNodeFlags_DefaultOpen)) {
        const bool texture = ctx.scene.camera.get_string("mode") == "texture";
        if (ImGui::SmallButton(texture ? "object" : "atlas")) {
            ctx.scene.camera.set("mode", std::string(texture ? "orbit" : "texture"));
            ctx.dirty.mark(Cost::Redraw);
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("camera.mode: the object, or its texture atlas one pixel per texel");
        aov_buttons(ctx, "translucency");
        // The error's RMSE, measured on demand (the brute force is O(texels²): seconds on large meshes).
        if (ImGui::SmallButton("measure RMSE vs brute force") && ctx.eval) {
            try {
                char b[96];
                std::snprintf(b, sizeof b, "radiosity RMSE / mean: %.4f", radiosity_error(ctx.scene, *ctx.eval, i));
                rmse_ = b;
            } catch (const std::exception& e) {
                rmse_ = e.what();
            }
        }
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("The method's radiosity against the brute-force sum over the same atlas, for the current lights (CPU; the window waits)");
        if (!rmse_.empty()) ImGui::TextUnformatted(rmse_.c_str());
        ImGui::TreePop();
    }
}
}  // namespace

void register_translucency_panel(PanelRegistry& r) { r.add<TranslucencyPanel>("translucency", "Translucency (Lensch et al. 2002)"); }
}  // namespace mesolab::panels
