#include "core/microgeom/device.h"

namespace mesolab::microgeom {
namespace {
GpuCompute& slot() {
    static GpuCompute g;
    return g;
}
}  // namespace

void set_gpu_compute(GpuCompute g) { slot() = std::move(g); }
const GpuCompute& gpu_compute() { return slot(); }
}  // namespace mesolab::microgeom
