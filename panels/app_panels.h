#pragma once
// [SECTION] The workbench's own panels (app/gui/gui.cpp lays them out): Scene, Presets, Timings.
// Like the technique panels they only draw and edit; anything with side effects (loading,
// saving, the clipboard) comes back to the caller as a request, so errors are handled in one
// place and never unwind through an open ImGui window.
#include "core/profile.h"
#include "core/render.h"
#include "panels/panel.h"
#include <string>
#include <vector>

namespace mesolab::panels {

// Scene: camera, lights (add / remove), environment, effects, the object selector and the
// geometry of the selected object (ctx.object, which the panel may change). `reference` (may be
// null) is the scene as loaded, for "Reset camera".
void scene_panel(PanelContext& ctx, const Scene* reference);

// Preset files under a folder (recursively), rescanned every few seconds.
struct PresetBrowser {
    std::string root = "presets";
    std::vector<std::string> files;  // paths as given to load_preset (root/...), sorted
    double last_scan = -1e30;
    int selected = -1;
    char filter[128] = "";
    char save_as[1024] = "";
    void rescan();
};

struct PresetRequest {
    enum class Kind { None, Load, Save, SaveAs, Copy, Paste } kind = Kind::None;
    std::string path;  // Load, SaveAs
};

// `current_file` is "" for an untitled scene; `modified`: unsaved changes.
PresetRequest presets_panel(PresetBrowser& b, const std::string& current_file, bool modified);
// The list with its filter box only (used by the Open dialog too); returns a path on activation.
PresetRequest preset_list(PresetBrowser& b, float height);

// Timings: one row per stage of the last evaluation (status, reason tooltip, time) and one per
// profiler path (last / median / min / max, device, the paper's figure and our ratio to it).
// `note` is shown above the tables (e.g. the last evaluation's failure).
// The stages of the last evaluation (object stages name their object), the last frame's frame
// steps, and the session profiler's history.
void timings_panel(const Scene& scene, const std::vector<StageRun>& runs, const std::vector<FrameStepRun>& steps, Profiler& profiler,
                   const std::string& note);

// Colour for a stage status (ran, cached, skipped, failed, cancelled).
unsigned status_color(StageStatus s);
}  // namespace mesolab::panels
