// Technique translucency: the timing table (mesolab bench translucency), Table 1 of the paper.
#include "core/strings.h"
#include "core/translucency/paper.h"
#include "core/translucency/technique.h"
#include "core/translucency/translucency.h"

#include <cstdio>
#include <filesystem>
#include <string>

namespace mesolab::translucency {
namespace {

// A shipped mesh: from the working directory (the repository's root), else from the source tree.
std::string shipped_mesh(const std::string& name) {
    const std::string rel = "presets/translucency/meshes/" + name;
    if (std::filesystem::exists(rel)) return std::filesystem::absolute(rel).string();
    return std::string(MESOLAB_SOURCE_DIR) + "/" + rel;
}

std::string mb(double bytes) { return format_bytes(bytes); }

// The row's scene: the mesh lit from behind at 45 degrees, marble, 512 x 512 atlas (vertices < 0:
// the key left out, for a method that does not read it).
Scene table_scene(const std::string& mesh, int vertices, const std::string& name) {
    Scene s = default_scene("translucency");
    s.name = name;
    apply_set(s, "geometry.type", "mesh");
    apply_set(s, "geometry.path", mesh);
    apply_set(s, "geometry.scale", "10");
    if (vertices >= 0) apply_set(s, "translucency.vertices", std::to_string(vertices));
    return s;
}
}  // namespace

std::vector<BenchTable> TranslucencyTechnique::bench_tables() const {
    BenchTable t;
    t.name = "translucency";
    t.title = "Lensch et al. 2002, Table 1: per-frame passes and precomputation (512 x 512 atlas, K = 7)";
    t.paper_machine = paper::kMachine;
    BenchColumn vertices{"vertices"}, factors{"form factors"}, memory{"memory: factors / kernels / atlas fill"};
    vertices.info = [](const Scene&, const Evaluation& ev) {
        const auto m = ev.get(stages::mesh, 0);
        return m ? std::to_string(m->vertex_count()) : std::string("—");
    };
    factors.info = [](const Scene&, const Evaluation& ev) {
        const auto F = ev.get(stages::factors, 0);
        return F ? std::to_string(F->count()) : std::string("—");
    };
    memory.info = [](const Scene&, const Evaluation& ev) {
        const auto F = ev.get(stages::factors, 0);
        const auto K = ev.get(stages::kernels, 0);
        const auto A = ev.get(stages::atlas, 0);
        char fill[32];
        std::snprintf(fill, sizeof fill, "%.1f%%", A ? 100.0 * A->atlas.fill_ratio : 0.0);
        return mb(F ? double(F->bytes()) : 0.0) + " / " + mb(K ? double(K->bytes()) : 0.0) + " / " + fill;
    };
    t.columns = {vertices,
                 factors,
                 memory,
                 {"simplify (decimater)", stages::mesh},
                 {"atlas", stages::atlas},
                 {"kernels", stages::kernels},
                 {"form factors (precompute)", stages::factors},
                 {"blending fit", stages::blend},
                 {"frame 512x512", {}, 512, 512, true, true}};
    // Columns with a paper figure: kernels (1-2 min: the upper end), factors (2-8 min), the frame.
    auto row = [&](const paper::Table1Row& p, const char* ours) {
        BenchRow r;
        r.name = std::string(ours) + " " + std::to_string(p.vertices) + " (paper: " + p.model + ")";
        const std::string mesh = shipped_mesh("stanford-bunny.obj");
        const int n = p.vertices;
        r.scene = [=] { return table_scene(mesh, n, r.name); };
        r.paper_ms = {std::nullopt, std::nullopt, std::nullopt, std::nullopt, std::nullopt, paper::kKernelsMaxMs, paper::kFactorsMaxMs, std::nullopt, p.total_ms};
        r.paper_step_ms = {{std::string(steps::illumination.name), p.illumination_ms}, {std::string(steps::local.name), p.local_ms}, {std::string(steps::global.name), p.global_ms}};
        return r;
    };
    t.rows = {row(paper::kTable1[0], "bunny"), row(paper::kTable1[2], "bunny"), row(paper::kTable1[3], "bunny")};
    // The same pipeline with Christensen and Burley's profile (translucency.method = lensch-burley):
    // what the profile costs in the precomputation and the frame (no paper figure).
    {
        BenchRow r;
        const int n = paper::kTable1[0].vertices;
        r.name = "bunny " + std::to_string(n) + ", lensch-burley";
        const std::string mesh = shipped_mesh("stanford-bunny.obj"), name = r.name;
        r.scene = [=] {
            Scene s = table_scene(mesh, n, name);
            apply_set(s, "translucency.method", "lensch-burley");
            return s;
        };
        t.rows.push_back(r);
    }
    // The screen-space separable blur (translucency.method = separable) on the whole bunny: no
    // precomputation, the frame's irradiance, blurs and display (no paper figure).
    {
        BenchRow r;
        r.name = "bunny, separable";
        const std::string mesh = shipped_mesh("stanford-bunny.obj"), name = r.name;
        r.scene = [=] {
            Scene s = table_scene(mesh, -1, name);
            apply_set(s, "translucency.method", "separable");
            return s;
        };
        t.rows.push_back(r);
    }
    t.mesh_row = [](const std::string& mesh, int vertices) {
        BenchRow r;
        r.name = std::filesystem::path(mesh).filename().string();
        if (vertices > 0) r.name.append(1, ' ').append(std::to_string(vertices));
        const std::string name = r.name;
        r.scene = [=] { return table_scene(mesh, vertices > 0 ? vertices : 10000, name); };
        return r;
    };
    return {t};
}
}  // namespace mesolab::translucency
