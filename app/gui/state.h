#pragma once
// [SECTION] The GUI's state
// One value, GuiState, in four parts; each part changes through the transitions declared with it.
//  - Document: the scene being edited, the scene as saved and its file, the edits not yet handed
//    to the evaluation.
//  - EvalState (app/gui/evaluator.h): idle / evaluating / failed / cancelled, the last good
//    evaluation and its stage keys.
//  - FrameState: none / preview / full: the frame on screen, the scene it shows, its size.
//  - UiState: the dialog to open, the toast, the error banner, a window screenshot under way,
//    what the viewport shows and where the windows go.
// The Gui (app/gui/gui.cpp) owns the window, the worker and the renderer and acts on this state;
// nothing here needs a window.
#include "app/gui/clock.h"
#include "app/gui/evaluator.h"
#include "core/math.h"
#include "core/scene.h"
#include "panels/panel.h"

#include <string>
#include <vector>

namespace mesolab::gui {

// [SECTION] Document
struct Document {
    // The scene being edited: by the panels, the viewport's camera, scripts, loading, pasting.
    Scene scene;
    // The scene as last loaded or saved: tells whether there are unsaved changes (the title's *,
    // the close prompt) and takes the Scene panel back to the file's camera.
    Scene saved;
    std::string file;         // "" while untitled
    int selected_object = 0;  // the object the Scene panel edits
    // What the edits since the evaluation last saw the scene cost (panels, camera, scripts; a new
    // scene counts as a recompute). Taken once per frame, after the UI.
    panels::Dirty edits;

    bool modified() const { return !(scene == saved); }

    // Transitions
    // A file was loaded ("" for the default scene): it is the scene and its saved state.
    void loaded(Scene s, std::string path);
    // The scene was saved as `path` and read back (relative paths rebased on its folder).
    void saved_as(Scene s, std::string path);
    // A scene from elsewhere (the clipboard): untitled, and unsaved against the last file.
    void replaced(Scene s);
    // Edits made directly on `scene` (a script's `set`).
    void edited(Cost c) { edits.mark(c); }
    // Whether there were edits since the last call.
    bool take_edits();
};

// [SECTION] Frame
struct FrameState {
    enum class Kind {
        None,     // nothing drawn yet
        Preview,  // drawn at a reduced size while a widget or the camera is dragged
        Full,     // drawn at the viewport's size
    };
    Kind kind = Kind::None;
    // The scene drawn (or to draw while `outdated`): always the one the last evaluation holds for,
    // so it lags behind the document while a recompute-cost edit is evaluated.
    Scene scene;
    bool outdated = false;          // `scene` or the evaluation changed since the frame was drawn
    bool display_outdated = false;  // only the display pass must run again (AOV, exposure)
    ivec2 px{0, 0};                 // the frame's size in pixels
    ivec2 view{0, 0};               // the viewport size it was drawn for
    double render_ms = 0;           // the last render
    double full_render_ms = 0;      // the last full-size render: whether drags draw previews

    bool shown() const { return kind != Kind::None; }
    bool preview() const { return kind == Kind::Preview; }
    // Whether to render (again) for a viewport of `viewport` pixels: the frame is outdated, for
    // another size, or a preview whose drag ended.
    bool needs_render(ivec2 viewport, bool interacting) const {
        return outdated || view != viewport || (preview() && !interacting);
    }

    // Transitions
    // Draw `s` with the (new) last evaluation.
    void redraw(Scene s);
    // A render for `viewport` starts (if it throws, the old frame stays and is not retried).
    void render_started(ivec2 viewport);
    // It produced a frame of `size` pixels in `ms`; the display pass follows.
    void rendered(ivec2 size, bool reduced, double ms);
};

// [SECTION] UI
struct UiState {
    enum class Modal { None, Open, SaveAs, SavePack, Close };
    enum class ErrorOrigin { Action, Evaluation, Render };

    struct Toast {
        std::string text;
        Clock::time_point t0{};
        bool visible() const { return !text.empty() && seconds_since(t0) < 4.0; }
    };
    // The last error over the viewport; the frame behind it stays the last good one.
    struct ErrorBanner {
        std::string text;  // "" when none
        ErrorOrigin origin = ErrorOrigin::Action;
        int count = 0;  // errors reported since the last dismissal
    };
    // The whole window as a PNG, read after ImGui drew `settle` more frames.
    struct WindowShot {
        enum class Kind { None, Requested, Done, Failed } kind = Kind::None;
        std::string path;   // Requested
        int settle = 0;     // Requested: frames to draw first
        std::string error;  // Failed
    };
    struct Viewport {
        ivec2 size{0, 0};           // the viewport window's content, in pixels: frames are drawn at this size
        bool image_covers = false;  // the last frame's image filled it (its background is skipped)
        std::string aov = "radiance";  // the AOV shown
        float exposure_ev = 0.f;       // display only: scales the radiance shown
    };
    // The Truth view (app/gui/truth_view.h): what the viewport shows instead of the real-time frame.
    struct TruthView {
        enum class Show { RealTime, Truth, Error };
        Show show = Show::RealTime;
        int spp = 64;             // the target the truth refines to
        int seed = 1;
        bool on_screen = false;   // the truth (or the error) is what the viewport shows now
        float error_scale = 1.f;  // the error view's legend: colours saturate at ±this
    };
    // The Frontier view (app/gui/frontier_view.h): the current scene's accuracy-time frontier.
    struct FrontierView {
        bool open = false;        // its window is shown
        float budget_min = 2.f;   // no new setting starts after this
        int size = 128;           // frame size (square)
        int spp = 64;             // the truth's samples
    };
    struct Layout {
        bool relayout = true;      // put the windows back in their default places this frame
        vec2 display{0, 0};        // the display size laid out for
        std::string tech_windows;  // the techniques with a window, laid out for
    };

    Modal modal = Modal::None;   // the dialog to open in the next frame
    char modal_path[1024] = "";  // the path field of the Open and Save as dialogs
    Toast toast;
    ErrorBanner error;
    WindowShot window_shot;
    Viewport viewport;
    TruthView truth;
    FrontierView frontier;
    Layout layout;
    bool close_confirmed = false;  // the user chose to quit with unsaved changes

    // Transitions
    void show_error(std::string text, ErrorOrigin origin);
    void dismiss_error();
    void clear_error(ErrorOrigin origin);  // the banner goes if it shows an error of this origin
    void show_toast(std::string text);
    // The dialog to open; Save as starts from `path`.
    void open_modal(Modal m, const std::string& path = "");
    void request_window_shot(std::string path, int settle);
    void window_shot_done();
    void window_shot_failed(std::string error);
};

// [SECTION] The whole
struct GuiState {
    Document doc;
    EvalState eval;
    FrameState frame;
    UiState ui;

    // Nothing left to do: no edit pending, the worker idle (`worker_idle`), a full-size frame of
    // the current evaluation and viewport on screen.
    bool settled(bool worker_idle) const;
};
}  // namespace mesolab::gui
