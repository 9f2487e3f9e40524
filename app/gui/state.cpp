// The GUI's state: the transitions of its parts.
#include "app/gui/state.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace mesolab::gui {

// [SECTION] Document
void Document::loaded(Scene s, std::string path) {
    saved_as(std::move(s), std::move(path));
    selected_object = 0;
}

void Document::saved_as(Scene s, std::string path) {
    scene = s;
    saved = std::move(s);
    file = std::move(path);
    edits.mark(Cost::Recompute);  // the same values from another folder may resolve other files
}

void Document::replaced(Scene s) {
    scene = std::move(s);
    file.clear();
    selected_object = 0;
    edits.mark(Cost::Recompute);
}

bool Document::take_edits() {
    const bool any = edits.any();
    edits = {};
    return any;
}

// [SECTION] Frame
void FrameState::redraw(Scene s) {
    scene = std::move(s);
    outdated = true;
}

void FrameState::render_started(ivec2 viewport) {
    outdated = false;
    view = viewport;
}

void FrameState::rendered(ivec2 size, bool reduced, double ms) {
    kind = reduced ? Kind::Preview : Kind::Full;
    px = size;
    render_ms = ms;
    if (!reduced) full_render_ms = ms;
}

// [SECTION] UI
void UiState::show_error(std::string text, ErrorOrigin origin) {
    error.text = std::move(text);
    error.origin = origin;
    ++error.count;
}

void UiState::dismiss_error() {
    error.text.clear();
    error.count = 0;
}

void UiState::clear_error(ErrorOrigin origin) {
    if (error.origin == origin) error.text.clear();
}

void UiState::show_toast(std::string text) {
    toast.text = std::move(text);
    toast.t0 = Clock::now();
}

void UiState::open_modal(Modal m, const std::string& path) {
    modal = m;
    if (m == Modal::SaveAs) {
        const size_t n = std::min(path.size(), sizeof modal_path - 1);
        std::memcpy(modal_path, path.data(), n);
        modal_path[n] = 0;
    }
}

void UiState::request_window_shot(std::string path, int settle) {
    window_shot = {WindowShot::Kind::Requested, std::move(path), settle, ""};
}

void UiState::window_shot_done() { window_shot = {WindowShot::Kind::Done, "", 0, ""}; }

void UiState::window_shot_failed(std::string e) { window_shot = {WindowShot::Kind::Failed, "", 0, std::move(e)}; }

// [SECTION] The whole
bool GuiState::settled(bool worker_idle) const {
    return worker_idle && !doc.edits.any() && frame.kind == FrameState::Kind::Full && !frame.outdated && !frame.display_outdated &&
           frame.view == ui.viewport.size;
}
}  // namespace mesolab::gui
