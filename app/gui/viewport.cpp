// The viewport: the window with the frame, camera input and overlays; rendering and display.
#include "app/gui/viewport.h"
#include "app/gui/truth_view.h"
#include "app/truth_figures.h"
#include "gpu/gl.h"
#include "core/error.h"
#include "core/image.h"
#include "core/render.h"
#include "core/technique.h"
#include "gpu/display.h"
#include "gpu/renderer.h"

#include <epoxy/gl.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace mesolab::gui {
namespace {

ImTextureID texture_id(GLuint tex) { return reinterpret_cast<ImTextureID>(static_cast<intptr_t>(tex)); }

// [SECTION] Camera input
// Orbit (left drag), pan (right or middle drag) and zoom (wheel) of the camera; marks `edits`.
void camera_input(ParamTable& cam, panels::Dirty& edits, ImVec2 size) {
    ImGui::InvisibleButton("##viewport_input", size, ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight | ImGuiButtonFlags_MouseButtonMiddle);
    const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive();
    ImGuiIO& io = ImGui::GetIO();
    const bool texture_mode = cam.get_string("mode") == "texture";
    const ImVec2 d = io.MouseDelta;
    if (active && (d.x != 0.f || d.y != 0.f)) {
        if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
            // Orbit: THETA from +z (clamped off the poles), PHI around z.
            vec2 o = cam.get_vec2("orbit");
            const float theta = std::clamp(o.x - 0.35f * d.y, 0.5f, 179.5f);
            float phi = std::fmod(o.y - 0.35f * d.x, 360.f);
            if (phi > 180.f) phi -= 360.f;
            if (phi < -180.f) phi += 360.f;
            cam.set("orbit", std::array<double, 2>{theta, phi});
            edits.mark(cam.group().find("orbit")->cost);
        } else if (!texture_mode && (ImGui::IsMouseDown(ImGuiMouseButton_Right) || ImGui::IsMouseDown(ImGuiMouseButton_Middle))) {
            // Pan the target in the view plane, one pixel = one pixel's footprint at the target.
            const vec2 o = cam.get_vec2("orbit");
            const vec3 dir = direction_from_degrees(o.x, o.y);  // target -> eye
            const vec3 up0 = std::fabs(dir.z) > 0.999f ? vec3(0.f, 1.f, 0.f) : vec3(0.f, 0.f, 1.f);  // as make_camera
            const vec3 right = glm::normalize(glm::cross(up0, dir));
            const vec3 up = glm::cross(dir, right);
            const float dist = float(cam.get_float("distance"));
            const float px = 2.f * dist * std::tan(radians(float(cam.get_float("fov"))) * 0.5f) / std::max(1.f, size.y);
            const vec3 t = cam.get_vec3("target") - right * (d.x * px) + up * (d.y * px);
            auto clampc = [](float v) { return std::clamp(double(v), -1e6, 1e6); };
            cam.set("target", std::array<double, 3>{clampc(t.x), clampc(t.y), clampc(t.z)});
            edits.mark(cam.group().find("target")->cost);
        }
    }
    if (hovered && io.MouseWheel != 0.f && !texture_mode) {
        const double dist = cam.get_float("distance") * std::pow(1.1, -double(io.MouseWheel));
        const ParamDecl* dd = cam.group().find("distance");
        cam.set("distance", std::clamp(dist, dd->min, dd->max));
        edits.mark(dd->cost);
    }
    if (hovered && !active && !io.WantTextInput) ImGui::SetMouseCursor(ImGuiMouseCursor_Hand);
}

// [SECTION] Overlays
// Over the frame: the error banner, the evaluation progress with Cancel, frame info, the toast.
Viewport::Requests overlays(GuiState& s, const Evaluator::Progress& pr, ImVec2 p0, ImVec2 size) {
    Viewport::Requests req;
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const float pad = 8.f;
    float y = p0.y + pad;

    // Error bar: the last error, the frame behind it stays the last good one.
    if (!s.ui.error.text.empty()) {
        const float w = size.x - 2.f * pad;
        const float wrap = w - 150.f;
        const float text_h = std::min(ImGui::CalcTextSize(s.ui.error.text.c_str(), nullptr, false, wrap).y, ImGui::GetTextLineHeight() * 6.f);
        const float h = text_h + ImGui::GetStyle().WindowPadding.y * 2.f + 2.f;
        ImGui::SetCursorScreenPos(ImVec2(p0.x + pad, y));
        ImGui::PushStyleColor(ImGuiCol_ChildBg, IM_COL32(110, 32, 32, 235));
        ImGui::PushStyleColor(ImGuiCol_Border, IM_COL32(200, 70, 60, 255));
        ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(10, 6));
        if (ImGui::BeginChild("##error_bar", ImVec2(w, h), true, ImGuiWindowFlags_NoScrollbar)) {
            ImGui::PushTextWrapPos(wrap);
            ImGui::TextUnformatted(s.ui.error.text.c_str());
            ImGui::PopTextWrapPos();
            ImGui::SameLine(w - 140.f);
            ImGui::SetCursorPosY(ImGui::GetStyle().WindowPadding.y);
            if (s.ui.error.count > 1) {
                ImGui::TextDisabled("x%d", s.ui.error.count);
                ImGui::SameLine();
            }
            if (ImGui::SmallButton("Copy")) ImGui::SetClipboardText(s.ui.error.text.c_str());
            ImGui::SameLine();
            if (ImGui::SmallButton("Dismiss")) s.ui.dismiss_error();
        }
        ImGui::EndChild();
        ImGui::PopStyleVar();
        ImGui::PopStyleColor(2);
        y += h + pad;
    }

    // Progress of a running evaluation, with Cancel.
    if (pr.running) {
        ImGui::SetCursorScreenPos(ImVec2(p0.x + pad, y));
        ImGui::PushStyleColor(ImGuiCol_ChildBg, IM_COL32(28, 30, 34, 230));
        const float h = ImGui::GetFrameHeight() * 2.f + ImGui::GetStyle().WindowPadding.y * 2.f + ImGui::GetStyle().ItemSpacing.y;
        if (ImGui::BeginChild("##progress", ImVec2(std::min(380.f, size.x - 2.f * pad), h), true, ImGuiWindowFlags_NoScrollbar)) {
            if (pr.stage.empty()) ImGui::TextUnformatted("Evaluating stages");
            else ImGui::Text("Evaluating stages  %s %s", pr.fraction >= 1.0 ? "done:" : "in", pr.stage.c_str());
            ImGui::SameLine(ImGui::GetContentRegionMax().x - ImGui::CalcTextSize("00.0 s").x);
            ImGui::TextDisabled("%.1f s", pr.seconds);
            char label[32];
            std::snprintf(label, sizeof label, "%.0f%%", 100.0 * pr.fraction);
            ImGui::ProgressBar(float(pr.fraction), ImVec2(-ImGui::CalcTextSize("Cancel").x - 24.f, 0), label);
            ImGui::SameLine();
            if (ImGui::Button("Cancel")) req.cancel_evaluation = true;
        }
        ImGui::EndChild();
        ImGui::PopStyleColor();
    }

    // Frame info, top right.
    if (s.frame.shown()) {
        char info[160];
        const char* shown = !s.ui.truth.on_screen ? s.ui.viewport.aov.c_str()
                            : s.ui.truth.show == UiState::TruthView::Show::Error ? "error against the truth" : "truth";
        std::snprintf(info, sizeof info, "%dx%d%s  %s  %.1f ms", s.frame.px.x, s.frame.px.y, s.frame.preview() ? " (preview)" : "", shown, s.frame.render_ms);
        const ImVec2 ts = ImGui::CalcTextSize(info);
        const ImVec2 a(p0.x + size.x - ts.x - pad - 8.f, p0.y + pad + (s.ui.error.text.empty() ? 0.f : y - p0.y - pad));
        dl->AddRectFilled(ImVec2(a.x - 6.f, a.y - 3.f), ImVec2(a.x + ts.x + 6.f, a.y + ts.y + 3.f), IM_COL32(15, 16, 18, 170), 3.f);
        dl->AddText(a, IM_COL32(200, 203, 210, 255), info);
    }

    // The error view's legend, bottom right: blue below the truth, white equal, red above.
    if (s.ui.truth.on_screen && s.ui.truth.show == UiState::TruthView::Show::Error) {
        const float w = 180.f, h = 10.f;
        const float scale = s.ui.truth.error_scale;
        char lo[32], hi[32];
        std::snprintf(lo, sizeof lo, "%+.3g", -double(scale));
        std::snprintf(hi, sizeof hi, "%+.3g", double(scale));
        const char* caption = "real-time - truth (radiance, mean of RGB)";
        const float line = ImGui::GetTextLineHeight();
        const ImVec2 a(p0.x + size.x - w - pad - 8.f, p0.y + size.y - pad - h - 2.f * line - 8.f);
        const float box_w = std::max(w, ImGui::CalcTextSize(caption).x);
        dl->AddRectFilled(ImVec2(a.x - 8.f - (box_w - w), a.y - line - 8.f), ImVec2(a.x + w + 8.f, a.y + h + line + 8.f), IM_COL32(15, 16, 18, 200), 4.f);
        dl->AddText(ImVec2(a.x + w - ImGui::CalcTextSize(caption).x, a.y - line - 4.f), IM_COL32(200, 203, 210, 255), caption);
        const ImU32 blue = IM_COL32(13, 137, 255, 255), white = IM_COL32(255, 255, 255, 255), red = IM_COL32(255, 89, 63, 255);
        dl->AddRectFilledMultiColor(a, ImVec2(a.x + w * 0.5f, a.y + h), blue, white, white, blue);
        dl->AddRectFilledMultiColor(ImVec2(a.x + w * 0.5f, a.y), ImVec2(a.x + w, a.y + h), white, red, red, white);
        dl->AddText(ImVec2(a.x, a.y + h + 2.f), IM_COL32(200, 203, 210, 255), lo);
        dl->AddText(ImVec2(a.x + w * 0.5f - 3.f, a.y + h + 2.f), IM_COL32(200, 203, 210, 255), "0");
        dl->AddText(ImVec2(a.x + w - ImGui::CalcTextSize(hi).x, a.y + h + 2.f), IM_COL32(200, 203, 210, 255), hi);
    }

    // Toast, bottom left, fading out.
    if (!s.ui.toast.text.empty()) {
        const double t = seconds_since(s.ui.toast.t0);
        if (t > 4.0) {
            s.ui.toast.text.clear();
        } else {
            const float alpha = float(std::clamp(4.0 - t, 0.0, 1.0));
            const ImVec2 ts = ImGui::CalcTextSize(s.ui.toast.text.c_str());
            const ImVec2 a(p0.x + pad + 6.f, p0.y + size.y - pad - ts.y - 6.f);
            dl->AddRectFilled(ImVec2(a.x - 8.f, a.y - 5.f), ImVec2(a.x + ts.x + 8.f, a.y + ts.y + 5.f), IM_COL32(40, 90, 170, int(220 * alpha)), 4.f);
            dl->AddText(a, IM_COL32(255, 255, 255, int(255 * alpha)), s.ui.toast.text.c_str());
        }
    }
    return req;
}

}  // namespace

// [SECTION] Reduced-size rendering during drags
ivec2 render_request(ivec2 view, bool dragging, double full_render_ms, bool& reduced) {
    float scale = 1.f;
    if (dragging && full_render_ms > kInteractiveBudgetMs) scale = float(std::clamp(std::sqrt(kInteractiveBudgetMs / full_render_ms), 0.25, 1.0));
    reduced = scale < 1.f;
    return {std::max(16, int(float(view.x) * scale)), std::max(16, int(float(view.y) * scale))};
}

// [SECTION] Viewport
struct Viewport::TruthTexture {
    gpu::Texture texture;
    gpu::TextureSpec spec;
};

Viewport::Viewport() : renderer_(std::make_unique<gpu::Renderer>()), display_(std::make_unique<gpu::DisplayPass>()) {}

Viewport::~Viewport() = default;

Viewport::Requests Viewport::window(GuiState& s, const layout::Rects& r, const Evaluator::Progress& progress) {
    Requests req;
    const ImGuiCond cond = s.ui.layout.relayout ? ImGuiCond_Always : ImGuiCond_FirstUseEver;
    ImGui::SetNextWindowPos(r.view_pos, cond);
    ImGui::SetNextWindowSize(r.view_size, cond);
    ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
    // When the frame covers the whole window, skip its background: on llvmpipe every full layer
    // of blended pixels costs milliseconds.
    const ImGuiWindowFlags bg = s.ui.viewport.image_covers ? ImGuiWindowFlags_NoBackground : 0;
    const bool open = ImGui::Begin("Viewport", nullptr, ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse | ImGuiWindowFlags_NoCollapse | bg);
    ImGui::PopStyleVar();
    s.ui.viewport.image_covers = false;
    if (open) {
        const ImVec2 p0 = ImGui::GetCursorScreenPos();
        const ImVec2 avail = ImGui::GetContentRegionAvail();
        if (avail.x >= 1.f && avail.y >= 1.f) {
            s.ui.viewport.size = {std::max(16, int(avail.x)), std::max(16, int(avail.y))};
            ImDrawList* dl = ImGui::GetWindowDrawList();
            if (s.frame.shown() && display_->valid()) {
                // Fit the frame (texture mode may have its own size), centred, aspect kept.
                const float sx = avail.x / float(s.frame.px.x), sy = avail.y / float(s.frame.px.y);
                const float k = std::min(sx, sy);
                const ImVec2 size(std::floor(float(s.frame.px.x) * k), std::floor(float(s.frame.px.y) * k));
                s.ui.viewport.image_covers = size.x >= avail.x - 1.f && size.y >= avail.y - 1.f;
                if (!s.ui.viewport.image_covers) dl->AddRectFilled(p0, ImVec2(p0.x + avail.x, p0.y + avail.y), IM_COL32(22, 23, 26, 255));
                ImGui::SetCursorScreenPos(ImVec2(std::floor(p0.x + (avail.x - size.x) * 0.5f), std::floor(p0.y + (avail.y - size.y) * 0.5f)));
                ImGui::Image(texture_id(display_->texture()), size, ImVec2(0, 1), ImVec2(1, 0));  // GL rows are bottom-up
            } else {
                dl->AddRectFilled(p0, ImVec2(p0.x + avail.x, p0.y + avail.y), IM_COL32(22, 23, 26, 255));
                const char* msg = progress.running ? "Evaluating stages..." : "No frame yet";
                const ImVec2 ts = ImGui::CalcTextSize(msg);
                dl->AddText(ImVec2(p0.x + (avail.x - ts.x) * 0.5f, p0.y + (avail.y - ts.y) * 0.5f), IM_COL32(150, 153, 160, 255), msg);
            }
            ImGui::SetCursorScreenPos(p0);
            camera_input(s.doc.scene.camera, s.doc.edits, avail);
            req = overlays(s, progress, p0, avail);
        }
    }
    ImGui::End();
    return req;
}

void Viewport::render(FrameState& f, const UiState::Viewport& v, const Evaluation& eval, bool dragging) {
    f.render_started(v.size);
    bool reduced = false;
    const ivec2 size = frame_size(f.scene, eval, render_request(v.size, dragging, f.full_render_ms, reduced));
    const auto t0 = Clock::now();
    // Radiance and the AOV shown (when this scene has it: a newly loaded scene may not).
    std::vector<std::string> aovs;
    for (const auto& a : Registry::instance().aovs(f.scene))
        if (a.name == v.aov) aovs.push_back(a.name);
    renderer_->render(f.scene, eval, size.x, size.y, aovs.empty() ? std::vector<std::string>{"radiance"} : aovs);
    // The frame is not waited for: its cost is what the CPU spent submitting it, or the GPU time
    // of the latest frame whose timings are in (a frame late), whichever is larger.
    const double gpu_ms = renderer_->last_complete_gpu_ms();
    f.rendered(size, reduced, std::isfinite(gpu_ms) ? std::max(ms_since(t0), gpu_ms) : ms_since(t0));
    update_display(f, v);
}

void Viewport::update_display(FrameState& f, const UiState::Viewport& v) {
    f.display_outdated = false;
    const auto& layout = renderer_->layout();
    auto it = std::find_if(layout.begin(), layout.end(), [&](const AovDecl& a) { return a.name == v.aov; });
    if (it == layout.end()) it = layout.begin();  // radiance
    const GLuint tex = renderer_->aov_texture(it->name);
    const bool normal = it->name == "normal";
    display_->run(tex, f.px.x, f.px.y, normal ? gpu::DisplayMode::Normal : gpu::DisplayMode::Color, it->channels,
                  it->name == "radiance" ? std::exp2(v.exposure_ev) : 1.f);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

Image Viewport::truth_image(const Frame& truth, UiState& ui) const {
    if (ui.truth.show != UiState::TruthView::Show::Error) return truth.aov("radiance");
    const Frame rt = renderer_->read_frame();
    const TruthComparison c = compare_to_truth(rt, truth, TruthSettings{});
    ui.truth.error_scale = error_scale(c.error, truth);
    return error_colors(c.error, truth, ui.truth.error_scale);
}

void Viewport::show_truth(const Frame& truth, UiState& ui) {
    const Image image = truth_image(truth, ui);
    const Image* shown = &image;
    // GL rows run bottom-up: flip while packing the RGB floats.
    std::vector<float> rows(size_t(shown->width) * size_t(shown->height) * 3);
    for (int y = 0; y < shown->height; ++y)
        for (int x = 0; x < shown->width; ++x)
            for (int c = 0; c < 3; ++c) rows[(size_t(shown->height - 1 - y) * size_t(shown->width) + size_t(x)) * 3 + size_t(c)] = shown->at(x, y)[c];
    if (!truth_texture_ || truth_texture_->spec.width != shown->width || truth_texture_->spec.height != shown->height) {
        truth_texture_ = std::make_unique<TruthTexture>();
        truth_texture_->spec.format = GL_RGB32F;
        truth_texture_->spec.width = shown->width, truth_texture_->spec.height = shown->height;
        truth_texture_->texture = gpu::make_texture(truth_texture_->spec, {GL_RGB, GL_FLOAT, rows.data()});
    } else {
        gpu::upload_texture(truth_texture_->texture, truth_texture_->spec, 0, {GL_RGB, GL_FLOAT, rows.data()});
    }
    const bool error = ui.truth.show == UiState::TruthView::Show::Error;
    display_->run(truth_texture_->texture.get(), shown->width, shown->height, gpu::DisplayMode::Color, 3, error ? 1.f : std::exp2(ui.viewport.exposure_ev));
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    ui.truth.on_screen = true;
}

const std::vector<FrameStepRun>& Viewport::frame_steps() const { return renderer_->last_steps(); }

void Viewport::poll_timings() {
    if (renderer_) renderer_->poll_timings();
}

void Viewport::screenshot(const FrameState& f, const std::string& path, const Frame* truth, UiState& ui) {
    if (!f.shown()) throw InputError("screenshot " + path + ": no frame rendered yet");
    if (truth && ui.truth.on_screen) {  // what the viewport shows: the truth, or the error's colours
        write_png_srgb(path, truth_image(*truth, ui));
        return;
    }
    const Frame frame = renderer_->read_frame();
    write_png_srgb(path, frame.aov("radiance"));
}
}  // namespace mesolab::gui
