#pragma once
// Technique translucency's own internals, shared by the files that implement it (other modules use
// translucency.h and stages.h). TranslucencyTechnique's members are defined by concern, in the files
// every technique uses for them (README.md, "How it is built"):
//   technique.cpp  the parameters and AOVs, the frame's stages, texture size and meshes, the
//                  agreement, the sweep metric (and radiosity_error)
//   stages.cpp     the stage graph (declare_stages) and the frame steps' CPU work (frame_steps)
//   shading.cpp    CPU shading (shade_cpu)
//   bench.cpp      the timing table (Table 1) and its rows
// The maths: dipole, mesh_prep, atlas, local, global, blend, reference; the atlas stage's extras
// (atlas_stage.cpp), the gather table (gather.cpp), rho (albedo.cpp), the lights' shadow maps
// (shadow_map.cpp) and the illumination map with the combination (illumination.cpp); paper.h the
// paper's figures.
#include "core/bench.h"
#include "core/technique.h"
#include "core/translucency/translucency.h"
#include <string>
#include <vector>

namespace mesolab::translucency {

// [SECTION] The keys the stages and frame steps read
// The optical material: what R_d depends on (and geometry.scale through the mm per unit).
inline const std::vector<std::string> kMaterialKeys = {"translucency.material", "translucency.sigma_s", "translucency.sigma_a", "translucency.eta",
                                                       "translucency.mm_per_unit", "geometry.scale"};
std::vector<std::string> with_material(std::vector<std::string> keys);
// A frame step's keys: the lights, environment, effects, geometry, shadows, material and method, and `extra`.
std::vector<std::string> step_keys(std::vector<std::string> extra);
AtlasParams atlas_params(const Settings& s);
// Factors above the threshold (an estimate before they are built, for the memory budget).
MemoryEstimate factor_memory(const PreparedMesh& m, const Settings& s);

// [SECTION] The technique
// The object stages a frame of the atlas and vertex pipeline reads (the paper's method and
// lensch-burley, which share it).
std::vector<StageName> pipeline_stages();

class TranslucencyTechnique final : public Technique {
public:
    TranslucencyTechnique();
    void declare_stages(StageGraph& g) const override;
    std::vector<StageName> frame_stages() const override;
    std::vector<FrameStepDecl> frame_steps() const override;
    void shade_cpu(const ShadeContext& ctx) const override;
    std::optional<ivec2> texture_size(const Scene& s, const Evaluation& ev) const override;
    std::shared_ptr<const TriMesh> object_mesh(const Scene&, const Evaluation& ev, int object) const override;
    std::vector<BenchTable> bench_tables() const override;
    FrameAgreement agreement() const override;
    std::vector<SweepMetricDecl> sweep_metrics() const override;
    std::optional<TruthDecl> truth() const override;
};
}  // namespace mesolab::translucency
