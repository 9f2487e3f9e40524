// The window's menus, side windows, timings, status bar, dialogs and shortcuts (the Gui: app.h).
#include "app/gui/app.h"

namespace fs = std::filesystem;

namespace mesolab::gui {

// [SECTION] Menus and windows
void Gui::menu_bar() {
    if (!ImGui::BeginMainMenuBar()) return;
    if (ImGui::BeginMenu("File")) {
        if (ImGui::MenuItem("Open preset...", "Ctrl+O")) state_.ui.open_modal(Modal::Open);
        if (ImGui::MenuItem("Save", "Ctrl+S")) handle({panels::PresetRequest::Kind::Save, state_.doc.file});
        if (ImGui::MenuItem("Save as...", "Ctrl+Shift+S")) {
            state_.ui.open_modal(Modal::SaveAs, presets_.save_as);
        }
        if (ImGui::MenuItem("Save as shareable...")) {
            const std::string name = state_.doc.scene.name.empty() ? "scene" : state_.doc.scene.name;
            state_.ui.open_modal(Modal::SavePack, "screenshots/" + name + ".zip");
        }
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("A pack: the preset with every file it names (meshes, images, samples, arrays from Python) under content-hash names, as NAME.zip or "
                              "a folder; it renders the same on another machine (mesolab preset pack does the same)");
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
        ImGui::MenuItem("Frontier...", nullptr, &state_.ui.frontier.open);
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("The accuracy-time frontier of the scene's methods against the truth, measured in the background");
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
    if (state_.ui.modal == Modal::SavePack) ImGui::OpenPopup("Save as shareable pack");
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
        const bool enter = ImGui::InputTextWithHint("##open_path", "path/to/preset.json or pack.zip (or pick one above)", state_.ui.modal_path, sizeof state_.ui.modal_path, ImGuiInputTextFlags_EnterReturnsTrue);
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

    // A dialog asking for a path to save to: Enter or Save calls `save` (an error is reported and the dialog stays).
    const auto save_dialog = [&](const char* title, const char* prompt, const char* id, const char* exists_note, void (Gui::*save)(const std::string&)) {
        ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
        if (!ImGui::BeginPopupModal(title, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) return;
        ImGui::TextUnformatted(prompt);
        ImGui::SetNextItemWidth(480);
        if (ImGui::IsWindowAppearing()) ImGui::SetKeyboardFocusHere();
        const bool enter = ImGui::InputText(id, state_.ui.modal_path, sizeof state_.ui.modal_path, ImGuiInputTextFlags_EnterReturnsTrue);
        if (fs::exists(state_.ui.modal_path)) ImGui::TextColored(ImVec4(0.95f, 0.7f, 0.3f, 1.f), "%s", exists_note);
        if (ImGui::Button("Save", ImVec2(120, 0)) || enter) {
            bool ok = true;
            try {
                (this->*save)(state_.ui.modal_path);
            } catch (const std::exception& e) {
                ok = false;
                report(e.what(), true, ErrorOrigin::Action);
            }
            if (ok) ImGui::CloseCurrentPopup();
        }
        ImGui::SameLine();
        if (ImGui::Button("Cancel", ImVec2(120, 0)) || ImGui::IsKeyPressed(GLFW_KEY_ESCAPE, false)) ImGui::CloseCurrentPopup();
        ImGui::EndPopup();
    };
    save_dialog("Save preset as", "Path of the preset file (relative to the working directory):", "##save_path", "The file exists and will be replaced.",
                &Gui::save_to);
    save_dialog("Save as shareable pack", "NAME.zip, or a folder (new, empty, or a pack it replaces), relative to the working directory:", "##pack_path",
                "It exists and will be replaced.", &Gui::save_pack_to);

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
}  // namespace mesolab::gui
