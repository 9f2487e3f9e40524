// Technique microgeom: the timing tables (mesolab bench microgeom, microgeom-brdf, ...).
#include "core/strings.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/goniometer.h"
#include "core/microgeom/paper.h"
#include "core/microgeom/technique.h"
#include "core/scene.h"

#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mesolab::microgeom {

// [SECTION] Table 1
namespace {
// A row's figures in the order of Table 1's columns below (S_i, shadows, software render, frame).
std::vector<std::optional<double>> table1_ms(const paper::Table1Row& r) { return {r.visibility.ms, r.shadows.ms, r.scattering.ms, r.frame.ms}; }
}  // namespace

std::vector<BenchTable> MicrogeomTechnique::bench_tables() const {
    auto scene = [](const char* field, int res, std::vector<std::pair<const char*, const char*>> extra = {}) {
        return [=] {
            Scene s = default_scene("microgeom");
            s.name = std::string(field) + std::to_string(res);
            apply_set(s, "camera.mode", "texture");
            apply_set(s, "geometry.type", "plane");
            apply_set(s, "microgeom.heightfield", field);
            apply_set(s, "microgeom.resolution", std::to_string(res));
            apply_set(s, "microgeom.directions", "100");
            apply_set(s, "microgeom.shadows", "ellipse");
            for (const auto& [k, v] : extra) apply_set(s, k, v);
            return s;
        };
    };
    auto mb = [](size_t bytes) { return format_bytes(double(bytes)); };
    BenchTable t;
    t.name = "microgeom";
    t.title = "Heidrich et al. 2000, Table 1: precomputation and rendering (100 directions)";
    t.paper_machine = "SGI Octane 300 MHz R12000 (software) / GeForce 256 (hardware), seconds converted to ms";
    BenchColumn memory;
    memory.name = "memory: S_i / ellipses / scattered light";
    memory.info = [mb](const Scene& s, const Evaluation& ev) {
        auto vis = ev.get(microgeom::stages::visibility, 0);
        auto ell = ev.get(microgeom::stages::ellipses, 0);
        auto sc = ev.get(microgeom::stages::scatter, 0);
        auto table = ev.get(microgeom::stages::scatter_directions, 0);
        (void)s;
        const size_t v = vis ? vis->bytes() : 0, e = ell ? ell->bytes() : 0;
        size_t l = 0;
        if (sc)
            for (const LightScatter& one : sc->lights) l += one.result.E_indirect.size() * sizeof(vec3);
        if (table) l += table->bytes();
        return mb(v) + " / " + mb(e) + " / " + mb(l);
    };
    BenchColumn vis_col{"S_i precompute", stages::visibility};
    vis_col.gpu_set = "microgeom.device=gpu";
    BenchColumn scatter_col{"software render (scattering, depth 2, all 100 directions)", stages::scatter};
    scatter_col.gpu_set = "microgeom.device=gpu";
    BenchColumn ellipse_col{"shadow (ellipse) precompute", stages::ellipses};
    ellipse_col.gpu_set = "microgeom.device=gpu";
    t.columns = {vis_col,
                 ellipse_col,
                 scatter_col,
                 {"frame (texture space, 1 pixel per texel; GPU = hardware render)", {}, 0, 0, true, true},
                 memory};
    t.rows = {{"Triangles 32x32", scene("triangles", 32), table1_ms(paper::kTriangles32)},
              {"Bricks 128x128", scene("bricks", 128), table1_ms(paper::kBricks128)},
              {"Bumps 32x32", scene("bumps", 32), table1_ms(paper::kBumps32)},
              {"Bricks 512x512", scene("bricks", 512), {}},
              {"Bricks 1024x1024", scene("bricks", 1024), {}}};

    BenchTable lod;
    lod.name = "microgeom-brdf";
    lod.title = "Heidrich et al. 2000, §6: simulated BRDF (virtual goniometer), Bricks 128x128, 100 directions, depth 2";
    lod.paper_machine = "SGI Octane + GeForce 256 (hardware goniometer images)";
    BenchColumn brdf_mem;
    brdf_mem.name = "memory";
    brdf_mem.info = [mb](const Scene&, const Evaluation& ev) {
        auto b = ev.get(microgeom::stages::brdf, 0);
        auto d = ev.get(microgeom::stages::displaced, 0);
        if (b) return mb(b->bytes()) + " (" + std::to_string(b->images) + " images)";
        if (d) return mb(d->vertex_count() * (3 * sizeof(vec3) + sizeof(vec2)) + d->index.size() * 4) + " (" + std::to_string(d->triangle_count()) + " triangles)";
        return std::string("—");
    };
    BenchColumn brdf_col{"precompute", stages::brdf};
    brdf_col.gpu_set = "microgeom.device=gpu";
    lod.columns = {brdf_col, brdf_mem};
    lod.rows = {{"BRDF table 8^4", scene("bricks", 128, {{"microgeom.lod", "brdf"}, {"microgeom.brdf_resolution", "8"}, {"microgeom.shadows", "exact"}}), {}},
                {"BRDF table 16^4", scene("bricks", 128, {{"microgeom.lod", "brdf"}, {"microgeom.brdf_resolution", "16"}, {"microgeom.shadows", "exact"}}), {paper::kBrdf16.ms}},
                {"BRDF SH, 300 random images, 3 bands", scene("bricks", 128, {{"microgeom.lod", "brdf"}, {"microgeom.brdf_fit", "sh"}, {"microgeom.shadows", "exact"}}), {}}};
    BenchTable geo;
    geo.name = "microgeom-geometry";
    geo.title = "Displaced geometry level of detail: Bricks 128x128 tiled 4x4 on a sphere (one vertex per texel), 512x512 frame";
    geo.columns = {{"displace (re-tessellate + displace)", stages::displaced}, {"frame 512x512", {}, 512, 512, true, true}, brdf_mem};
    geo.rows = {{"Bricks 128x128 on a sphere", [scene] {
                     Scene s = scene("bricks", 128, {{"microgeom.lod", "geometry"}, {"microgeom.shadows", "exact"}})();
                     apply_set(s, "camera.mode", "orbit");
                     apply_set(s, "geometry.type", "sphere");
                     return s;
                 }, {}}};
    BenchTable curved_t;
    curved_t.name = "microgeom-curved";
    curved_t.title = "Scattering on a non-planar base: Bricks 128x128 on a sphere, 100 directions (50 above the horizon), depth 2";
    BenchColumn table_col{"scattering for 50 light directions", stages::scatter_directions};
    table_col.gpu_set = "microgeom.device=gpu";
    BenchColumn table_mem;
    table_mem.name = "memory: scattered light";
    table_mem.info = [mb](const Scene&, const Evaluation& ev) {
        auto table = ev.get(microgeom::stages::scatter_directions, 0);
        if (!table) return std::string("—");
        return mb(table->bytes()) + " (" + std::to_string(table->count) + " directions)";
    };
    curved_t.columns = {table_col, {"frame 512x512", {}, 512, 512, true, true}, table_mem};
    curved_t.rows = {{"Bricks 128x128 on a sphere", [scene] {
                          Scene s = scene("bricks", 128, {{"microgeom.shadows", "exact"}})();
                          apply_set(s, "camera.mode", "orbit");
                          apply_set(s, "geometry.type", "sphere");
                          return s;
                      }, {}}};
    return {t, lod, geo, curved_t};
}
}  // namespace mesolab::microgeom
