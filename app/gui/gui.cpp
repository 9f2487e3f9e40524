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
//  - app/gui/frontier_view.h, frontier_panel.cpp  the Frontier view: its worker, its plot
//  - app/gui/app.h        the Gui class; here its frame loop, actions (load, save, paste,
//                         screenshots), errors; app/gui/menus.cpp its menus, windows, dialogs
//
// [SECTION] Index
//  here: The application, Errors and notifications, Actions, Scene changes, Frame loop, Script
//  commands, Layout, Entry point; app/gui/menus.cpp: Menus and windows, Dialogs and shortcuts
#include "app/gui/app.h"

namespace fs = std::filesystem;

namespace mesolab::gui {

Gui::Gui(GLFWwindow* window, ScriptRunner script, bool scripted, std::optional<Scene> initial,
         std::string initial_file, std::string initial_error, uint64_t memory_limit)
    : window_(window), scripted_(scripted), evaluator_(session_), script_(std::move(script)) {
    session_.set_memory_limit(memory_limit);
    try {
        session_.set_store(StageStore::from_environment(version_string()));  // expensive stages kept between runs
    } catch (const InputError& e) {
        std::fprintf(stderr, "mesolab: %s; stages are not kept on disk\n", e.what());
    }
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
    if (is_pack(path)) return save_pack_to(path);  // a pack opened is saved as a pack
    save_preset(state_.doc.scene, path);
    // Reload, so that relative paths are rebased onto the new file's folder.
    state_.doc.saved_as(load_preset(path), path);
    presets_.rescan();
    toast("Saved " + path);
}

void Gui::save_pack_to(const std::string& path) {
    if (path.empty()) throw InputError("save as shareable: no file name given");
    const std::vector<std::string> members = write_pack(state_.doc.scene, path);
    state_.doc.saved_as(load_preset(path), path);
    presets_.rescan();
    toast("Saved the pack " + path + " (" + std::to_string(members.size() - 1) + " file" + (members.size() == 2 ? "" : "s") + " beside scene.json)");
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
    if (state_.ui.frontier.open && frontier_.status().running) return false;
    if (state_.ui.truth.show == UiState::TruthView::Show::RealTime) return true;
    const TruthRunner::Status ts = truth_.status();
    return !ts.error.empty() || (!ts.running && state_.ui.truth.on_screen);
}

void Gui::view(const std::string& what, int spp) {
    if (what == "frontier") {  // the Frontier view, measuring the scene now (wait: until it is done)
        if (spp > 0) state_.ui.frontier.spp = spp;
        state_.ui.frontier.open = true;
        start_frontier();
        return;
    }
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
    if (scripted_ || busy_frames_ > 0 || evaluator_.busy() || truth_.status().running || frontier_.status().running || state_.ui.toast.visible() || state_.frame.outdated || ImGui::IsAnyMouseDown() || shot_pending) {
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
        if (fs::path(p).extension() == ".json" || is_pack(p)) {
            attempt([&] { load(p); });
            return;
        }
    }
    report("dropped " + paths.front() + ": not a preset or a pack (drop a .json or .zip file, or a pack's folder)", true, ErrorOrigin::Action);
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
        frontier_window();
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
