// Panel of technique microgeom: the generated widgets for each object's heightfield, direction
// set, curvature, scattering, shading and level of detail, the light and view directions as
// hemisphere discs, a Fig. 9-style side-by-side of the three levels of detail, and what the
// stages hold (sizes, fold-over warnings).
#include "core/microgeom/stages.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/microgeom.h"
#include "core/technique.h"
#include "panels/panel.h"

#include <imgui.h>
#include <optional>

namespace mesolab::panels {
namespace {

void group(ParamTable& t, Dirty& dirty, const char* title, std::initializer_list<const char*> names, bool open) {
    if (!ImGui::TreeNodeEx(title, open ? ImGuiTreeNodeFlags_DefaultOpen : 0)) return;
    for (const char* n : names) {
        const ParamDecl* d = t.group().find(n);
        if (d && t.is_used(*d)) param_widget(*d, t, dirty);
    }
    ImGui::TreePop();
}

// The objects and camera the side-by-side view replaced, to go back to.
struct Saved {
    std::vector<SceneObject> objects;
    ParamTable camera;
};
std::optional<Saved>& saved_scene() {
    static std::optional<Saved> saved;
    return saved;
}

// Replace the scene's objects by three spheres with the material of `src`: geometry, bump, BRDF.
void side_by_side(Scene& s, const SceneObject& src, Dirty& dirty) {
    saved_scene() = Saved{s.objects, s.camera};
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
}
}  // namespace

void register_microgeom_panel(PanelRegistry& r) {
    r.add("microgeom", "Micro-geometry (Heidrich et al. 2000)", [](PanelContext& ctx) {
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
        // Only while the three spheres are still there (a preset loaded since forgets the way back).
        if (saved_scene() && !(ctx.scene.objects.size() == 3 && ctx.scene.objects[0].name == "lod-geometry")) saved_scene().reset();
        if (saved_scene()) {
            if (ImGui::Button("Back to the scene before the side-by-side view")) {
                ctx.scene.objects = std::move(saved_scene()->objects);
                ctx.scene.camera = std::move(saved_scene()->camera);
                saved_scene().reset();
                ctx.dirty.mark(Cost::Recompute);
            }
            help_marker("Restores the objects and camera that the side-by-side levels of detail replaced.");
        }
        for (size_t i = 0; i < ctx.scene.objects.size(); ++i) {
            SceneObject& o = ctx.scene.objects[i];
            if (o.technique != "microgeom") continue;
            ImGui::PushID(int(i));
            ImGui::Separator();
            ImGui::TextDisabled("%s", o.name.c_str());
            group(o.material, ctx.dirty, "Heightfield",
                  {"heightfield", "resolution", "height_scale", "texel_size", "periodic", "vgroove_angle", "rms_slope", "correlation", "seed", "albedo", "albedo_map", "tiling"}, true);
            group(o.material, ctx.dirty, "Visibility and scattering", {"directions", "depth", "sampling", "paths", "scatter_seed", "shadows", "device"}, true);
            group(o.material, ctx.dirty, "Curvature of the base (§5)", {"curvature_u", "curvature_v"}, true);
            group(o.material, ctx.dirty, "Level of detail", {"lod", "brdf_fit", "brdf_resolution", "brdf_samples", "sh_bands"}, true);
            group(o.material, ctx.dirty, "Shading", {"brdf", "ks", "shininess"}, false);
            if (ImGui::Button("Side-by-side levels of detail")) {
                const SceneObject src = o;
                side_by_side(ctx.scene, src, ctx.dirty);
                ImGui::PopID();
                break;
            }
            help_marker("Like the paper's Fig. 9: replaces the scene's objects by three spheres with this material as displaced geometry, "
                        "bump map and simulated BRDF, left to right (a button at the top of this panel goes back).");
            if (ctx.eval) {
                if (const auto v = ctx.eval->get(microgeom::stages::visibility, int(i)))
                    ImGui::TextDisabled("S_i: %d directions x %dx%d texels, %.1f MB", v->count, v->width, v->height, double(v->bytes()) / (1 << 20));
                if (const auto f = ctx.eval->get(microgeom::stages::brdf, int(i)))
                    ImGui::TextDisabled("BRDF: %d^4 table from %d goniometer images, %.2f MB", f->n_theta, f->images, double(f->bytes()) / (1 << 20));
                if (const auto m = ctx.eval->get(microgeom::stages::displaced, int(i))) ImGui::TextDisabled("displaced: %zu triangles", m->triangle_count());
            }
            ImGui::PopID();
        }
    });
}
}  // namespace mesolab::panels
