// Technique microgeom: the BTF export (mesolab export btf; see btf.h).
#include "core/file.h"
#include "core/error.h"
#include "core/image.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/btf.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/technique.h"
#include "core/scene.h"
#include "core/strings.h"

#include <nlohmann/json.hpp>
#include <chrono>
#include <cstdio>
#include <map>

namespace mesolab::microgeom {

// [SECTION] BTF export (§6)
namespace {
ivec2 parse_grid(const std::string& key, const std::string& text) {
    const auto ab = parse_wxh(text);
    const int a = ab ? ab->first : 0, b = ab ? ab->second : 0;
    if (a < 1 || b < 1 || a > 64 || b > 128)
        throw InputError("--option " + key + "=" + text + ": expected THETAxPHI with 1..64 theta and 1..128 phi steps, e.g. 4x8");
    return {a, b};
}
}  // namespace

std::vector<ExportDecl> MicrogeomTechnique::exports() const {
    ExportDecl btf;
    btf.name = "btf";
    btf.help = "Light field / BTF: a view x light grid of texture-space heightfield images (shadows, scattering, masking) as one EXR mosaic";
    btf.options_help = "grid=THETAxPHI (default 4x8; both lights and views), lights=THETAxPHI, views=THETAxPHI";
    btf.stages = {stages::heightfield, stages::directions, stages::visibility, stages::importance, stages::ellipses_curved, stages::ellipses};
    btf.run = [](const Scene& s, const Evaluation& ev, int object, const std::map<std::string, std::string>& options, const std::string& path,
                 const ProgressFn& progress) {
        ivec2 lg(4, 8), vg(4, 8);
        for (const auto& [k, v] : options) {
            if (k == "grid") lg = vg = parse_grid(k, v);
            else if (k == "lights") lg = parse_grid(k, v);
            else if (k == "views") vg = parse_grid(k, v);
            else throw InputError("--option " + k + ": unknown option of export btf (accepts grid, lights, views)");
        }
        for (const auto& [k, v] : options)  // explicit lights/views win over grid whatever the order
            if (k == "lights") lg = parse_grid(k, v);
            else if (k == "views") vg = parse_grid(k, v);
        const SceneObject& o = s.objects[size_t(object)];
        const ObjectFrame of = ObjectFrame::from(s, ev, object);
        const Heightfield& hf = *of.hf;
        const DirectionSet& dirs = *of.dirs;
        const Visibility& vis = *of.vis;
        GonioSettings gs;
        gs.scatter = scatter_settings(o.material);
        if (!s.effect("indirect")) gs.scatter.depth = 0;
        gs.scatter.importance = of.imp.get();
        gs.scatter.ellipses = of.ell.get();
        gs.phong = o.material.get_string("brdf") == "blinn-phong";
        gs.ks = o.material.get_vec3("ks");
        gs.shininess = float(o.material.get_float("shininess"));
        const std::vector<vec3> lights = btf_directions(lg.x, lg.y), views = btf_directions(vg.x, vg.y);
        const auto t0 = std::chrono::steady_clock::now();
        std::string warnings;
        const Image mosaic = with_light_solver([&](std::string m) { warnings += "\nwarning: " + o.name + ": " + m; }, o, hf, dirs, vis, gs.scatter,
                                                                   [&](LightSolver* solver) {
                                                                       gs.lights = solver;
                                                                       return btf_mosaic(hf, dirs, vis, gs, lights, views, [&](double f) { if (progress) progress("export.btf", f); });
                                                                   });
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        write_exr(path, mosaic);
        // Sidecar: layout and directions.
        nlohmann::json j;
        j["export"] = "btf";
        j["object"] = o.name;
        j["tile"] = {hf.width, hf.height};
        j["layout"] = "tile (row = light index, column = view index); tile row 0 = heightfield row 0 (top)";
        auto list = [](ivec2 g) {
            nlohmann::json a = nlohmann::json::array();
            for (int i = 0; i < g.x; ++i)
                for (int k = 0; k < g.y; ++k) a.push_back({(double(i) + 0.5) * 90.0 / g.x, double(k) * 360.0 / g.y});
            return a;
        };
        j["lights_theta_phi_deg"] = list(lg);
        j["views_theta_phi_deg"] = list(vg);
        j["unit"] = "radiance towards the view per unit irradiance from the light (at normal incidence to the light); 0 where masked";
        j["compute_ms"] = ms;
        write_text_atomic(path + ".json", j.dump(2) + "\n");
        char buf[256];
        std::snprintf(buf, sizeof buf, "btf: %zu lights x %zu views of %dx%d texels (%dx%d EXR), computed in %.0f ms; directions in %s.json", lights.size(), views.size(),
                      hf.width, hf.height, mosaic.width, mosaic.height, ms, path.c_str());
        return std::string(buf) + warnings;
    };
    return {btf};
}
}  // namespace mesolab::microgeom
