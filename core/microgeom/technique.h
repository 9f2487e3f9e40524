#pragma once
// Technique microgeom's own internals, shared by the files that implement it (other modules use
// microgeom.h and stages.h). MicrogeomTechnique's members are defined by concern, in the files
// every technique uses for them (README.md, "How it is built"):
//   technique.cpp  the parameters, effect and AOVs, the agreement; the frame's stages, texture size and meshes
//   stages.cpp     the stage graph (declare_stages)
//   shading.cpp    CPU shading (shade_cpu)
//   commands.cpp   the BTF export (exports, §6)
//   bench.cpp      the timing tables (bench_tables: Table 1 and §6)
// The paper's figures are in paper.h. The stages and the BTF export share the scattering settings
// of a material and the GPU's light solver with its CPU fallback (below).
#include "core/error.h"
#include "core/gpu_or_cpu.h"
#include "core/microgeom/device.h"
#include "core/microgeom/microgeom.h"
#include "core/technique.h"
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace mesolab::microgeom {

class MicrogeomTechnique final : public Technique {
public:
    MicrogeomTechnique();
    void declare_stages(StageGraph& g) const override;
    std::vector<StageName> frame_stages() const override;
    std::shared_ptr<const TriMesh> object_mesh(const Scene&, const Evaluation& ev, int object) const override;
    std::optional<ivec2> texture_size(const Scene& s, const Evaluation& ev) const override;
    void shade_cpu(const ShadeContext& ctx) const override;
    std::vector<ExportDecl> exports() const override;
    std::vector<BenchTable> bench_tables() const override;
    FrameAgreement agreement() const override;
    std::optional<TruthDecl> truth() const override;
};

// The tiling of the truth's surface (truth.cpp): microgeom.tiling; in texture mode the field
// once (1:1, as the real-time texture mode draws it), on a plane with a copy on every side (3).
float truth_tiling(const Scene& s, const SceneObject& o);

// The scattering settings of a material (microgeom.depth, sampling, paths, scatter_seed, shadows).
ScatterSettings scatter_settings(const ParamTable& material);

// The first line of an error message (EGL failures list every platform tried).
inline std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// f(solver) with the GPU's light solver (goniometer and BTF light images) where the object asks
// for it and OpenGL works; else, or when the GPU fails on the way, f(nullptr) (the CPU), with a
// warning through `warn` (gpu_or_cpu).
template <class F>
auto with_light_solver(const std::function<void(std::string)>& warn, const SceneObject& o, const Heightfield& hf, const DirectionSet& dirs,
                       const Visibility& vis, const ScatterSettings& st, F&& f) {
    return gpu_or_cpu(
        o.material.get_string("device") == "gpu", "light images", warn,
        [&] {
            require_gpu(bool(gpu_compute().light_solver));
            const std::unique_ptr<LightSolver> solver = gpu_compute().light_solver(hf, dirs, vis, st);
            return f(solver.get());
        },
        [&] { return f(nullptr); });
}
}  // namespace mesolab::microgeom
