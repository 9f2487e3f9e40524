#pragma once
// The window's application class, shared by its files (the overview: gui.cpp):
//   gui.cpp    the application, errors, actions, scene changes, the frame loop, script commands,
//              the layout and the entry point
//   menus.cpp  the menus, the side windows, the timings and status bar, dialogs and shortcuts
#include "app/commands.h"
#include "app/gui/evaluator.h"
#include "app/gui/script.h"
#include "app/gui/state.h"
#include "app/gui/frontier_view.h"
#include "app/gui/truth_view.h"
#include "app/gui/viewport.h"
#include "app/gui/window.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/profile.h"
#include "core/pack.h"
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

namespace mesolab::gui {

// [SECTION] Small helpers
inline std::string timestamp() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    localtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
    return buf;
}

inline std::string file_safe(const std::string& name) {
    std::string r;
    for (char c : name) r += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.') ? c : '_';
    return r.empty() ? "untitled" : r;
}

// Copy into a fixed text buffer of an ImGui input, truncating, always terminated.
template <size_t N>
inline void copy_text(char (&dst)[N], std::string_view src) {
    const size_t n = std::min(src.size(), N - 1);
    std::memcpy(dst, src.data(), n);
    dst[n] = 0;
}

inline void ignore_imgui_log(void*, const char*, ...) {}


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
    void frontier_window();  // app/gui/frontier_panel.cpp
    void start_frontier();   // measures the scene's frontier with the view's settings
    void status_bar();
    void modals();
    void shortcuts();
    void handle(const panels::PresetRequest& r);

    // Actions (throw InputError; callers report)
    void load(const std::string& path) override;
    void save_to(const std::string& path);
    void save_pack(const std::string& path) override { save_pack_to(path); }
    void save_pack_to(const std::string& path);  // a pack (core/pack.h); the document becomes it
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
    FrontierRunner frontier_;      // the Frontier view's worker (its own workbench)
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

// [SECTION] Errors: run f, reporting an InputError (bad input) or another error where it came from.
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

}  // namespace mesolab::gui
