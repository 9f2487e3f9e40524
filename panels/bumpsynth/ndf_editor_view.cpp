// NDF editor: the ImGui side (the view over the disk with its handles and brush, the controls).
// Everything is drawn with ImDrawList primitives, so it needs no GL texture and runs headless.
#include "core/bumpsynth/bumpsynth.h"
#include "core/bumpsynth/stages.h"
#include "core/error.h"
#include "panels/bumpsynth/ndf_editor.h"

#include <imgui.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace mesolab::panels::ndf_editor {
namespace {

constexpr float kViewExtent = 1.25f;  // the view spans [-1.25, 1.25]² (rotation knobs sit outside the rim)
constexpr float kHandlePick = 10.f;   // pixels
const ImVec4 kErrorColor(1.f, 0.38f, 0.33f, 1.f);
const ImU32 kLobeColor[2] = {IM_COL32(255, 255, 255, 230), IM_COL32(255, 170, 60, 240)};

void text_tooltip(const char* text) {
    if (!ImGui::IsItemHovered()) return;
    ImGui::BeginTooltip();
    ImGui::PushTextWrapPos(ImGui::GetFontSize() * 35.0f);
    ImGui::TextUnformatted(text);
    ImGui::PopTextWrapPos();
    ImGui::EndTooltip();
}

const char* handle_name(const Handle& h, const std::string& kind) {
    if (kind == "phong") return "exponent (the circle is the equivalent width sqrt(2 / (e + 2)))";
    switch (h.kind) {
        case HandleKind::alpha_x: return "alpha_x";
        case HandleKind::alpha_y: return "alpha_y";
        case HandleKind::rotation: return "rotation";
    }
    return "";
}
}  // namespace

void NdfEditor::start_painting(const bumpsynth::Ndf& ndf) {
    NdfImage img = image_from_ndf(ndf);
    const float peak = *std::max_element(img.px.begin(), img.px.end());
    painter_.reset(std::move(img));
    painting_ = true;
    if (peak > 0.f && std::isfinite(peak)) brush.strength = float(std::pow(10.0, std::round(std::log10(0.25 * double(peak)) * 4.0) / 4.0));
}

void NdfEditor::start_empty(int resolution) {
    painter_.reset(NdfImage(std::clamp(resolution, bumpsynth::Ndf::kMinResolution, bumpsynth::Ndf::kMaxResolution)));
    painting_ = true;
    if (!(brush.strength > 0.f)) brush.strength = 1.f;
}

void NdfEditor::apply(Scene& s, int object, Dirty& dirty) {
    try {
        const std::string path = apply_painted(s, object, painter_.image(), dirty);
        note_ = "saved " + path + " (ndf = image)";
        error_.clear();
    } catch (const std::exception& e) {
        error_ = e.what();
    }
}

void NdfEditor::undo_redo(PanelContext& ctx, int object, bool undo) {
    if (undo ? painter_.undo() : painter_.redo()) apply(ctx.scene, object, ctx.dirty);
}

// [SECTION] Draw
void NdfEditor::draw(PanelContext& ctx, int object) {
    if (size_t(object) >= ctx.scene.objects.size()) return;
    SceneObject& o = ctx.scene.objects[size_t(object)];
    const std::string owner = ctx.scene.name + "/" + std::to_string(object) + "/" + o.name;
    if (!owner_.empty() && owner != owner_) {  // another object or scene: start over, keeping the brush, display settings and path field
        NdfEditor fresh;
        fresh.brush = brush;
        fresh.view = view;
        std::memcpy(fresh.path, path, sizeof path);
        *this = std::move(fresh);
    }
    owner_ = owner;
    ImGui::PushID("ndf_editor");

    // The last evaluation's NDF of this object (it may lag behind the parameters while one runs).
    std::shared_ptr<const bumpsynth::Ndf> ndf;
    if (ctx.eval)
        ndf = ctx.eval->get(bumpsynth::stages::ndf, object);
    if (ndf != shown_) {
        shown_ = ndf;
        shown_image_ = ndf ? image_from_ndf(*ndf) : NdfImage{};
    }
    if (painting_)
        ImGui::TextDisabled("painting %dx%d pixels (shown: the painted image)", painter_.image().size, painter_.image().size);
    else if (ndf)
        ImGui::TextDisabled("ndf = %s, %dx%d cells", o.material.get_string("ndf").c_str(), ndf->resolution(), ndf->resolution());
    else
        ImGui::TextDisabled("no tabulated NDF yet (evaluation running or failed)");

    // Display options.
    ImGui::Checkbox("log", &view.log);
    help_marker("Colour by log10 of D over the chosen number of decades below the maximum (off: linear, 0 to the maximum).");
    if (view.log) {
        ImGui::SameLine();
        ImGui::SetNextItemWidth(ImGui::GetFontSize() * 7.f);
        ImGui::SliderFloat("decades", &view.decades, 1.f, 10.f, "%.1f", ImGuiSliderFlags_AlwaysClamp);
        help_marker("Range of the log display: values below max / 10^decades get the lowest colour.");
    }
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 7.f);
    int cm = int(view.map);
    if (ImGui::Combo("colours", &cm, kColorMapNames, IM_ARRAYSIZE(kColorMapNames))) view.map = ColorMap(cm);
    help_marker("Colour map of the NDF view.");

    draw_view(ctx, object, ndf.get());
    if (!painting_) draw_lobe_buttons(ctx, o);
    draw_paint_controls(ctx, object, ndf.get());
    draw_files(ctx, object, ndf.get());

    if (!error_.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, kErrorColor);
        ImGui::TextWrapped("%s", error_.c_str());
        ImGui::PopStyleColor();
    } else if (!note_.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
        ImGui::TextWrapped("%s", note_.c_str());
        ImGui::PopStyleColor();
    }

    // Ctrl+Z / Ctrl+Y (Ctrl+Shift+Z) while painting, when this panel has the focus and no text field does.
    const ImGuiIO& io = ImGui::GetIO();
    if (painting_ && io.KeyCtrl && !io.WantTextInput && ImGui::IsWindowFocused(ImGuiFocusedFlags_RootAndChildWindows) && !painter_.stroking()) {
        const bool z = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Z), false), y = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Y), false);
        if (z && !io.KeyShift) undo_redo(ctx, object, true);
        else if (y || (z && io.KeyShift)) undo_redo(ctx, object, false);
    }
    ImGui::PopID();
}

void NdfEditor::draw_view(PanelContext& ctx, int object, const bumpsynth::Ndf* ndf) {
    SceneObject& o = ctx.scene.objects[size_t(object)];
    const float side = std::clamp(ImGui::GetContentRegionAvail().x, 160.f, 360.f);
    // A child window: its own draw list, so up to 128² cells stay within 16-bit indices.
    ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
    ImGui::BeginChild("view", ImVec2(side, side), false, ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse);
    const ImVec2 p0 = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton("canvas", ImVec2(side, side), ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
    const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive(), activated = ImGui::IsItemActivated();
    cx_ = p0.x + 0.5f * side;
    cy_ = p0.y + 0.5f * side;
    scale_ = 0.5f * side / kViewExtent;
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    const vec2 xy = disk_of(mouse.x, mouse.y);
    auto S = [&](vec2 p) {
        const auto s = screen_of(p);
        return ImVec2(s[0], s[1]);
    };

    // Interaction: strokes while painting, handles otherwise.
    std::vector<Handle> handles = painting_ ? std::vector<Handle>{} : handles_of(o.material);
    int hot = -1;  // the handle under the mouse
    if (!painting_ && (hovered || active)) {
        float best = kHandlePick;
        for (size_t k = 0; k < handles.size(); ++k) {
            const ImVec2 q = S(handles[k].pos);
            const float d = std::hypot(q.x - mouse.x, q.y - mouse.y);
            if (d < best) best = d, hot = int(k);
        }
    }
    if (painting_) {
        if (activated) {
            stroke_erase_ = brush.erase || (ImGui::IsMouseDown(ImGuiMouseButton_Right) && !ImGui::IsMouseDown(ImGuiMouseButton_Left));
            Brush b = brush;
            b.erase = stroke_erase_;
            painter_.begin_stroke(b);
        }
        if (active && painter_.stroking()) painter_.stroke_to(xy);
        if (!active && painter_.stroking() && painter_.end_stroke()) apply(ctx.scene, object, ctx.dirty);
    } else {
        if (activated) dragging_ = hot >= 0 ? std::optional<Handle>(handles[size_t(hot)]) : std::nullopt;
        if (active && dragging_) {
            try {
                drag_handle(o.material, *dragging_, xy, ctx.dirty);
            } catch (const std::exception& e) {
                error_ = e.what();
            }
        }
        if (!active) dragging_.reset();
    }

    // The NDF (or the painted image) as rectangles, equal neighbours in a row merged.
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const ImVec2 c(cx_, cy_);
    dl->AddRectFilled(p0, ImVec2(p0.x + side, p0.y + side), IM_COL32(18, 19, 22, 255));
    const NdfImage& img = painting_ ? painter_.image() : shown_image_;
    const DisplayGrid g = display_grid(img, 128);
    if (g.n > 0) {
        const float cell = 2.f / float(g.n);
        for (int b = 0; b < g.n; ++b) {
            const float y0 = 1.f - float(b) * cell, y1 = y0 - cell;
            int a = 0;
            while (a < g.n) {
                const float v = g.v[size_t(b) * size_t(g.n) + size_t(a)];
                if (std::isnan(v)) {
                    ++a;
                    continue;
                }
                const ImU32 col = color_of(view.map, display_t(view, v, g.vmax));
                int e = a + 1;
                while (e < g.n) {
                    const float w = g.v[size_t(b) * size_t(g.n) + size_t(e)];
                    if (std::isnan(w) || color_of(view.map, display_t(view, w, g.vmax)) != col) break;
                    ++e;
                }
                dl->AddRectFilled(S(vec2(-1.f + float(a) * cell, y0)), S(vec2(-1.f + float(e) * cell, y1)), col);
                a = e;
            }
        }
    } else {
        dl->AddCircleFilled(c, scale_, IM_COL32(40, 42, 48, 255), 64);
        const char* msg = "no NDF to show";
        const ImVec2 ts = ImGui::CalcTextSize(msg);
        dl->AddText(ImVec2(c.x - 0.5f * ts.x, c.y - 0.5f * ts.y), IM_COL32(200, 200, 200, 255), msg);
    }
    // Rim, rings at theta = 30 and 60 degrees, axes.
    const ImU32 guide = IM_COL32(255, 255, 255, 60);
    dl->AddCircle(c, scale_, IM_COL32(255, 255, 255, 140), 96, 1.5f);
    for (float deg : {30.f, 60.f}) dl->AddCircle(c, scale_ * std::sin(radians(deg)), guide, 64);
    dl->AddLine(S({-1.f, 0.f}), S({1.f, 0.f}), guide);
    dl->AddLine(S({0.f, -1.f}), S({0.f, 1.f}), guide);

    // Lobes: the alpha ellipse of each, its axis handles and rotation knob.
    const auto lobes = painting_ ? std::vector<LobeShape>{} : lobes_of(o.material);
    for (size_t k = 0; k < lobes.size(); ++k) {
        const LobeShape& l = lobes[k];
        const float r = radians(l.rotation_deg), cr = std::cos(r), sr = std::sin(r);
        ImVec2 pts[72];
        for (int t = 0; t < 72; ++t) {
            const float u = 2.f * kPi * float(t) / 72.f, ex = l.alpha.x * std::cos(u), ey = l.alpha.y * std::sin(u);
            pts[t] = S(vec2(cr * ex - sr * ey, sr * ex + cr * ey));
        }
        dl->AddPolyline(pts, 72, kLobeColor[k % 2], ImDrawFlags_Closed, 1.5f);
    }
    for (size_t k = 0; k < handles.size(); ++k) {
        const Handle& h = handles[k];
        const ImU32 col = kLobeColor[size_t(h.lobe) % 2];
        const bool big = int(k) == hot || (dragging_ && dragging_->lobe == h.lobe && dragging_->kind == h.kind);
        const ImVec2 q = S(h.pos);
        if (h.kind == HandleKind::rotation) {
            dl->AddLine(S(h.pos * (1.f / glm::length(h.pos))), q, col, 1.f);
            dl->AddCircle(q, big ? 7.f : 5.f, col, 16, 2.f);
        } else {
            dl->AddCircleFilled(q, big ? 6.f : 4.f, col, 12);
            dl->AddCircle(q, big ? 6.f : 4.f, IM_COL32(0, 0, 0, 200), 12, 1.f);
        }
    }
    // The brush and its symmetric images.
    if (painting_ && (hovered || active)) {
        const ImU32 bc = (active ? stroke_erase_ : brush.erase) ? IM_COL32(255, 90, 90, 220) : IM_COL32(255, 255, 255, 220);
        for (vec2 q : symmetric_points(xy, brush.symmetry, brush.fold)) dl->AddCircle(S(q), brush.radius * scale_, bc, 32, 1.f);
    }
    ImGui::EndChild();
    ImGui::PopStyleVar();

    // What is under the mouse.
    if (hovered && !(active && dragging_)) {
        ImGui::BeginTooltip();
        if (!painting_ && hot >= 0) {
            const Handle& h = handles[size_t(hot)];
            if (lobes.size() > 1) ImGui::Text("drag: lobe %d (%s) %s", h.lobe + 1, lobes[size_t(h.lobe)].kind.c_str(), handle_name(h, lobes[size_t(h.lobe)].kind));
            else ImGui::Text("drag: %s", handle_name(h, lobes[size_t(h.lobe)].kind));
        } else if (glm::dot(xy, xy) <= 1.f) {
            const float mz = std::sqrt(std::max(0.f, 1.f - glm::dot(xy, xy)));
            ImGui::Text("x %.3f  y %.3f", double(xy.x), double(xy.y));
            ImGui::Text("normal: theta %.1f deg  phi %.1f deg", double(std::acos(mz) * 180.f / kPi), double(std::atan2(xy.y, xy.x) * 180.f / kPi));
            if (painting_) {
                const int R = img.size, cc = std::clamp(int((xy.x + 1.f) * 0.5f * float(R)), 0, R - 1), rr = std::clamp(int((1.f - xy.y) * 0.5f * float(R)), 0, R - 1);
                ImGui::Text("painted value %.4g (normalised when applied)", double(img.at(cc, rr)));
            } else if (ndf) {
                ImGui::Text("D %.4g sr^-1", double(ndf->eval(xy)));
            }
        } else {
            ImGui::TextUnformatted("outside the disk of normals");
        }
        if (painting_) ImGui::TextDisabled("left: paint, right: erase");
        else if (!handles.empty()) ImGui::TextDisabled("drag the handles: axes set alpha, the outer knobs the rotation");
        ImGui::EndTooltip();
    }

    // Colour bar with its range.
    const ImVec2 b0 = ImGui::GetCursorScreenPos();
    const float bh = ImGui::GetTextLineHeight() * 0.6f;
    ImGui::Dummy(ImVec2(side, bh));
    if (g.vmax > 0.f) {
        ImDrawList* wl = ImGui::GetWindowDrawList();
        for (int k = 0; k < 64; ++k)
            wl->AddRectFilled(ImVec2(b0.x + side * float(k) / 64.f, b0.y), ImVec2(b0.x + side * float(k + 1) / 64.f + 0.5f, b0.y + bh),
                              color_of(view.map, (float(k) + 0.5f) / 64.f));
        text_tooltip("Colour map: left the lowest value shown, right the maximum of the view.");
        if (view.log) ImGui::TextDisabled("%.3g .. %.4g (log, %.1f decades)", double(g.vmax) * std::pow(10.0, -double(view.decades)), double(g.vmax), double(view.decades));
        else ImGui::TextDisabled("0 .. %.4g (linear)", double(g.vmax));
    }
}

void NdfEditor::draw_lobe_buttons(PanelContext& ctx, SceneObject& o) {
    ParamTable& m = o.material;
    ImGui::BeginDisabled(!can_add_lobe(m));
    if (ImGui::Button("Add lobe")) add_lobe(m, ctx.dirty);
    ImGui::EndDisabled();
    help_marker("Adds a lobe (a narrow GGX at weight 0.5) to the NDF: ndf becomes lobes, a weighted sum written in bumpsynth.lobes, "
                "which you can also edit as text, e.g. beckmann(0.08, 0.3) + 0.5 * ggx(0.3, 0.05, 45).");
    ImGui::SameLine();
    ImGui::BeginDisabled(!can_remove_lobe(m));
    if (ImGui::Button("Remove lobe")) remove_lobe(m, ctx.dirty);
    ImGui::EndDisabled();
    help_marker("Removes the last lobe of bumpsynth.lobes; with one lobe left, ndf becomes that lobe (its kind, alpha_x, alpha_y, rotation).");
}

void NdfEditor::draw_paint_controls(PanelContext& ctx, int object, const bumpsynth::Ndf* ndf) {
    SceneObject& o = ctx.scene.objects[size_t(object)];
    if (!painting_) {
        if (ImGui::Button("Paint")) {
            try {
                if (ndf) start_painting(*ndf);
                else start_painting(bumpsynth::ndf_from_material(ctx.scene, o.material));
                error_.clear();
                note_ = "painting: each stroke is saved to " + painted_file_path(ctx.scene, object);
            } catch (const std::exception& e) {
                error_ = e.what();
            }
        }
        help_marker("Paint the NDF: the current table becomes an editable image (one pixel per cell, row 0 at y = +1). When a stroke ends, "
                    "the image is saved as <scene>.<object>.ndf.exr next to the preset (or in the current folder) and the material "
                    "switches to ndf = image with that file.");
        ImGui::SameLine();
        if (ImGui::Button("Paint from empty")) {
            start_empty(int(o.material.get_int("ndf_resolution")));
            error_.clear();
            note_ = "painting: each stroke is saved to " + painted_file_path(ctx.scene, object);
        }
        help_marker("Paint on an empty image of ndf_resolution pixels per side (nothing is applied until the first stroke).");
        return;
    }
    if (ImGui::Button("Stop painting")) {
        painting_ = false;
        note_.clear();
    }
    help_marker("Leave paint mode. The material keeps the last applied image; the undo history is dropped.");
    ImGui::SameLine();
    if (ImGui::Button("Clear")) painter_.replace(NdfImage(painter_.image().size));
    help_marker("Empty the image (one undo step). Nothing is applied until the next stroke: an empty image is no NDF.");
    ImGui::SameLine();
    ImGui::BeginDisabled(!painter_.can_undo());
    if (ImGui::Button("Undo")) undo_redo(ctx, object, true);
    ImGui::EndDisabled();
    help_marker("Undo the last stroke (Ctrl+Z) and apply the image; up to 64 steps.");
    ImGui::SameLine();
    ImGui::BeginDisabled(!painter_.can_redo());
    if (ImGui::Button("Redo")) undo_redo(ctx, object, false);
    ImGui::EndDisabled();
    help_marker("Redo the stroke undone last (Ctrl+Y or Ctrl+Shift+Z) and apply the image.");

    ImGui::SliderFloat("radius", &brush.radius, 0.01f, 1.f, "%.3f", ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
    help_marker("Brush radius in the disk of normals (x, y); the Gaussian falloff reaches 0 there.");
    ImGui::SliderFloat("strength", &brush.strength, 1e-3f, 1e5f, "%.4g", ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
    help_marker("Value one stroke adds (or removes) under the brush centre, in the image's units (D in sr^-1 until the first stroke "
                "renormalises it). Going over a spot again in the same stroke adds nothing more; a new stroke does.");
    ImGui::Checkbox("erase", &brush.erase);
    help_marker("Strokes remove instead of adding (the right mouse button always erases). Values never go below 0.");
    int sym = int(brush.symmetry);
    if (ImGui::Combo("symmetry", &sym, kSymmetryNames, IM_ARRAYSIZE(kSymmetryNames))) brush.symmetry = Symmetry(sym);
    help_marker("Mirror x: also at (-x, y); mirror y: at (x, -y); both: the four images (exactly symmetric results); rotational: N copies "
                "rotated by 360/N degrees about the normal.");
    if (brush.symmetry == Symmetry::rotational) {
        ImGui::SliderInt("N", &brush.fold, 2, 32, "%d", ImGuiSliderFlags_AlwaysClamp);
        help_marker("Number of rotated copies of each dab.");
    }
    ImGui::TextDisabled("%zu undo step%s", painter_.undo_steps(), painter_.undo_steps() == 1 ? "" : "s");
}

void NdfEditor::draw_files(PanelContext& ctx, int object, const bumpsynth::Ndf* ndf) {
    ImGui::InputTextWithHint("file", "NDF image path (EXR, PNG, ...)", path, sizeof path);
    help_marker("Path of an NDF image to load or of the EXR to save; relative paths are relative to the preset's folder (like ndf_image), "
                "or to the current folder for a scene without one.");
    if (ImGui::Button("Load")) {
        try {
            const bumpsynth::Ndf loaded = load_ndf_file(ctx.scene, object, path, ctx.dirty);
            if (painting_) painter_.replace(image_from_ndf(loaded));
            error_.clear();
            note_ = std::string("loaded ") + path + " (ndf = image)";
        } catch (const std::exception& e) {
            error_ = e.what();
        }
    }
    help_marker("Read the image (channels averaged, x right, y up, pixels outside the disk ignored) and set ndf = image, ndf_image = the "
                "path. A file that cannot be read or is no NDF (negative values, no mass in the disk) is reported here and changes nothing.");
    ImGui::SameLine();
    if (ImGui::Button("Save EXR")) {
        try {
            if (!path[0]) throw InputError("enter a path to save the NDF to");
            const std::string full = ctx.scene.resolve(path);
            if (painting_) write_ndf_exr(full, painter_.image());
            else if (ndf) write_ndf_exr(full, image_from_ndf(*ndf));
            else throw InputError("no tabulated NDF to save yet");
            error_.clear();
            note_ = "saved " + full;
        } catch (const std::exception& e) {
            error_ = e.what();
        }
    }
    help_marker("Write the current NDF (the tabulated values, or the painted image while painting) as a one-channel float EXR, atomically "
                "(a temporary file renamed over the target). It reads back as ndf = image.");
}
}  // namespace mesolab::panels::ndf_editor
