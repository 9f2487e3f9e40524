// Method lensch-burley of technique translucency: the paper's atlas and vertex pipeline (local
// kernels, vertex-to-vertex factors, blending, the brute-force reference) built from Christensen
// and Burley's normalised diffusion profile instead of the dipole (burley.h). The stages read
// translucency.method (Settings::profile), so the method is the paper's pipeline with other data:
// its objects run the technique's frame steps, CPU shading and GPU pass (shares_paper_pipeline).
#include "core/technique.h"
#include "core/translucency/technique.h"

#include <memory>
#include <stdexcept>

namespace mesolab {
namespace translucency {
namespace {
class LenschBurleyMethod final : public Method {
public:
    LenschBurleyMethod()
        : Method("translucency", "lensch-burley", "the paper's pipeline with Christensen and Burley's normalised diffusion profile (2015)") {}
    // Its knobs are the paper's (vertices, atlas_size, kernel, threshold): no keys of its own.
    void declare_params(ParamGroup&) const override {}
    std::vector<StageName> frame_stages() const override { return pipeline_stages(); }
    bool shares_paper_pipeline() const override { return true; }
    void shade_cpu(const ShadeContext&) const override {
        throw std::logic_error("translucency/lensch-burley shares the paper's pipeline: its objects are shaded by the technique");
    }
};
}  // namespace
}  // namespace translucency

void register_translucency_lensch_burley(Registry& r) { r.add_method(std::make_unique<translucency::LenschBurleyMethod>()); }
}  // namespace mesolab
