// mesolab gui: the main window. GLFW + OpenGL 4.5/4.3 core + Dear ImGui 1.86.
//
// [SECTION] Overview
//  - One working Scene (the document of GuiState, app/gui/state.h), edited by the panels
//    (widgets generated from the declarations), the viewport's camera interaction, preset loading
//    and scripts; each edit marks what it costs in the document's Dirty value.
//  - After the UI of each frame, an edited scene is compared with the last completed evaluation
//    by the cache keys of its frame stages. Equal keys (light, camera, material colour...) only
//    redraw: the frame is rendered at once from the last Evaluation, no stage runs. Otherwise the
//    stage graph is evaluated on a worker thread with a snapshot of the scene; a newer edit
//    cancels it and starts again. Meanwhile the last completed frame stays on screen.
//  - Rendering happens on the main thread with gpu::Renderer at the size of the viewport; the
//    display pass (gpu/display.h) turns the chosen AOV into an RGBA8 texture for ImGui::Image.
//  - Scripted mode (--script FILE, or --frames N with screenshots) drives the same loop without
//    vsync and exits with 0, 2 (bad input) or 1 (internal failure).
//
// [SECTION] Parts
//  - app/gui/state.h      GuiState: document, evaluation, frame, UI; their transitions
//  - app/gui/evaluator.h  the evaluation worker; redraw or evaluate, by the stage keys
//  - app/gui/script.h     script files and their commands, stepped once per frame
//  - app/gui/viewport.h   the viewport window, camera input, overlays; rendering, previews
//  - app/gui/window.h     GLFW, the window, ImGui and its style, the default layout
//  - here                 the Gui: the frame loop, panels, menus, dialogs, actions (load, save,
//                         paste, screenshots), errors
//
// [SECTION] Index
//  Small helpers, The application, Errors and notifications, Actions, Scene changes, Frame loop,
//  Script commands, Layout, Menus and windows, Dialogs and shortcuts, Entry point
#include "app/commands.h"
#include "app/gui/evaluator.h"
#include "app/gui/script.h"
#include "app/gui/state.h"
#include "app/gui/truth_view.h"
#include "app/gui/viewport.h"
#include "app/gui/window.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/profile.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/stage.h"
#include "core/technique.h"
#include "gpu/context.h"
#include "gpu/gl.h"
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

// [SECTION] The application
class Gui : private ScriptHost {
public:
    Gui(GLFWwindow* window, ScriptRunner script, bool scripted, std::optional<Scene> initial,
        std::string initial_file, std::string initial_error, uint64_t memory_limit);
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
    void view(const std::string& what, int spp) override;

    // State changes
    void on_scene_changed();
    bool settled() const override;
    bool modified() const { return state_.doc.modified(); }
    void report(const std::string& msg, bool input_error, ErrorOrigin origin);
    template <class F>
    void attempt(F&& f, ErrorOrigin origin = ErrorOrigin::Action);
    void toast(std::string text);
    void update_title();

    GLFWwindow* window_;
    bool scripted_;                // a script drives the loop: no vsync, errors end the run
    Viewport viewport_;            // the renderer and the viewport window
    std::string gl_renderer_;      // GL_RENDERER, for the status bar
    Session session_;              // the stage cache, timings and memory budget of this window
    Evaluator evaluator_;          // the worker thread (evaluates with session_)
    TruthRunner truth_;            // the Truth view's worker (its own session)
    std::optional<Frame> truth_frame_;  // the newest truth it published for the frame on screen
    std::string truth_key_;             // the frame on screen's truth (TruthRunner::key_of)
    uint64_t frames_drawn_ = 0;    // real-time renders and display passes: the truth is asked for again after each
    uint64_t truth_asked_at_ = ~uint64_t(0);
    void update_truth_view(bool display_changed);
    panels::PanelRegistry technique_panels_;                                    // the panels' declarations
    std::map<std::string, std::unique_ptr<panels::TechniquePanel>> panels_;  // this window's panels, by technique
    void reset_panels() {
        for (auto& [t, p] : panels_) p->reset();
    }
    panels::PresetBrowser presets_;

    GuiState state_;  // what the window shows and the user changed

    // Window plumbing
    std::vector<std::string> dropped_;  // paths dropped on the window, handled next frame
    std::string title_;                 // the window title last set
    int busy_frames_ = 3;               // frames to poll (not wait for) events: ImGui settles after one
    ScriptRunner script_;               // scripted mode's commands and first failure
};

Gui::Gui(GLFWwindow* window, ScriptRunner script, bool scripted, std::optional<Scene> initial,
         std::string initial_file, std::string initial_error, uint64_t memory_limit)
    : window_(window), scripted_(scripted), evaluator_(session_), script_(std::move(script)) {
    session_.set_memory_limit(memory_limit);
    gl_renderer_ = gpu::query_gl_info("glfw").renderer;
    panels::register_technique_panels(technique_panels_);
    for (const panels::PanelEntry& e : technique_panels_.entries) panels_[e.technique] = e.make();
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
    reset_panels();
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
    reset_panels();
    toast("Pasted a preset from the clipboard (untitled)");
}

std::string Gui::screenshot_path(bool window) const {
    return "screenshots/" + file_safe(state_.doc.scene.name) + (window ? "-window-" : "-") + timestamp() + ".png";
}

void Gui::screenshot_viewport(const std::string& path) {
    viewport_.screenshot(state_.frame, path, truth_frame_ ? &*truth_frame_ : nullptr, state_.ui);
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

bool Gui::settled() const {
    if (!state_.settled(evaluator_.idle())) return false;
    if (state_.ui.truth.show == UiState::TruthView::Show::RealTime) return true;
    const TruthRunner::Status ts = truth_.status();
    return !ts.error.empty() || (!ts.running && state_.ui.truth.on_screen);
}

void Gui::view(const std::string& what, int spp) {
    using Show = UiState::TruthView::Show;
    UiState::TruthView& tv = state_.ui.truth;
    tv.show = what == "truth" ? Show::Truth : what == "error" ? Show::Error : Show::RealTime;
    if (spp > 0) tv.spp = spp;
    tv.on_screen = false;
    truth_asked_at_ = ~uint64_t(0);
    state_.frame.display_outdated = true;
}

// [SECTION] Frame loop
void Gui::wait_or_poll() {
    const bool shot_pending = state_.ui.window_shot.kind == UiState::WindowShot::Kind::Requested;
    if (scripted_ || busy_frames_ > 0 || evaluator_.busy() || truth_.status().running || state_.ui.toast.visible() || state_.frame.outdated || ImGui::IsAnyMouseDown() || shot_pending) {
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
    ProfilerBinding bind(session_.profiler());  // the main thread's scopes (frames, uploads) time this window's session
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
        session_.profiler().record("gui.frame", ms_since(t0));
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
    session_.profiler().record("gui.ui", ms_since(t0));
}

void Gui::after_ui() {
    if (state_.doc.take_edits()) attempt([&] { on_scene_changed(); });
    const bool interacting = ImGui::IsAnyItemActive();
    bool display_changed = false;
    attempt([&] { viewport_.poll_timings(); }, ErrorOrigin::Render);
    if (state_.eval.last && state_.frame.needs_render(state_.ui.viewport.size, interacting)) {
        attempt([&] { viewport_.render(state_.frame, state_.ui.viewport, *state_.eval.last, interacting && !scripted_); }, ErrorOrigin::Render);
        display_changed = true;
    } else if (state_.frame.shown() && state_.frame.display_outdated) {
        attempt([&] { viewport_.update_display(state_.frame, state_.ui.viewport); }, ErrorOrigin::Render);
        display_changed = true;
    }
    if (display_changed) {
        ++frames_drawn_;
        state_.ui.truth.on_screen = false;
    }
    update_truth_view(display_changed);
    update_title();
}

// The Truth view: the truth of the frame on screen is asked for after each real-time frame (the
// runner starts over only when what the truth reads changed), and shown once it has a pass of
// the frame's size; previews during drags keep the real-time frame.
void Gui::update_truth_view(bool display_changed) {
    UiState::TruthView& tv = state_.ui.truth;
    if (tv.show == UiState::TruthView::Show::RealTime || !state_.frame.shown() || state_.frame.preview()) return;
    if (truth_asked_at_ != frames_drawn_) {
        TruthSettings st;
        st.spp = tv.spp;
        st.seed = uint64_t(tv.seed);
        truth_.want(state_.frame.scene, state_.frame.px.x, state_.frame.px.y, st);
        truth_asked_at_ = frames_drawn_;
        std::string key;
        try {
            key = TruthRunner::key_of(state_.frame.scene, state_.frame.px.x, state_.frame.px.y, st.seed);
        } catch (const std::exception&) {
            // no truth (the status bar says why)
        }
        if (key != truth_key_) truth_frame_.reset();  // another truth: the real-time frame until its first pass
        truth_key_ = std::move(key);
    }
    bool fresh = false;
    while (auto f = truth_.take_frame())
        if (f->key == truth_key_) truth_frame_ = std::move(f->frame), fresh = true;
    if (truth_key_.empty()) truth_frame_.reset();
    (void)display_changed;
    if ((fresh || !tv.on_screen) && truth_frame_ && truth_frame_->width == state_.frame.px.x && truth_frame_->height == state_.frame.px.y)
        attempt([&] { viewport_.show_truth(*truth_frame_, state_.ui); }, ErrorOrigin::Render);
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
    session_.profiler().record("gui.draw", ms_since(t0));
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
    l.tech_windows = techs;
}

// [SECTION] Menus and windows
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
                state_.frame.outdated = true;  // a frame holds radiance and the AOV shown only
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
        ImGui::TextDisabled("Truth (path traced, --backend truth)");
        using Show = UiState::TruthView::Show;
        UiState::TruthView& tv = state_.ui.truth;
        const Show before = tv.show;
        if (ImGui::MenuItem("Real-time", "T", tv.show == Show::RealTime)) tv.show = Show::RealTime;
        if (ImGui::MenuItem("Truth", nullptr, tv.show == Show::Truth)) tv.show = Show::Truth;
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("The scene's truth, refined in the background while you watch (spp and noise in the status bar); a technique without a truth says so there");
        if (ImGui::MenuItem("Error: real-time - truth", nullptr, tv.show == Show::Error)) tv.show = Show::Error;
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("Blue where the real-time frame is darker than the truth, red where brighter; the legend gives the scale");
        ImGui::SetNextItemWidth(ImGui::GetFontSize() * 9.f);
        if (ImGui::SliderInt("Truth samples", &tv.spp, 1, 4096, "%d spp", ImGuiSliderFlags_Logarithmic)) truth_asked_at_ = ~uint64_t(0);
        if (ImGui::MenuItem("Cancel the truth", nullptr, false, truth_.status().running)) truth_.cancel();
        if (tv.show != before) {
            tv.on_screen = false;
            truth_asked_at_ = ~uint64_t(0);
            state_.frame.display_outdated = true;  // back to the real-time frame until the truth is there
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
    if (viewport_.window(state_, r, evaluator_.progress()).cancel_evaluation) cancel_evaluation(state_.eval, evaluator_);
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
    ctx.aov = &state_.ui.viewport.aov;
    const std::string aov_before = state_.ui.viewport.aov;

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
            // The selected object when it uses the technique, else its first object.
            panels::PanelContext own = ctx;
            own.object = panels::panel_object(state_.doc.scene, e->technique, ctx.object);
            if (own.object >= 0) panels_.at(e->technique)->draw(own);
            ImGui::PopItemWidth();
        }
        ImGui::End();
    }
    if (state_.ui.viewport.aov != aov_before) state_.frame.outdated = true;  // a panel picked another view

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
        panels::timings_panel(state_.frame.scene, state_.eval.last ? state_.eval.last->runs : no_runs, viewport_.frame_steps(), session_.profiler(),
                              state_.eval.note);
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
        if (state_.ui.truth.show != UiState::TruthView::Show::RealTime) {
            const TruthRunner::Status ts = truth_.status();
            ImGui::SameLine(0, 24);
            if (!ts.error.empty()) ImGui::TextColored(ImVec4(0.92f, 0.4f, 0.35f, 1.f), "truth: %s", ts.error.c_str());
            else if (ts.running)
                ImGui::TextColored(ImVec4(0.45f, 0.7f, 1.f, 1.f), "truth %d/%d spp, noise %.2f%%, refining %.0f%%", ts.spp, ts.target, 100.0 * ts.noise_rel, 100.0 * ts.fraction);
            else if (ts.cancelled) ImGui::TextColored(ImVec4(0.9f, 0.67f, 0.3f, 1.f), "truth cancelled at %d/%d spp, noise %.2f%%", ts.spp, ts.target, 100.0 * ts.noise_rel);
            else if (ts.spp > 0) ImGui::TextDisabled("truth %d spp, noise %.2f%%", ts.spp, 100.0 * ts.noise_rel);
            if (ts.running) {
                ImGui::SameLine();
                if (ImGui::SmallButton("Cancel truth")) truth_.cancel();
            }
        }
        TimingStat fs{};
        char right[256];
        const bool have = session_.profiler().find("gui.frame", fs);
        std::snprintf(right, sizeof right, "frame %.1f ms  |  %.0f fps  |  %s", have ? fs.median : 0.0, double(ImGui::GetIO().Framerate), gl_renderer_.c_str());
        ImGui::SameLine(ds.x - ImGui::CalcTextSize(right).x - 12.f);
        ImGui::TextDisabled("%s", right);
    }
    ImGui::End();
    ImGui::PopStyleColor();
    ImGui::PopStyleVar(2);
}

// [SECTION] Dialogs and shortcuts
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
    if (!io.KeyCtrl && ImGui::IsKeyPressed(GLFW_KEY_T, false)) {  // real-time -> truth -> error -> real-time
        using Show = UiState::TruthView::Show;
        UiState::TruthView& tv = state_.ui.truth;
        tv.show = tv.show == Show::RealTime ? Show::Truth : tv.show == Show::Truth ? Show::Error : Show::RealTime;
        tv.on_screen = false;
        truth_asked_at_ = ~uint64_t(0);
        state_.frame.display_outdated = true;
    }
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
    Gui gui(window.handle, std::move(script), scripted, std::move(initial), o.preset, initial_error, memory_limit_bytes(o.memory_limit));
    return gui.run();
}
}  // namespace mesolab
