#pragma once
// Curved-base importance of technique microgeom (Heidrich et al. 2000, §5) on the GPU: the compute
// shader microgeom/importance.comp evaluates core/microgeom/curvature.h's model (bent directions
// towards the lowered hit points, fan-area ratios I_j over the hit-only triangles, normalised
// gather weights w_j, folded flags), with core/microgeom/curvature.cpp compute_importance as the
// reference: tests/microgeom/importance_gpu_test.cpp states and measures the agreement.
//
// Host work: per-texel normals (Heightfield::normal), the unbent triangle areas and the
// direction table, all O(W H + N); then one invocation per texel, dispatched in batches of rows
// (each batch uploads its rows of S_i and reads back its rows of I and w). The largest buffer is
// the shader's scratch of bent directions, 16 N bytes per texel, kept to 64 MiB per batch: e.g.
// 1024^2 texels x 100 directions run in batches of 40 rows. Only a single row above
// GL_MAX_SHADER_STORAGE_BLOCK_SIZE (W N > 8 Mi on llvmpipe's 128 MiB) is refused.
// folded_count is counted on the host.
#include "core/microgeom/curvature.h"

#include <functional>

namespace mesolab::gpu {

// core/microgeom/curvature.h compute_importance on the GPU (importance.comp): same I, w and folded
// flags (agreement stated in tests/microgeom/importance_gpu_test.cpp). Runs on the shared compute
// context (gpu/context.h ComputeScope, taken inside), so it may be called from any thread; the
// scope is held while `progress` runs, so `progress` must not take it. Empty result for zero
// curvature, as the CPU (no GL needed then). Throws std::runtime_error without OpenGL or when one
// row of the field (W x N bent directions, 16 bytes each) exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE;
// std::invalid_argument when vis does not match hf and dirs. `progress` as the CPU's: the fraction
// done after each batch of rows, on the calling thread; it may throw to cancel (the exception
// propagates, GL state restored).
microgeom::Importance compute_importance_gpu(const Heightfield& hf, const microgeom::DirectionSet& dirs,
                                             const microgeom::Visibility& vis, microgeom::Bending b,
                                             const std::function<void(double)>& progress = {});
}  // namespace mesolab::gpu
