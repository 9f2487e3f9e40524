#pragma once
// [SECTION] The viewport
//  - Viewport: the renderer and the display pass (the AOV shown as an RGBA8 texture), and the
//    "Viewport" window: the frame fitted and centred, the camera input (left-drag orbits,
//    right/middle-drag pans the target, the wheel zooms) and the overlays (error banner,
//    evaluation progress with Cancel, frame info, toast).
//  - render_request: while a widget or the camera is dragged and full-size frames are slow
//    (llvmpipe), frames are rendered at a reduced size; the full-size frame follows the drag.
#include "app/gui/evaluator.h"
#include "app/gui/state.h"
#include "core/render.h"
#include "app/gui/window.h"

#include <memory>
#include <string>

namespace mesolab::gpu {
class Renderer;
class DisplayPass;
}  // namespace mesolab::gpu

namespace mesolab::gui {

// [SECTION] Reduced-size rendering during drags
// Full-size frame time above which drags render at a reduced size.
constexpr double kInteractiveBudgetMs = 40.0;
// The size to render at for a viewport of `view` pixels: `view` itself, or while `dragging` with
// a last full-size frame slower than the budget, a size expected to meet it (at least a quarter
// of each side, 16 pixels). `reduced` says which.
ivec2 render_request(ivec2 view, bool dragging, double full_render_ms, bool& reduced);

// [SECTION] Viewport
class Viewport {
public:
    Viewport();  // GL objects: the window's context must be current
    ~Viewport();
    Viewport(const Viewport&) = delete;
    Viewport& operator=(const Viewport&) = delete;

    struct Requests {
        bool cancel_evaluation = false;  // the progress overlay's Cancel
    };
    // The window at its default place in `r` (forced there while s.ui.layout.relayout). Records
    // the viewport's size, edits the document's camera (marking its edits), dismisses the error
    // banner and expires the toast; what needs the worker comes back as requests.
    Requests window(GuiState& s, const layout::Rects& r, const Evaluator::Progress& progress);

    // Renders `f.scene` with `eval` for the viewport (reduced while `dragging` when slow), then
    // the display pass.
    void render(FrameState& f, const UiState::Viewport& v, const Evaluation& eval, bool dragging);
    // The display pass only: the AOV shown and the exposure.
    void update_display(FrameState& f, const UiState::Viewport& v);
    // The Truth view: shows `truth`'s radiance (with the exposure) or, for the error view, the
    // real-time radiance minus the truth's in colours (ui.truth.error_scale is set for the legend).
    void show_truth(const Frame& truth, UiState& ui);
    // What the Truth view shows: the truth's radiance, or the error's colours.
    Image truth_image(const Frame& truth, UiState& ui) const;
    // The frame on screen as an 8-bit sRGB PNG: the real-time radiance, or, while the Truth view
    // shows `truth`, what it shows.
    void screenshot(const FrameState& f, const std::string& path, const Frame* truth, UiState& ui);
    // The frame steps of the frame on screen (offscreen work before it), for the Timings panel.
    const std::vector<FrameStepRun>& frame_steps() const;
    // Takes the GPU timings that have arrived since (never waits): called once per window frame,
    // so that a frame's timings reach the Timings panel while nothing is re-rendered.
    void poll_timings();

private:
    std::unique_ptr<gpu::Renderer> renderer_;
    std::unique_ptr<gpu::DisplayPass> display_;
    struct TruthTexture;
    std::unique_ptr<TruthTexture> truth_texture_;  // the truth's image, uploaded for the display pass
};
}  // namespace mesolab::gui
