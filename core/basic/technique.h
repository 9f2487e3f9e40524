#pragma once
// Technique basic: the Technique class, shared by the technique's own files (technique.cpp,
// stages.cpp, shading.cpp, bench.cpp, truth.cpp); other layers use basic.h and stages.h.
#include "core/basic/basic.h"
#include "core/technique.h"

namespace mesolab::basic {

class BasicTechnique final : public Technique {
public:
    BasicTechnique();
    void declare_stages(StageGraph& g) const override;
    std::vector<StageName> frame_stages() const override;
    void shade_cpu(const ShadeContext& ctx) const override;
    std::vector<BenchTable> bench_tables() const override;
    FrameAgreement agreement() const override;
    bool has_truth() const override { return true; }
    TruthObject truth_object(const Scene& s, const Evaluation& ev, int object) const override;
    std::vector<StageName> truth_stages() const override;
    std::vector<std::string> truth_params() const override;
};
}  // namespace mesolab::basic
