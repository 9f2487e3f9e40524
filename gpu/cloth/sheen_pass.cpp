// Method sheen of technique cloth draws with the technique's own pass: its pyramid entries hold
// the sheen instead of the lobes (core/cloth/sheen.cpp, cloth.frag), so it has no pass of its own.
#include "gpu/renderer.h"

#include <map>
#include <string>

namespace mesolab::gpu {
void register_cloth_sheen_gpu(std::map<std::string, PassFactory>&) {}
}  // namespace mesolab::gpu
