// Panel of technique cloth: the stitch with a 3D preview, the acquisition and the fit with their
// times, fitted against acquired BRDF slices with the fit's error, and the garment's mip blending
// with one-click views of the mip level, the BRDF index and alpha.
#include "core/strings.h"
#include "core/cloth/stages.h"
#include "core/cloth/cloth.h"
#include "core/technique.h"
#include "panels/panel.h"

#include <imgui.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

namespace mesolab::panels {
namespace {

using namespace mesolab::cloth;

void stage_line(const Evaluation* ev, const StageName& stage, int object) {
    if (!ev) return;
    for (const StageRun* r : ev->runs_of(stage))
        if (r->object == object) {
            ImGui::TextDisabled("%s: %s, %.0f ms", stage.str().c_str(), to_string(r->status), r->ms);
            for (const auto& w : r->warnings) ImGui::TextColored(ImVec4(1.f, 0.8f, 0.4f, 1.f), "%s", w.c_str());
            if (r->status == StageStatus::Failed) ImGui::TextColored(ImVec4(1.f, 0.45f, 0.4f, 1.f), "%s", r->reason.c_str());
        }
}

// [SECTION] Stitch preview: the centre tile's triangles, orthographic, painter's order, drag to turn.
// The view's angles.
struct PreviewView {
    float yaw = 0.6f, pitch = 0.9f;
};
void stitch_preview(const StitchMesh& s, PreviewView& view_angles) {
    float& yaw = view_angles.yaw;
    float& pitch = view_angles.pitch;
    const float side = std::min(ImGui::GetContentRegionAvail().x, ImGui::GetFontSize() * 16.f);
    const ImVec2 p0 = ImGui::GetCursorScreenPos(), size(side, side);
    ImGui::InvisibleButton("##stitch", size);
    if (ImGui::IsItemActive()) {
        yaw += ImGui::GetIO().MouseDelta.x * 0.01f;
        pitch = std::clamp(pitch + ImGui::GetIO().MouseDelta.y * 0.01f, 0.05f, 1.55f);
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("The stitch's centre tile (drag to turn): %zu triangles over 3 x 3 tiles", s.mesh.index.size() / 3);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->AddRectFilled(p0, ImVec2(p0.x + size.x, p0.y + size.y), IM_COL32(24, 25, 28, 255));
    const vec3 centre = 0.5f * (s.lo + s.hi);
    const float extent = std::max({s.hi.x - s.lo.x, s.hi.y - s.lo.y, s.hi.z - s.lo.z}) * 1.2f;
    const float cy = std::cos(yaw), sy = std::sin(yaw), cp = std::cos(pitch), sp = std::sin(pitch);
    // View: turn about z by yaw, then tilt by pitch (0: from the side, pi/2: from above).
    auto view = [&](vec3 p) {
        p -= centre;
        const vec3 a(cy * p.x - sy * p.y, sy * p.x + cy * p.y, p.z);
        return vec3(a.x, cp * a.z - sp * a.y, sp * a.z + cp * a.y);  // x right, y up, z towards the viewer
    };
    const vec3 light = glm::normalize(vec3(0.4f, 0.6f, 0.7f));
    struct Tri {
        float depth;
        ImVec2 p[3];
        ImU32 col;
    };
    std::vector<Tri> tris;
    const auto& m = s.mesh;
    for (size_t t = 0; t + 2 < m.index.size(); t += 3) {
        const uint32_t i0 = m.index[t], i1 = m.index[t + 1], i2 = m.index[t + 2];
        const vec3 c = (m.position[i0] + m.position[i1] + m.position[i2]) / 3.f;
        if (c.x < 0.f || c.y < 0.f || c.x >= s.tile.x || c.y >= s.tile.y) continue;  // the centre tile only
        Tri tri;
        float z = 0.f;
        for (int k = 0; k < 3; ++k) {
            const vec3 v = view(m.position[m.index[t + size_t(k)]]);
            tri.p[k] = ImVec2(p0.x + size.x * (0.5f + v.x / extent), p0.y + size.y * (0.5f - v.y / extent));
            z += v.z;
        }
        const vec3 n = view(centre + glm::normalize(glm::cross(m.position[i1] - m.position[i0], m.position[i2] - m.position[i0])));
        if (n.z <= 0.f) continue;  // back-facing
        tri.depth = z;
        const vec3 col = (s.color.empty() ? vec3(0.8f) : (s.color[i0] + s.color[i1] + s.color[i2]) / 3.f) * (0.25f + 0.75f * std::max(0.f, glm::dot(n, light)));
        auto c8 = [](float x) { return int(std::clamp(std::pow(std::max(x, 0.f), 1.f / 2.2f), 0.f, 1.f) * 255.f + 0.5f); };
        tri.col = IM_COL32(c8(col.x), c8(col.y), c8(col.z), 255);
        tris.push_back(tri);
    }
    std::sort(tris.begin(), tris.end(), [](const Tri& a, const Tri& b) { return a.depth < b.depth; });
    dl->PushClipRect(p0, ImVec2(p0.x + size.x, p0.y + size.y), true);
    for (const Tri& t : tris) dl->AddTriangleFilled(t.p[0], t.p[1], t.p[2], t.col);
    dl->PopClipRect();
}

// [SECTION] BRDF slice: acquired against fitted, one light, every view, at one sample point.
// The slice's light and sample point.
struct SliceChoice {
    int light = 0, point = -1;
};
void brdf_slice(const SampleGrid& g, const BrdfPyramid& p, SliceChoice& choice) {
    int& light = choice.light;
    int& point = choice.point;
    // The light directions of the grid, in order of first appearance.
    std::vector<dvec3> lights;
    for (const dvec3& l : g.l)
        if (std::none_of(lights.begin(), lights.end(), [&](const dvec3& a) { return glm::length(a - l) < 1e-9; })) lights.push_back(l);
    if (lights.empty() || p.level.empty()) return;
    const int points = g.res * g.res;
    if (point < 0 || point >= points) point = (g.res / 2) * g.res + g.res / 2;
    light = std::clamp(light, 0, int(lights.size()) - 1);
    ImGui::SliderInt("light##slice", &light, 0, int(lights.size()) - 1);
    ImGui::SameLine();
    help_marker("Which of the acquisition's light directions the slice shows; the views run along the x axis in the acquisition's order "
                "(a spiral from the zenith down to grazing).");
    ImGui::SliderInt("point##slice", &point, 0, points - 1);
    const dvec3 ld = lights[size_t(light)];
    std::vector<double> acq, fit;
    const ClothBrdf& b = p.level[0][size_t(point)];
    const glm::dmat3& F = p.frame[0][size_t(point)];
    for (size_t i = 0; i < g.l.size(); ++i) {
        if (glm::length(g.l[i] - ld) > 1e-9) continue;
        const dvec3 a = g.f[size_t(point)][i] * g.l[i].z, f = entry_reflectance(b, F, g.l[i], g.v[i]);
        acq.push_back((a.x + a.y + a.z) / 3.0);
        fit.push_back((f.x + f.y + f.z) / 3.0);
    }
    if (acq.size() < 2) return;
    double hi = 1e-12;
    for (size_t i = 0; i < acq.size(); ++i) hi = std::max({hi, acq[i], fit[i]});
    const ImVec2 size(ImGui::GetContentRegionAvail().x, ImGui::GetFontSize() * 8.f);
    const ImVec2 p0 = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton("##slice", size);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->AddRectFilled(p0, ImVec2(p0.x + size.x, p0.y + size.y), IM_COL32(24, 25, 28, 255));
    auto pt = [&](size_t i, double v) { return ImVec2(p0.x + size.x * float(i) / float(acq.size() - 1), p0.y + size.y * float(1.0 - 0.95 * v / hi)); };
    for (size_t i = 1; i < fit.size(); ++i) dl->AddLine(pt(i - 1, fit[i - 1]), pt(i, fit[i]), IM_COL32(240, 180, 80, 255), 1.5f);
    for (size_t i = 0; i < acq.size(); ++i) dl->AddCircleFilled(pt(i, acq[i]), 2.f, IM_COL32(120, 190, 250, 255));
    char label[160];
    std::snprintf(label, sizeof label, "f_r cos(theta_l), mean of RGB, 0..%.3g: acquired (dots), fitted (line)", hi);
    dl->AddText(ImVec2(p0.x + 4, p0.y + 2), IM_COL32(200, 200, 200, 255), label);
    const FitReport& r = p.report[0][size_t(point)];
    std::vector<double> all;
    for (const FitReport& f : p.report[0]) all.push_back(f.rel_rms);
    std::nth_element(all.begin(), all.begin() + long(all.size() / 2), all.end());
    ImGui::Text("this point: relative RMS %.3f, %d rounds%s; level 0 median %.3f", r.rel_rms, r.rounds, r.converged ? "" : " (not converged)",
                all[all.size() / 2]);
}

class ClothPanel final : public TechniquePanel {
public:
    void draw(PanelContext& ctx) override {
        const int i = ctx.object;
        SceneObject& o = ctx.scene.objects[size_t(i)];
        ImGui::TextDisabled("%s", o.name.c_str());
        param_sections(o.material, ctx.dirty, "##cloth", [&](const std::string& section) {
            if (section == "Stitch") {
                if (ctx.eval)
                    if (const auto s = ctx.eval->get(cloth::stages::stitch, i)) stitch_preview(*s, view_);
                stage_line(ctx.eval, cloth::stages::stitch, i);
            } else if (section == "Acquisition") {
                stage_line(ctx.eval, cloth::stages::acquire, i);
            } else if (section == "Fit") {
                stage_line(ctx.eval, cloth::stages::fit, i);
                if (ctx.eval) {
                    const auto g = ctx.eval->get(cloth::stages::acquire, i);
                    const auto p = ctx.eval->get(cloth::stages::fit, i);
                    if (p) ImGui::Text("%zu BRDFs in %zu levels, %s", p->count(), p->level.size(), format_bytes(double(p->bytes())).c_str());
                    if (g && p && g->res == p->res) brdf_slice(*g, *p, slice_);
                }
            } else if (section == "Garment and mip blending") {
                aov_buttons(ctx, "cloth");
            }
        });
    }
    void reset() override { view_ = {}, slice_ = {}; }

private:
    PreviewView view_;
    SliceChoice slice_;
};
}  // namespace

void register_cloth_panel(PanelRegistry& r) { r.add<ClothPanel>("cloth", "Cloth (Daubert et al. 2001)"); }
}  // namespace mesolab::panels
