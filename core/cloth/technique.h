#pragma once
// Technique cloth's own internals, shared by the files that implement it (other modules use
// cloth.h and stages.h). ClothTechnique's members are defined by concern, in the files every
// technique uses for them (README.md, "How it is built"):
//   technique.cpp  the parameters and AOVs, the agreement, the samples export, the sweep metric
//                  and the settings read from an object's keys
//   stages.cpp     the stage graph (declare_stages)
//   shading.cpp    CPU shading (shade_cpu) and a pixel's uv footprint
//   bench.cpp      the timing table (the paper's §7 figures)
//   commands.cpp   mesolab cloth fit and mesolab cloth eval
// The maths: stitch, marching_cubes, acquire, samples, lafortune, fit, pyramid, shade, garment;
// gpu_layout.cpp packs the pyramid as the GPU pass reads it.
#include "core/bench.h"
#include "core/cloth/cloth.h"
#include "core/technique.h"

#include <memory>
#include <vector>

namespace mesolab::cloth {

// [SECTION] The technique
class ClothTechnique final : public Technique {
public:
    ClothTechnique();
    void declare_stages(StageGraph& g) const override;
    std::vector<StageName> frame_stages() const override;
    // The object stages a frame reads (the paper's method and sheen, which share the pipeline).
    static std::vector<StageName> pipeline_stages();
    void shade_cpu(const ShadeContext& ctx) const override;
    std::shared_ptr<const TriMesh> object_mesh(const Scene&, const Evaluation& ev, int object) const override;
    std::vector<ExportDecl> exports() const override;
    std::vector<CommandDecl> commands() const override;
    std::vector<BenchTable> bench_tables() const override;
    FrameAgreement agreement() const override;
    std::vector<SweepMetricDecl> sweep_metrics() const override;
    bool uses_uv_derivatives() const override { return true; }  // the mip level's footprint
    std::optional<TruthDecl> truth() const override;
};
}  // namespace mesolab::cloth
