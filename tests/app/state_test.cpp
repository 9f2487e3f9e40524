// The GUI's state without a window: the transitions of the document, the frame and the UI, and
// when a scripted run counts as settled.
#include "app/gui/state.h"

#include <gtest/gtest.h>

#include <string>

using namespace mesolab;
using namespace mesolab::gui;

namespace {
Scene scene_named(const std::string& name) {
    Scene s = default_scene();
    s.name = name;
    return s;
}

// A state with a full-size frame of the current scene in a 640x480 viewport and nothing pending.
GuiState settled_state() {
    GuiState st;
    st.doc.loaded(scene_named("a"), "a.json");
    st.doc.take_edits();
    st.ui.viewport.size = {640, 480};
    st.frame.redraw(st.doc.scene);
    st.frame.render_started(st.ui.viewport.size);
    st.frame.rendered({640, 480}, false, 12.0);
    return st;
}
}  // namespace

// [SECTION] Document
TEST(Document, LoadingMakesTheSceneSavedAndPendingEvaluation) {
    Document d;
    d.selected_object = 2;
    d.loaded(scene_named("a"), "a.json");
    EXPECT_EQ(d.file, "a.json");
    EXPECT_EQ(d.selected_object, 0);
    EXPECT_FALSE(d.modified());
    EXPECT_TRUE(d.edits.recompute);
    EXPECT_TRUE(d.take_edits());
    EXPECT_FALSE(d.take_edits());  // taken once
}

TEST(Document, EditsShowAsModifiedUntilSaved) {
    Document d;
    d.loaded(scene_named("a"), "a.json");
    d.take_edits();
    d.selected_object = 1;
    apply_set(d.scene, "camera.distance=6");
    d.edited(Cost::Redraw);
    EXPECT_TRUE(d.modified());
    EXPECT_TRUE(d.take_edits());

    Scene reread = d.scene;
    d.saved_as(reread, "b.json");
    EXPECT_FALSE(d.modified());
    EXPECT_EQ(d.file, "b.json");
    EXPECT_EQ(d.selected_object, 1);  // saving keeps the selection
    EXPECT_TRUE(d.take_edits());      // the reread scene may resolve files differently
}

TEST(Document, PastedSceneIsUntitledAndUnsaved) {
    Document d;
    d.loaded(scene_named("a"), "a.json");
    d.take_edits();
    d.replaced(scene_named("pasted"));
    EXPECT_TRUE(d.file.empty());
    EXPECT_TRUE(d.modified());
    EXPECT_TRUE(d.take_edits());
}

// [SECTION] Frame
TEST(FrameState, RedrawRenderAndPreview) {
    FrameState f;
    EXPECT_FALSE(f.shown());
    f.redraw(scene_named("a"));
    EXPECT_TRUE(f.outdated);
    EXPECT_TRUE(f.needs_render({100, 100}, false));

    f.render_started({100, 100});
    EXPECT_FALSE(f.outdated);
    f.rendered({50, 50}, true, 30.0);
    EXPECT_TRUE(f.shown());
    EXPECT_TRUE(f.preview());
    EXPECT_EQ(f.full_render_ms, 0.0);
    EXPECT_FALSE(f.needs_render({100, 100}, true));  // still dragging: the preview stays
    EXPECT_TRUE(f.needs_render({100, 100}, false));  // the drag ended: full size follows
    EXPECT_TRUE(f.needs_render({120, 100}, true));   // the viewport changed size

    f.render_started({100, 100});
    f.rendered({100, 100}, false, 60.0);
    EXPECT_EQ(f.kind, FrameState::Kind::Full);
    EXPECT_EQ(f.px, ivec2(100, 100));
    EXPECT_EQ(f.full_render_ms, 60.0);
    EXPECT_FALSE(f.needs_render({100, 100}, false));
}

// [SECTION] UI
TEST(UiState, ErrorsCountUntilDismissedAndClearByOrigin) {
    UiState ui;
    ui.show_error("bad file", UiState::ErrorOrigin::Evaluation);
    ui.show_error("bad file again", UiState::ErrorOrigin::Evaluation);
    EXPECT_EQ(ui.error.count, 2);
    ui.clear_error(UiState::ErrorOrigin::Action);
    EXPECT_EQ(ui.error.text, "bad file again");
    ui.clear_error(UiState::ErrorOrigin::Evaluation);
    EXPECT_TRUE(ui.error.text.empty());
    ui.show_error("x", UiState::ErrorOrigin::Action);
    ui.dismiss_error();
    EXPECT_TRUE(ui.error.text.empty());
    EXPECT_EQ(ui.error.count, 0);
}

TEST(UiState, SaveAsDialogStartsFromThePathTruncated) {
    UiState ui;
    ui.open_modal(UiState::Modal::SaveAs, "presets/mine.json");
    EXPECT_EQ(ui.modal, UiState::Modal::SaveAs);
    EXPECT_STREQ(ui.modal_path, "presets/mine.json");
    const std::string long_path(5000, 'x');
    ui.open_modal(UiState::Modal::SaveAs, long_path);
    EXPECT_EQ(std::string(ui.modal_path).size(), sizeof ui.modal_path - 1);
}

TEST(UiState, WindowShotRequestedThenDoneOrFailed) {
    UiState ui;
    ui.request_window_shot("w.png", 2);
    EXPECT_EQ(ui.window_shot.kind, UiState::WindowShot::Kind::Requested);
    EXPECT_EQ(ui.window_shot.path, "w.png");
    EXPECT_EQ(ui.window_shot.settle, 2);
    ui.window_shot_failed("w.png: cannot write");
    EXPECT_EQ(ui.window_shot.kind, UiState::WindowShot::Kind::Failed);
    EXPECT_EQ(ui.window_shot.error, "w.png: cannot write");
    ui.request_window_shot("w2.png", 0);  // a new request forgets the old failure
    EXPECT_TRUE(ui.window_shot.error.empty());
    ui.window_shot_done();
    EXPECT_EQ(ui.window_shot.kind, UiState::WindowShot::Kind::Done);
}

// [SECTION] Settled
TEST(GuiState, SettledNeedsAnIdleWorkerNoEditsAndAFullFrameOfTheViewport) {
    EXPECT_TRUE(settled_state().settled(true));
    EXPECT_FALSE(settled_state().settled(false));  // the worker is busy or has an outcome to collect

    GuiState edited = settled_state();
    edited.doc.edited(Cost::Redraw);
    EXPECT_FALSE(edited.settled(true));

    GuiState resized = settled_state();
    resized.ui.viewport.size = {800, 480};
    EXPECT_FALSE(resized.settled(true));

    GuiState preview = settled_state();
    preview.frame.rendered({320, 240}, true, 5.0);
    EXPECT_FALSE(preview.settled(true));

    GuiState outdated = settled_state();
    outdated.frame.redraw(outdated.doc.scene);
    EXPECT_FALSE(outdated.settled(true));

    GuiState display = settled_state();
    display.frame.display_outdated = true;
    EXPECT_FALSE(display.settled(true));

    EXPECT_FALSE(GuiState().settled(true));  // no frame yet
}
