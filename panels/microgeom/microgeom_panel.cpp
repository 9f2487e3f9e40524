// Panel of technique microgeom: the generated widgets for each object's heightfield, direction
// set, curvature, scattering, shading and level of detail, the light and view directions as
// hemisphere discs, a Fig. 9-style side-by-side of the three levels of detail, and what the
// stages hold (sizes, fold-over warnings).
#include "core/strings.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/microgeom.h"
#include "core/technique.h"
#include "panels/panel.h"

#include <imgui.h>
#include <optional>

namespace mesolab::panels {
namespace {

// The objects and camera the side-by-side view replaced, to go back to.
struct Saved {
    std::vector<SceneObject> objects;
    ParamTable camera;
};

// Replace the scene's objects by three spheres with the material of `src`: geometry, bump, BRDF.
Saved side_by_side(Scene& s, const SceneObject& src, Dirty& dirty) {
    Saved saved{s.objects, s.camera};
    const char* lods[3] = {"geometry", "bump", "brdf"};
    std::vector<SceneObject> objs;
    for (int k = 0; k < 3; ++k) {
        SceneObject o = src;
        o.name = std::string("lod-") + lods[k];
        o.geometry.set("type", std::string("sphere"));
        o.geometry.set("position", std::array<double, 3>{2.3 * (k - 1), 0.0, 0.0});
        o.geometry.set("scale", 1.0);
        o.material.set("lod", std::string(lods[k]));
        objs.push_back(std::move(o));
    }
    s.objects = std::move(objs);
    s.camera.set("mode", std::string("orbit"));
    s.camera.set("target", std::array<double, 3>{0.0, 0.0, 0.0});
    s.camera.set("distance", 7.5);
    dirty.mark(Cost::Recompute);
    return saved;
}

class MicrogeomPanel final : public TechniquePanel {
public:
    void draw(PanelContext& ctx) override;
    void reset() override { saved_.reset(); }

private:
    std::optional<Saved> saved_;  // while the side-by-side view shows
};
}  // namespace

void MicrogeomPanel::draw(PanelContext& ctx) {
    // Light and view: hemisphere discs (light.direction of the first light, camera.orbit).
    if (ImGui::TreeNodeEx("Light and view", ImGuiTreeNodeFlags_DefaultOpen)) {
        if (!ctx.scene.lights.empty() && ctx.scene.lights[0].get_string("type") == "directional")
            hemisphere_widget(*ctx.scene.lights[0].group().find("direction"), ctx.scene.lights[0], ctx.dirty, 120.f, "light");
        else
            ImGui::TextDisabled("light: a point light (set its position in the Scene panel)");
        hemisphere_widget(*ctx.scene.camera.group().find("orbit"), ctx.scene.camera, ctx.dirty, 120.f, "view");
        ImGui::TextDisabled("moving the light or the view never recomputes S_i (see Timings)");
        ImGui::TreePop();
    }
    // Environment (the scene's, also in the Scene panel): looked up wherever a visibility ray
    // leaves the heightfield; effects.environment / effects.indirect switch the stages on.
    if (ImGui::TreeNodeEx("Environment and effects")) {
        ImGui::PushID("mg-env");
        param_table_widgets(ctx.scene.env, ctx.dirty, "##mg");
        param_table_widgets(ctx.scene.effects, ctx.dirty, "##mg");
        ImGui::PopID();
        ImGui::TreePop();
    }
    // Only while the three spheres are still there.
    if (saved_ && !(ctx.scene.objects.size() == 3 && ctx.scene.objects[0].name == "lod-geometry")) saved_.reset();
    if (saved_) {
        if (ImGui::Button("Back to the scene before the side-by-side view")) {
            ctx.scene.objects = std::move(saved_->objects);
            ctx.scene.camera = std::move(saved_->camera);
            saved_.reset();
            ctx.dirty.mark(Cost::Recompute);
            return;
        }
        help_marker("Restores the objects and camera that the side-by-side levels of detail replaced.");
    }
    const int i = ctx.object;
    SceneObject& o = ctx.scene.objects[size_t(i)];
    ImGui::Separator();
    ImGui::TextDisabled("%s", o.name.c_str());
    param_sections(o.material, ctx.dirty);
    if (ImGui::Button("Side-by-side levels of detail")) {
        const SceneObject src = o;
        saved_ = side_by_side(ctx.scene, src, ctx.dirty);
        return;
    }
    help_marker("Like the paper's Fig. 9: replaces the scene's objects by three spheres with this material as displaced geometry, "
                "bump map and simulated BRDF, left to right (a button at the top of this panel goes back).");
    aov_buttons(ctx, "microgeom");
    if (ctx.eval) {
        if (const auto v = ctx.eval->get(microgeom::stages::visibility, i))
            ImGui::TextDisabled("S_i: %d directions x %dx%d texels, %s", v->count, v->width, v->height, format_bytes(double(v->bytes())).c_str());
        if (const auto f = ctx.eval->get(microgeom::stages::brdf, i))
            ImGui::TextDisabled("BRDF: %d^4 table from %d goniometer images, %s", f->n_theta, f->images, format_bytes(double(f->bytes())).c_str());
        if (const auto m = ctx.eval->get(microgeom::stages::displaced, i)) ImGui::TextDisabled("displaced: %zu triangles", m->triangle_count());
    }
}

void register_microgeom_panel(PanelRegistry& r) { r.add<MicrogeomPanel>("microgeom", "Micro-geometry (Heidrich et al. 2000)"); }
}  // namespace mesolab::panels
