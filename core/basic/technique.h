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
    std::optional<TruthDecl> truth() const override;
};
}  // namespace mesolab::basic
