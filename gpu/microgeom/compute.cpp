// microgeom's GPU precomputations, installed into the core's hook (core/microgeom/device.h).
#include "core/microgeom/device.h"
#include "gpu/context.h"
#include "gpu/microgeom/ellipse_gpu.h"
#include "gpu/microgeom/importance_gpu.h"
#include "gpu/microgeom/lights_gpu.h"
#include "gpu/microgeom/scatter_gpu.h"
#include "gpu/microgeom/visibility_gpu.h"

namespace mesolab::gpu {

void install_microgeom_gpu_compute() {
    microgeom::GpuCompute g;
    g.visibility = [](const Heightfield& hf, const microgeom::DirectionSet& dirs) {
        ComputeScope scope;
        // Compiled once, on the compute context, and kept (that context lives until exit).
        static const VisibilityProgram* program = new VisibilityProgram();
        const KeepOnGpu k = keep_visibility_on_gpu();
        const bool keep = k == KeepOnGpu::Always || (k == KeepOnGpu::Automatic && !current_renderer_is_software());
        return program->compute(hf, dirs, keep);
    };
    g.gatherer = [] { return make_gpu_gatherer(); };
    g.light_solver = [](const Heightfield& hf, const microgeom::DirectionSet& dirs, const microgeom::Visibility& vis, const microgeom::ScatterSettings& s) {
        return make_gpu_light_solver(hf, dirs, vis, s);
    };
    g.importance = [](const Heightfield& hf, const microgeom::DirectionSet& dirs, const microgeom::Visibility& vis, microgeom::Bending b,
                      const std::function<void(double)>& progress) { return compute_importance_gpu(hf, dirs, vis, b, progress); };
    g.ellipses = [](const Heightfield& hf, const microgeom::DirectionSet& dirs, const microgeom::Visibility& vis, microgeom::Bending b,
                    const std::function<void(double)>& progress) { return fit_ellipses_gpu(hf, dirs, vis, b, progress); };
    microgeom::set_gpu_compute(std::move(g));
}
}  // namespace mesolab::gpu
