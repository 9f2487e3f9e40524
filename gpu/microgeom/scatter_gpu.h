#pragma once
// microgeom's precomputations on the GPU (microgeom.device = gpu): S_i (visibility_gpu.h) and
// the bounces of the dependent-test scattering (scatter.comp), on the shared compute context
// (gpu/context.h ComputeScope), so they run from any thread. The CPU code is the reference:
// tests/microgeom/scatter_gpu_test.cpp checks the two agree.
#include "core/microgeom/scatter.h"
#include <cstddef>
#include <memory>

namespace mesolab::gpu {

// A Gatherer (core/microgeom/scatter.h) whose gathers run in scatter.comp. Holds the compute
// scope (the context current, other users waiting) from construction to destruction. S_i go up
// in chunks of directions of at most max_chunk_bytes each (0: GL_MAX_SHADER_STORAGE_BLOCK_SIZE;
// gpu/microgeom/chunks.h). Throws std::runtime_error without OpenGL, or when one direction's
// texture alone exceeds that limit.
std::unique_ptr<microgeom::Gatherer> make_gpu_gatherer(size_t max_chunk_bytes = 0);
}  // namespace mesolab::gpu
