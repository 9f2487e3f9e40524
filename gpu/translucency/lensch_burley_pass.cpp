// Method lensch-burley of technique translucency draws with the technique's own pass: its stages
// hold the kernels, factors and blending made from Christensen and Burley's profile
// (core/translucency/lensch_burley.cpp), so it has no pass of its own.
#include "gpu/renderer.h"

#include <map>
#include <string>

namespace mesolab::gpu {
void register_translucency_lensch_burley_gpu(std::map<std::string, PassFactory>&) {}
}  // namespace mesolab::gpu
