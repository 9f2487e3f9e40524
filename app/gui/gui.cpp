// mesolab gui: the main window. GLFW + OpenGL 4.5/4.3 core + Dear ImGui 1.86.
//
// [SECTION] Overview
//  - One working Scene, edited by the panels (widgets generated from the declarations), the
//    viewport's camera interaction, preset loading and scripts.
//  - After the UI of each frame, a changed scene is compared with the last completed evaluation
//    by the cache keys of its frame stages. Equal keys (light, camera, material colour...) only
//    redraw: the frame is rendered at once from the last Evaluation, no stage runs. Otherwise the
//    stage graph is evaluated on a worker thread with a snapshot of the scene; a newer edit
//    cancels it and starts again. Meanwhile the last completed frame stays on screen.
//  - Rendering happens on the main thread with gpu::Renderer at the size of the viewport; the
//    display pass (gpu/display.h) turns the chosen AOV into an RGBA8 texture for ImGui::Image.
//  - Scripted mode (--script FILE, or --frames N with screenshots) drives the same loop without
//    vsync and exits with 0, 2 (bad input) or 1 (internal failure).
#include "app/commands.h"
#include "app/gui/evaluator.h"
#include "app/gui/script.h"
#include "app/gui/state.h"
#include "app/gui/window.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/profile.h"
#include "core/render.h"
#include "core/scene.h"
#include "core/stage.h"
#include "core/technique.h"
#include "gpu/context.h"
#include "gpu/display.h"
#include "gpu/renderer.h"
#include "panels/app_panels.h"
#include "panels/panel.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <imgui_internal.h>  // ErrorCheckEndFrameRecover: keep running after an exception mid-frame

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <optional>

namespace fs = std::filesystem;

namespace mesolab::gui {
namespace {

// Frame time above which drags render the viewport at a reduced size.
constexpr double kInteractiveBudgetMs = 40.0;

// [SECTION] Small helpers
std::string timestamp() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    localtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
    return buf;
}

std::string file_safe(const std::string& name) {
    std::string r;
    for (char c : name) r += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.') ? c : '_';
    return r.empty() ? "untitled" : r;
}

// Copy into a fixed text buffer of an ImGui input, truncating, always terminated.
template <size_t N>
void copy_text(char (&dst)[N], std::string_view src) {
    const size_t n = std::min(src.size(), N - 1);
    std::memcpy(dst, src.data(), n);
    dst[n] = 0;
}

void ignore_imgui_log(void*, const char*, ...) {}

ImTextureID texture_id(GLuint tex) { return reinterpret_cast<ImTextureID>(static_cast<intptr_t>(tex)); }

// [SECTION] The application
class Gui : private ScriptHost {
public:
    Gui(GLFWwindow* window, ScriptRunner script, bool scripted, std::optional<Scene> initial,
        std::string initial_file, std::string initial_error);
    int run();

private:
    using Modal = UiState::Modal;
    using ErrorOrigin = UiState::ErrorOrigin;

    // Frame phases
    void wait_or_poll();
    void handle_drops();
    void poll_evaluator();
    void build_ui();
    void after_ui();
    void present();

    // UI pieces
    void layout_windows();
    void menu_bar();
    void viewport_window();
    void viewport_overlays(ImVec2 p0, ImVec2 size);
    void camera_input(ImVec2 size);
    void side_windows();
    void timings_window();
    void status_bar();
    void modals();
    void shortcuts();
    void handle(const panels::PresetRequest& r);

    // Actions (throw InputError; callers report)
    void load(const std::string& path) override;
    void save_to(const std::string& path);
    void paste();
    void screenshot_viewport(const std::string& path);
    void capture_window(const std::string& path);
    std::string screenshot_path(bool window) const;

    // Script commands (ScriptHost)
    void set(const std::string& assignment) override;
    void screenshot(const std::string& path) override { screenshot_viewport(path); }
    void request_window_screenshot(const std::string& path) override;
    ShotResult window_screenshot_result() const override;
    void request_size(int w, int h) override;
    bool has_size(int w, int h) const override;

    // State changes
    void on_scene_changed();
    void render_now(bool interacting);
    void update_display();
    bool settled() const override;
    bool modified() const { return state_.doc.modified(); }
    void report(const std::string& msg, bool input_error, ErrorOrigin origin);
    template <class F>
    void attempt(F&& f, ErrorOrigin origin = ErrorOrigin::Action);
    void toast(std::string text);
    void update_title();

    GLFWwindow* window_;
    bool scripted_;
    std::unique_ptr<gpu::Renderer> renderer_;
    std::unique_ptr<gpu::DisplayPass> display_;
    std::string gl_renderer_;
    Evaluator evaluator_;
    panels::PanelRegistry technique_panels_;
    panels::PresetBrowser presets_;

    GuiState state_;

    // Window plumbing
    std::vector<std::string> dropped_;  // paths dropped on the window, handled next frame
    std::string title_;                 // the window title last set
    int busy_frames_ = 3;               // frames to poll (not wait for) events: ImGui settles after one
    ScriptRunner script_;
};

Gui::Gui(GLFWwindow* window, ScriptRunner script, bool scripted, std::optional<Scene> initial,
         std::string initial_file, std::string initial_error)
    : window_(window), scripted_(scripted), script_(std::move(script)) {
    renderer_ = std::make_unique<gpu::Renderer>();
    display_ = std::make_unique<gpu::DisplayPass>();
    gl_renderer_ = gpu::query_gl_info("glfw").renderer;
    panels::register_technique_panels(technique_panels_);
    if (initial) state_.doc.loaded(std::move(*initial), std::move(initial_file));
    else state_.doc.loaded(default_scene(), "");  // the first frame evaluates it
    if (!initial_error.empty()) report(initial_error, true, ErrorOrigin::Action);
    glfwSetWindowUserPointer(window_, this);
    glfwSetDropCallback(window_, [](GLFWwindow* w, int count, const char** paths) {
        auto* self = static_cast<Gui*>(glfwGetWindowUserPointer(w));
        for (int i = 0; i < count; ++i) self->dropped_.emplace_back(paths[i]);
    });
    glfwSwapInterval(scripted_ ? 0 : 1);
    update_title();
}

// [SECTION] Errors and notifications
void Gui::report(const std::string& msg, bool input_error, ErrorOrigin origin) {
    if (scripted_) {
        script_.fail(msg, input_error);
        return;
    }
    std::fprintf(stderr, "mesolab: %s%s\n", origin == ErrorOrigin::Evaluation ? "evaluation failed: " : "", msg.c_str());
    state_.ui.show_error(msg, origin);
}

template <class F>
void Gui::attempt(F&& f, ErrorOrigin origin) {
    try {
        f();
    } catch (const InputError& e) {
        report(e.what(), true, origin);
    } catch (const std::exception& e) {
        report(e.what(), false, origin);
    }
}

void Gui::toast(std::string text) { state_.ui.show_toast(std::move(text)); }

void Gui::update_title() {
    const std::string t = "mesolab - " + (state_.doc.file.empty() ? std::string("untitled") : state_.doc.file) + (modified() ? " *" : "");
    if (t != title_) {
        title_ = t;
        glfwSetWindowTitle(window_, t.c_str());
    }
}

// [SECTION] Actions
void Gui::load(const std::string& path) {
    state_.doc.loaded(load_preset(path), path);  // InputError names the file; the old scene stays
    copy_text(presets_.save_as, path);
    if (!scripted_) toast("Loaded " + path);
}

void Gui::save_to(const std::string& path) {
    if (path.empty()) throw InputError("save: no file name given");
    save_preset(state_.doc.scene, path);
    // Reload, so that relative paths are rebased onto the new file's folder.
    state_.doc.saved_as(load_preset(path), path);
    presets_.rescan();
    toast("Saved " + path);
}

void Gui::paste() {
    const char* text = ImGui::GetClipboardText();
    if (!text || !*text) throw InputError("clipboard: empty (copy a preset's JSON first)");
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        throw InputError(std::string("clipboard: invalid JSON (") + e.what() + ")");
    }
    const std::string base = state_.doc.scene.base_dir.empty() ? fs::current_path().string() : state_.doc.scene.base_dir;
    state_.doc.replaced(scene_from_json(j, "clipboard", base));
    toast("Pasted a preset from the clipboard (untitled)");
}

std::string Gui::screenshot_path(bool window) const {
    return "screenshots/" + file_safe(state_.doc.scene.name) + (window ? "-window-" : "-") + timestamp() + ".png";
}

void Gui::screenshot_viewport(const std::string& path) {
    if (!state_.frame.shown()) throw InputError("screenshot " + path + ": no frame rendered yet");
    const Frame f = renderer_->read_frame();
    write_png_srgb(path, f.aov("radiance"));
}

void Gui::capture_window(const std::string& path) {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    if (w < 1 || h < 1) throw InputError("window-screenshot " + path + ": the window has no area");
    std::vector<uint8_t> px(size_t(w) * size_t(h) * 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
    gpu::check_gl("window screenshot");
    for (size_t i = 3; i < px.size(); i += 4) px[i] = 255;  // the default framebuffer's alpha is meaningless
    write_png_rgba8(path, w, h, px.data(), true);
}

void Gui::handle(const panels::PresetRequest& r) {
    using K = panels::PresetRequest::Kind;
    switch (r.kind) {
        case K::None: break;
        case K::Load: attempt([&] { load(r.path); }); break;
        case K::Save:
            if (state_.doc.file.empty()) {
                state_.ui.open_modal(Modal::SaveAs, presets_.save_as);
            } else {
                attempt([&] { save_to(state_.doc.file); });
            }
            break;
        case K::SaveAs: attempt([&] { save_to(r.path); }); break;
        case K::Copy:
            ImGui::SetClipboardText(scene_to_text(state_.doc.scene).c_str());
            toast("Copied the preset JSON to the clipboard");
            break;
        case K::Paste: attempt([&] { paste(); }); break;
    }
}

// [SECTION] Scene changes: redraw or evaluate
void Gui::on_scene_changed() {
    if (scene_changed(state_.eval, evaluator_, state_.doc.scene) == SceneChange::Redraw) state_.frame.redraw(state_.doc.scene);
}

void Gui::poll_evaluator() {
    while (auto r = poll_evaluation(state_.eval, evaluator_, state_.doc.scene)) {
        if (r->kind == Polled::Kind::Done) {
            state_.frame.redraw(std::move(r->scene));
            state_.ui.clear_error(ErrorOrigin::Evaluation);  // fixed by this edit
        } else if (r->kind == Polled::Kind::Failed) {
            report(r->error, r->input_error, ErrorOrigin::Evaluation);
        }
    }
}

void Gui::render_now(bool interacting) {
    FrameState& f = state_.frame;
    const ivec2 view = state_.ui.viewport.size;
    f.render_started(view);
    // While a widget or the camera is being dragged, a slow renderer (llvmpipe) draws fewer
    // pixels to keep up; the full-size frame follows when the drag ends.
    float scale = 1.f;
    if (interacting && !scripted_ && f.full_render_ms > kInteractiveBudgetMs)
        scale = float(std::clamp(std::sqrt(kInteractiveBudgetMs / f.full_render_ms), 0.25, 1.0));
    const ivec2 req{std::max(16, int(float(view.x) * scale)), std::max(16, int(float(view.y) * scale))};
    const ivec2 size = frame_size(f.scene, *state_.eval.last, req);
    const auto t0 = Clock::now();
    renderer_->render(f.scene, *state_.eval.last, size.x, size.y);
    f.rendered(size, scale < 1.f, ms_since(t0));
    update_display();
}

void Gui::update_display() {
    FrameState& f = state_.frame;
    f.display_outdated = false;
    const auto layout = Registry::instance().aovs(f.scene);
    auto it = std::find_if(layout.begin(), layout.end(), [&](const AovDecl& a) { return a.name == state_.ui.viewport.aov; });
    if (it == layout.end()) it = layout.begin();  // radiance
    const GLuint tex = renderer_->aov_texture(it->name);
    const bool normal = it->name == "normal";
    display_->run(tex, f.px.x, f.px.y, normal ? gpu::DisplayMode::Normal : gpu::DisplayMode::Color, it->channels,
                  it->name == "radiance" ? std::exp2(state_.ui.viewport.exposure_ev) : 1.f);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

bool Gui::settled() const { return state_.settled(evaluator_.idle()); }

// [SECTION] Frame loop
void Gui::wait_or_poll() {
    const bool shot_pending = state_.ui.window_shot.kind == UiState::WindowShot::Kind::Requested;
    if (scripted_ || busy_frames_ > 0 || evaluator_.busy() || state_.ui.toast.visible() || state_.frame.outdated || ImGui::IsAnyMouseDown() || shot_pending) {
        glfwPollEvents();
        if (busy_frames_ > 0) --busy_frames_;
    } else {
        glfwWaitEventsTimeout(0.5);  // idle: wake on input, or twice a second (text cursor)
        busy_frames_ = 2;            // let ImGui settle after an event
    }
}

void Gui::handle_drops() {
    if (dropped_.empty()) return;
    std::vector<std::string> paths;
    paths.swap(dropped_);
    for (const auto& p : paths) {
        if (fs::path(p).extension() == ".json") {
            attempt([&] { load(p); });
            return;
        }
    }
    report("dropped " + paths.front() + ": not a preset (drop a .json file)", true, ErrorOrigin::Action);
}

int Gui::run() {
    for (;;) {
        wait_or_poll();
        const auto t0 = Clock::now();
        if (glfwWindowShouldClose(window_)) {
            if (scripted_) {
                report("the window was closed before the script finished", false, ErrorOrigin::Action);
                break;
            }
            if (modified() && !state_.ui.close_confirmed) {
                glfwSetWindowShouldClose(window_, GLFW_FALSE);
                state_.ui.open_modal(Modal::Close);
            } else {
                break;
            }
        }
        handle_drops();
        poll_evaluator();
        if (scripted_) script_.step(*this);
        if (script_.failure() || (scripted_ && script_.finished())) break;
        build_ui();
        after_ui();
        present();
        Profiler::global().record("gui.frame", ms_since(t0));
        if (script_.failure()) break;
    }
    if (const auto& f = script_.failure()) {
        if (f->input_error) throw InputError(f->message);
        throw std::runtime_error(f->message);
    }
    return 0;
}

// [SECTION] Script commands
void Gui::set(const std::string& assignment) {
    apply_set(state_.doc.scene, assignment);
    state_.doc.edited(Cost::Recompute);  // the keys decide what it costs
}

void Gui::request_window_screenshot(const std::string& path) {
    state_.ui.request_window_shot(path, 2);  // let the panels show the final values
}

ScriptHost::ShotResult Gui::window_screenshot_result() const {
    const UiState::WindowShot& w = state_.ui.window_shot;
    return {w.kind == UiState::WindowShot::Kind::Done, w.kind == UiState::WindowShot::Kind::Failed ? w.error : ""};
}

void Gui::request_size(int w, int h) { glfwSetWindowSize(window_, w, h); }

bool Gui::has_size(int w, int h) const {
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    return fw == w && fh == h;
}

void Gui::build_ui() {
    const auto t0 = Clock::now();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    try {
        layout_windows();
        menu_bar();
        viewport_window();
        side_windows();
        timings_window();
        status_bar();
        modals();
        shortcuts();
    } catch (const std::exception& e) {
        // Close whatever the exception left open, then carry on with the next frame.
        ImGui::ErrorCheckEndFrameRecover(ignore_imgui_log, nullptr);
        report(e.what(), dynamic_cast<const InputError*>(&e) != nullptr, ErrorOrigin::Action);
    }
    ImGui::Render();
    Profiler::global().record("gui.ui", ms_since(t0));
}

void Gui::after_ui() {
    if (state_.doc.take_edits()) attempt([&] { on_scene_changed(); });
    const bool interacting = ImGui::IsAnyItemActive();
    if (state_.eval.last && state_.frame.needs_render(state_.ui.viewport.size, interacting)) {
        attempt([&] { render_now(interacting); }, ErrorOrigin::Render);
    } else if (state_.frame.shown() && state_.frame.display_outdated) {
        attempt([&] { update_display(); }, ErrorOrigin::Render);
    }
    update_title();
}

void Gui::present() {
    const auto t0 = Clock::now();
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, w, h);
    glClearColor(0.08f, 0.085f, 0.095f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    UiState::WindowShot& shot = state_.ui.window_shot;
    if (shot.kind == UiState::WindowShot::Kind::Requested && shot.settle-- <= 0) {
        const std::string path = shot.path;
        try {
            capture_window(path);
            state_.ui.window_shot_done();
            if (!scripted_) toast("Saved " + path);
        } catch (const std::exception& e) {
            state_.ui.window_shot_failed(e.what());
            if (!scripted_) report(e.what(), true, ErrorOrigin::Action);
        }
    }
    glfwSwapBuffers(window_);
    Profiler::global().record("gui.draw", ms_since(t0));
}

// [SECTION] Layout
void Gui::layout_windows() {
    const ImVec2 ds = ImGui::GetIO().DisplaySize;
    std::string techs;
    for (const auto& e : technique_panels_.entries)
        if (state_.doc.scene.uses_technique(e.technique)) techs += e.technique + ";";
    UiState::Layout& l = state_.ui.layout;
    if (ds.x != l.display.x || ds.y != l.display.y || techs != l.tech_windows) l.relayout = true;
    l.display = vec2(ds.x, ds.y);
    state_.ui.layout.tech_windows = techs;
}


void Gui::menu_bar() {
    if (!ImGui::BeginMainMenuBar()) return;
    if (ImGui::BeginMenu("File")) {
        if (ImGui::MenuItem("Open preset...", "Ctrl+O")) state_.ui.open_modal(Modal::Open);
        if (ImGui::MenuItem("Save", "Ctrl+S")) handle({panels::PresetRequest::Kind::Save, state_.doc.file});
        if (ImGui::MenuItem("Save as...", "Ctrl+Shift+S")) {
            state_.ui.open_modal(Modal::SaveAs, presets_.save_as);
        }
        ImGui::Separator();
        if (ImGui::MenuItem("Copy preset JSON to clipboard")) handle({panels::PresetRequest::Kind::Copy, ""});
        if (ImGui::MenuItem("Paste preset JSON from clipboard")) handle({panels::PresetRequest::Kind::Paste, ""});
        ImGui::Separator();
        if (ImGui::MenuItem("Quit", "Ctrl+Q")) glfwSetWindowShouldClose(window_, GLFW_TRUE);
        ImGui::EndMenu();
    }
    if (ImGui::BeginMenu("View")) {
        ImGui::TextDisabled("AOV shown");
        for (const auto& a : Registry::instance().aovs(state_.frame.shown() ? state_.frame.scene : state_.doc.scene)) {
            if (ImGui::MenuItem(a.name.c_str(), nullptr, state_.ui.viewport.aov == a.name)) {
                state_.ui.viewport.aov = a.name;
                state_.frame.display_outdated = true;
            }
            if (ImGui::IsItemHovered() && !a.help.empty()) ImGui::SetTooltip("%s", a.help.c_str());
        }
        ImGui::Separator();
        ImGui::SetNextItemWidth(ImGui::GetFontSize() * 9.f);
        if (ImGui::SliderFloat("Exposure (EV)", &state_.ui.viewport.exposure_ev, -8.f, 8.f, "%+.1f")) state_.frame.display_outdated = true;
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("Display only: scales the radiance shown; screenshots keep the rendered values");
        if (ImGui::MenuItem("Reset exposure", nullptr, false, state_.ui.viewport.exposure_ev != 0.f)) {
            state_.ui.viewport.exposure_ev = 0.f;
            state_.frame.display_outdated = true;
        }
        ImGui::Separator();
        if (ImGui::MenuItem("Reset layout")) state_.ui.layout.relayout = true;
        ImGui::EndMenu();
    }
    if (ImGui::BeginMenu("Screenshot")) {
        if (ImGui::MenuItem("Viewport", "F12", false, state_.frame.shown())) {
            attempt([&] {
                const std::string p = screenshot_path(false);
                screenshot_viewport(p);
                toast("Saved " + p);
            });
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("The radiance AOV of the current frame, 8-bit sRGB PNG, in screenshots/");
        if (ImGui::MenuItem("Window", "Shift+F12")) {
            state_.ui.request_window_shot(screenshot_path(true), 1);  // next frame, once this menu is closed
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("The whole window with its panels, PNG, in screenshots/");
        ImGui::EndMenu();
    }
    const char* version = version_string();
    const float w = ImGui::CalcTextSize(version).x + ImGui::CalcTextSize("mesolab ").x;
    ImGui::SameLine(ImGui::GetWindowWidth() - w - ImGui::GetStyle().WindowPadding.x * 2.f);
    ImGui::TextDisabled("mesolab %s", version);
    ImGui::EndMainMenuBar();
}

void Gui::viewport_window() {
    const layout::Rects r = layout::compute(ImGui::GetIO().DisplaySize);
    const ImGuiCond cond = state_.ui.layout.relayout ? ImGuiCond_Always : ImGuiCond_FirstUseEver;
    ImGui::SetNextWindowPos(r.view_pos, cond);
    ImGui::SetNextWindowSize(r.view_size, cond);
    ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(0, 0));
    // When the frame covers the whole window, skip its background: on llvmpipe every full layer
    // of blended pixels costs milliseconds.
    const ImGuiWindowFlags bg = state_.ui.viewport.image_covers ? ImGuiWindowFlags_NoBackground : 0;
    const bool open = ImGui::Begin("Viewport", nullptr, ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse | ImGuiWindowFlags_NoCollapse | bg);
    ImGui::PopStyleVar();
    state_.ui.viewport.image_covers = false;
    if (open) {
        const ImVec2 p0 = ImGui::GetCursorScreenPos();
        const ImVec2 avail = ImGui::GetContentRegionAvail();
        if (avail.x >= 1.f && avail.y >= 1.f) {
            state_.ui.viewport.size = {std::max(16, int(avail.x)), std::max(16, int(avail.y))};
            ImDrawList* dl = ImGui::GetWindowDrawList();
            if (state_.frame.shown() && display_->valid()) {
                // Fit the frame (texture mode may have its own size), centred, aspect kept.
                const float sx = avail.x / float(state_.frame.px.x), sy = avail.y / float(state_.frame.px.y);
                const float s = std::min(sx, sy);
                const ImVec2 size(std::floor(float(state_.frame.px.x) * s), std::floor(float(state_.frame.px.y) * s));
                state_.ui.viewport.image_covers = size.x >= avail.x - 1.f && size.y >= avail.y - 1.f;
                if (!state_.ui.viewport.image_covers) dl->AddRectFilled(p0, ImVec2(p0.x + avail.x, p0.y + avail.y), IM_COL32(22, 23, 26, 255));
                ImGui::SetCursorScreenPos(ImVec2(std::floor(p0.x + (avail.x - size.x) * 0.5f), std::floor(p0.y + (avail.y - size.y) * 0.5f)));
                ImGui::Image(texture_id(display_->texture()), size, ImVec2(0, 1), ImVec2(1, 0));  // GL rows are bottom-up
            } else {
                dl->AddRectFilled(p0, ImVec2(p0.x + avail.x, p0.y + avail.y), IM_COL32(22, 23, 26, 255));
                const char* msg = evaluator_.busy() ? "Evaluating stages..." : "No frame yet";
                const ImVec2 ts = ImGui::CalcTextSize(msg);
                dl->AddText(ImVec2(p0.x + (avail.x - ts.x) * 0.5f, p0.y + (avail.y - ts.y) * 0.5f), IM_COL32(150, 153, 160, 255), msg);
            }
            ImGui::SetCursorScreenPos(p0);
            camera_input(avail);
            viewport_overlays(p0, avail);
        }
    }
    ImGui::End();
}

void Gui::camera_input(ImVec2 size) {
    ImGui::InvisibleButton("##viewport_input", size, ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight | ImGuiButtonFlags_MouseButtonMiddle);
    const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive();
    ImGuiIO& io = ImGui::GetIO();
    ParamTable& cam = state_.doc.scene.camera;
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
            state_.doc.edits.mark(cam.group().find("orbit")->cost);
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
            state_.doc.edits.mark(cam.group().find("target")->cost);
        }
    }
    if (hovered && io.MouseWheel != 0.f && !texture_mode) {
        const double dist = cam.get_float("distance") * std::pow(1.1, -double(io.MouseWheel));
        const ParamDecl* dd = cam.group().find("distance");
        cam.set("distance", std::clamp(dist, dd->min, dd->max));
        state_.doc.edits.mark(dd->cost);
    }
    if (hovered && !active && !io.WantTextInput) ImGui::SetMouseCursor(ImGuiMouseCursor_Hand);
}

void Gui::viewport_overlays(ImVec2 p0, ImVec2 size) {
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const float pad = 8.f;
    float y = p0.y + pad;

    // Error bar: the last error, the frame behind it stays the last good one.
    if (!state_.ui.error.text.empty()) {
        const float w = size.x - 2.f * pad;
        const float wrap = w - 150.f;
        const float text_h = std::min(ImGui::CalcTextSize(state_.ui.error.text.c_str(), nullptr, false, wrap).y, ImGui::GetTextLineHeight() * 6.f);
        const float h = text_h + ImGui::GetStyle().WindowPadding.y * 2.f + 2.f;
        ImGui::SetCursorScreenPos(ImVec2(p0.x + pad, y));
        ImGui::PushStyleColor(ImGuiCol_ChildBg, IM_COL32(110, 32, 32, 235));
        ImGui::PushStyleColor(ImGuiCol_Border, IM_COL32(200, 70, 60, 255));
        ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(10, 6));
        if (ImGui::BeginChild("##error_bar", ImVec2(w, h), true, ImGuiWindowFlags_NoScrollbar)) {
            ImGui::PushTextWrapPos(wrap);
            ImGui::TextUnformatted(state_.ui.error.text.c_str());
            ImGui::PopTextWrapPos();
            ImGui::SameLine(w - 140.f);
            ImGui::SetCursorPosY(ImGui::GetStyle().WindowPadding.y);
            if (state_.ui.error.count > 1) {
                ImGui::TextDisabled("x%d", state_.ui.error.count);
                ImGui::SameLine();
            }
            if (ImGui::SmallButton("Copy")) ImGui::SetClipboardText(state_.ui.error.text.c_str());
            ImGui::SameLine();
            if (ImGui::SmallButton("Dismiss")) {
                state_.ui.dismiss_error();
            }
        }
        ImGui::EndChild();
        ImGui::PopStyleVar();
        ImGui::PopStyleColor(2);
        y += h + pad;
    }

    // Progress of a running evaluation, with Cancel.
    const Evaluator::Progress pr = evaluator_.progress();
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
            if (ImGui::Button("Cancel")) {
                cancel_evaluation(state_.eval, evaluator_);
            }
        }
        ImGui::EndChild();
        ImGui::PopStyleColor();
    }

    // Frame info, top right.
    if (state_.frame.shown()) {
        char info[160];
        std::snprintf(info, sizeof info, "%dx%d%s  %s  %.1f ms", state_.frame.px.x, state_.frame.px.y, state_.frame.preview() ? " (preview)" : "", state_.ui.viewport.aov.c_str(), state_.frame.render_ms);
        const ImVec2 ts = ImGui::CalcTextSize(info);
        const ImVec2 a(p0.x + size.x - ts.x - pad - 8.f, p0.y + pad + (state_.ui.error.text.empty() ? 0.f : y - p0.y - pad));
        dl->AddRectFilled(ImVec2(a.x - 6.f, a.y - 3.f), ImVec2(a.x + ts.x + 6.f, a.y + ts.y + 3.f), IM_COL32(15, 16, 18, 170), 3.f);
        dl->AddText(a, IM_COL32(200, 203, 210, 255), info);
    }

    // Toast, bottom left, fading out.
    if (!state_.ui.toast.text.empty()) {
        const double t = seconds_since(state_.ui.toast.t0);
        if (t > 4.0) {
            state_.ui.toast.text.clear();
        } else {
            const float alpha = float(std::clamp(4.0 - t, 0.0, 1.0));
            const ImVec2 ts = ImGui::CalcTextSize(state_.ui.toast.text.c_str());
            const ImVec2 a(p0.x + pad + 6.f, p0.y + size.y - pad - ts.y - 6.f);
            dl->AddRectFilled(ImVec2(a.x - 8.f, a.y - 5.f), ImVec2(a.x + ts.x + 8.f, a.y + ts.y + 5.f), IM_COL32(40, 90, 170, int(220 * alpha)), 4.f);
            dl->AddText(a, IM_COL32(255, 255, 255, int(255 * alpha)), state_.ui.toast.text.c_str());
        }
    }
}

void Gui::side_windows() {
    const layout::Rects r = layout::compute(ImGui::GetIO().DisplaySize);
    const ImGuiCond cond = state_.ui.layout.relayout ? ImGuiCond_Always : ImGuiCond_FirstUseEver;
    std::vector<const panels::PanelEntry*> techs;
    for (const auto& e : technique_panels_.entries)
        if (state_.doc.scene.uses_technique(e.technique)) techs.push_back(&e);
    const float scene_h = std::floor(r.body_h * (techs.empty() ? 0.66f : 0.48f));
    const float tech_total = techs.empty() ? 0.f : std::floor(r.body_h * 0.22f);
    const float presets_h = r.body_h - scene_h - tech_total;
    float y = r.top;

    panels::PanelContext ctx{state_.doc.scene, state_.doc.edits, state_.eval.last ? &*state_.eval.last : nullptr, state_.doc.selected_object};

    ImGui::SetNextWindowPos(ImVec2(r.side_x, y), cond);
    ImGui::SetNextWindowSize(ImVec2(r.side_w, scene_h), cond);
    if (ImGui::Begin("Scene")) panels::scene_panel(ctx, state_.doc.file.empty() ? nullptr : &state_.doc.saved);
    ImGui::End();
    y += scene_h;
    state_.doc.selected_object = ctx.object;

    for (const panels::PanelEntry* e : techs) {
        const float h = std::floor(tech_total / float(techs.size()));
        ImGui::SetNextWindowPos(ImVec2(r.side_x, y), cond);
        ImGui::SetNextWindowSize(ImVec2(r.side_w, h), cond);
        y += h;
        const std::string title = e->title + "###technique." + e->technique;
        if (ImGui::Begin(title.c_str())) {
            ImGui::PushItemWidth(-ImGui::GetFontSize() * 8.5f);
            e->draw(ctx);
            ImGui::PopItemWidth();
        }
        ImGui::End();
    }

    ImGui::SetNextWindowPos(ImVec2(r.side_x, y), cond);
    ImGui::SetNextWindowSize(ImVec2(r.side_w, presets_h), cond);
    panels::PresetRequest req;
    if (ImGui::Begin("Presets")) req = panels::presets_panel(presets_, state_.doc.file, modified());
    ImGui::End();
    handle(req);
}

void Gui::timings_window() {
    const layout::Rects r = layout::compute(ImGui::GetIO().DisplaySize);
    const ImGuiCond cond = state_.ui.layout.relayout ? ImGuiCond_Always : ImGuiCond_FirstUseEver;
    ImGui::SetNextWindowPos(r.timings_pos, cond);
    ImGui::SetNextWindowSize(r.timings_size, cond);
    if (ImGui::Begin("Timings")) {
        if (ImGui::Button("Re-evaluate")) {
            // Picks up edits of files on disk (their size and time are in the keys).
            if (!reevaluate(state_.eval, evaluator_, state_.doc.scene)) toast("Up to date: every stage key matches the last evaluation");
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("Evaluate the stage graph again if any key changed (e.g. an input file was edited)");
        ImGui::SameLine();
        if (state_.eval.last) ImGui::TextDisabled("last evaluation %.1f ms, render %.2f ms", state_.eval.last_ms, state_.frame.render_ms);
        ImGui::SameLine();
        static const std::vector<StageRun> no_runs;
        panels::timings_panel(state_.eval.last ? state_.eval.last->runs : no_runs, state_.eval.note);
    }
    ImGui::End();
    state_.ui.layout.relayout = false;
}

void Gui::status_bar() {
    const ImVec2 ds = ImGui::GetIO().DisplaySize;
    const float h = ImGui::GetFrameHeight();
    ImGui::SetNextWindowPos(ImVec2(0, ds.y - h));
    ImGui::SetNextWindowSize(ImVec2(ds.x, h));
    ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, ImVec2(8, 3));
    ImGui::PushStyleVar(ImGuiStyleVar_WindowBorderSize, 0.f);
    ImGui::PushStyleColor(ImGuiCol_WindowBg, IM_COL32(26, 28, 31, 255));
    const ImGuiWindowFlags flags = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                                   ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoBringToFrontOnFocus | ImGuiWindowFlags_NoNav;
    if (ImGui::Begin("##status", nullptr, flags)) {
        ImGui::TextUnformatted(state_.doc.file.empty() ? "untitled" : state_.doc.file.c_str());
        if (modified()) {
            ImGui::SameLine();
            ImGui::TextColored(ImVec4(0.95f, 0.7f, 0.3f, 1.f), "(modified)");
        }
        ImGui::SameLine(0, 24);
        const Evaluator::Progress pr = evaluator_.progress();
        if (pr.running) ImGui::TextColored(ImVec4(0.45f, 0.7f, 1.f, 1.f), "evaluating stages %.1f s", pr.seconds);
        else if (state_.eval.failed()) ImGui::TextColored(ImVec4(0.92f, 0.4f, 0.35f, 1.f), "evaluation failed");
        else if (state_.eval.cancelled()) ImGui::TextColored(ImVec4(0.9f, 0.67f, 0.3f, 1.f), "evaluation cancelled: the frame is out of date");
        else if (state_.eval.last) ImGui::TextDisabled("up to date");
        TimingStat fs{};
        char right[256];
        const bool have = Profiler::global().find("gui.frame", fs);
        std::snprintf(right, sizeof right, "frame %.1f ms  |  %.0f fps  |  %s", have ? fs.median : 0.0, double(ImGui::GetIO().Framerate), gl_renderer_.c_str());
        ImGui::SameLine(ds.x - ImGui::CalcTextSize(right).x - 12.f);
        ImGui::TextDisabled("%s", right);
    }
    ImGui::End();
    ImGui::PopStyleColor();
    ImGui::PopStyleVar(2);
}

void Gui::modals() {
    if (state_.ui.modal == Modal::Open) ImGui::OpenPopup("Open preset");
    if (state_.ui.modal == Modal::SaveAs) ImGui::OpenPopup("Save preset as");
    if (state_.ui.modal == Modal::Close) ImGui::OpenPopup("Unsaved changes");
    state_.ui.modal = Modal::None;
    const ImVec2 centre(ImGui::GetIO().DisplaySize.x * 0.5f, ImGui::GetIO().DisplaySize.y * 0.5f);

    ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
    ImGui::SetNextWindowSize(ImVec2(560, 420), ImGuiCond_Appearing);
    if (ImGui::BeginPopupModal("Open preset")) {
        const bool appearing = ImGui::IsWindowAppearing();
        panels::PresetRequest r = panels::preset_list(presets_, ImGui::GetContentRegionAvail().y - ImGui::GetFrameHeightWithSpacing() * 3.f);
        ImGui::SetNextItemWidth(-1);
        if (appearing) ImGui::SetKeyboardFocusHere();
        const bool enter = ImGui::InputTextWithHint("##open_path", "path/to/preset.json (or pick one above)", state_.ui.modal_path, sizeof state_.ui.modal_path, ImGuiInputTextFlags_EnterReturnsTrue);
        std::string path = state_.ui.modal_path;
        if (path.empty() && presets_.selected >= 0 && presets_.selected < int(presets_.files.size())) path = presets_.files[size_t(presets_.selected)];
        if (r.kind == panels::PresetRequest::Kind::Load) path = r.path;
        const bool go = ImGui::Button("Open", ImVec2(120, 0)) || enter || r.kind == panels::PresetRequest::Kind::Load;
        ImGui::SameLine();
        if (ImGui::Button("Cancel", ImVec2(120, 0)) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) ImGui::CloseCurrentPopup();
        if (go && !path.empty()) {
            bool ok = true;
            try {
                load(path);
            } catch (const std::exception& e) {
                ok = false;
                report(e.what(), true, ErrorOrigin::Action);
            }
            if (ok) {
                state_.ui.modal_path[0] = 0;
                ImGui::CloseCurrentPopup();
            }
        }
        ImGui::EndPopup();
    }

    ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
    if (ImGui::BeginPopupModal("Save preset as", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
        ImGui::TextUnformatted("Path of the preset file (relative to the working directory):");
        ImGui::SetNextItemWidth(480);
        if (ImGui::IsWindowAppearing()) ImGui::SetKeyboardFocusHere();
        const bool enter = ImGui::InputText("##save_path", state_.ui.modal_path, sizeof state_.ui.modal_path, ImGuiInputTextFlags_EnterReturnsTrue);
        const bool exists = fs::exists(state_.ui.modal_path);
        if (exists) ImGui::TextColored(ImVec4(0.95f, 0.7f, 0.3f, 1.f), "The file exists and will be replaced.");
        if (ImGui::Button("Save", ImVec2(120, 0)) || enter) {
            bool ok = true;
            try {
                save_to(state_.ui.modal_path);
            } catch (const std::exception& e) {
                ok = false;
                report(e.what(), true, ErrorOrigin::Action);
            }
            if (ok) ImGui::CloseCurrentPopup();
        }
        ImGui::SameLine();
        if (ImGui::Button("Cancel", ImVec2(120, 0)) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) ImGui::CloseCurrentPopup();
        ImGui::EndPopup();
    }

    ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
    if (ImGui::BeginPopupModal("Unsaved changes", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
        ImGui::Text("%s has unsaved changes.", state_.doc.file.empty() ? "The scene" : state_.doc.file.c_str());
        ImGui::Spacing();
        if (ImGui::Button(state_.doc.file.empty() ? "Save as..." : "Save and quit", ImVec2(140, 0))) {
            ImGui::CloseCurrentPopup();
            if (state_.doc.file.empty()) {
                state_.ui.open_modal(Modal::SaveAs, presets_.save_as);
            } else {
                attempt([&] {
                    save_to(state_.doc.file);
                    state_.ui.close_confirmed = true;
                    glfwSetWindowShouldClose(window_, GLFW_TRUE);
                });
            }
        }
        ImGui::SameLine();
        if (ImGui::Button("Discard and quit", ImVec2(140, 0))) {
            state_.ui.close_confirmed = true;
            glfwSetWindowShouldClose(window_, GLFW_TRUE);
            ImGui::CloseCurrentPopup();
        }
        ImGui::SameLine();
        if (ImGui::Button("Cancel", ImVec2(100, 0)) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) ImGui::CloseCurrentPopup();
        ImGui::EndPopup();
    }
}

void Gui::shortcuts() {
    ImGuiIO& io = ImGui::GetIO();
    if (io.WantTextInput) return;
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_O, false)) state_.ui.open_modal(Modal::Open);
    if (io.KeyCtrl && !io.KeyShift && ImGui::IsKeyPressed(GLFW_KEY_S, false)) handle({panels::PresetRequest::Kind::Save, state_.doc.file});
    if (io.KeyCtrl && io.KeyShift && ImGui::IsKeyPressed(GLFW_KEY_S, false)) {
        state_.ui.open_modal(Modal::SaveAs, presets_.save_as);
    }
    if (io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_Q, false)) glfwSetWindowShouldClose(window_, GLFW_TRUE);
    if (ImGui::IsKeyPressed(GLFW_KEY_F12, false)) {
        if (io.KeyShift) {
            state_.ui.request_window_shot(screenshot_path(true), 0);
        } else if (state_.frame.shown()) {
            attempt([&] {
                const std::string p = screenshot_path(false);
                screenshot_viewport(p);
                toast("Saved " + p);
            });
        }
    }
}
}  // namespace
}  // namespace mesolab::gui

namespace mesolab {
// [SECTION] Entry point
int run_gui(const GuiOptions& o) {
    using namespace gui;
    int w = 0, h = 0;
    parse_size(o.size, w, h);
    if (!o.script.empty() && o.frames > 0) throw InputError("gui: --script and --frames cannot be combined");
    if ((!o.screenshot.empty() || !o.window_screenshot.empty()) && o.frames <= 0)
        throw InputError("gui: --screenshot and --window-screenshot need --frames N (or use a --script)");
    if (o.frames < 0) throw InputError("gui: --frames must be positive");
    const bool scripted = !o.script.empty() || o.frames > 0;
    ScriptRunner script = !o.script.empty() ? ScriptRunner(parse_script(o.script), o.script)
                          : o.frames > 0    ? ScriptRunner(frames_script(o), "")
                                            : ScriptRunner();

    // The preset first: bad input fails before a window opens (scripted), or shows in it.
    std::optional<Scene> initial;
    std::string initial_error;
    if (!o.preset.empty()) {
        try {
            initial = load_preset(o.preset);
        } catch (const InputError& e) {
            if (scripted) throw;
            initial_error = e.what();
        }
    }

    GlfwLibrary glfw;
    Window window(w, h);
    ImGuiSession imgui(window.handle);
    Gui gui(window.handle, std::move(script), scripted, std::move(initial), o.preset, initial_error);
    return gui.run();
}
}  // namespace mesolab
