// Method kautz-consistent of technique bumpsynth draws with the technique's own pass
// (bumpsynth_pass.cpp), which binds its tables, one texture layer per octave count, in place of the
// NDF's and the Smith table's (core/bumpsynth/consistent.h), so it has no pass of its own.
#include "gpu/renderer.h"

#include <map>
#include <string>

namespace mesolab::gpu {
void register_bumpsynth_kautz_consistent_gpu(std::map<std::string, PassFactory>&) {}
}  // namespace mesolab::gpu
