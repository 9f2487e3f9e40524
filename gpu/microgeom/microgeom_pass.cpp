// GPU pass of technique microgeom.
#include "core/error.h"
#include "gpu/renderer.h"

namespace mesolab::gpu {
namespace {
class MicrogeomPass final : public TechniquePass {
public:
    void draw(DrawContext&) override { throw InputError("microgeom: the GPU pass is not implemented yet; use --backend cpu"); }
};
}  // namespace

void register_microgeom_gpu(std::map<std::string, PassFactory>& out) {
    out["microgeom"] = [] { return std::make_unique<MicrogeomPass>(); };
}
}  // namespace mesolab::gpu
