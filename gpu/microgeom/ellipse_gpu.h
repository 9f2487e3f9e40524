#pragma once
// Per-texel shadow ellipses (Heidrich et al. 2000, §4; core/microgeom/ellipse.h) fitted on the
// GPU by microgeom/ellipse_fit.comp, one work group per texel. The CPU Fitter
// (core/microgeom/ellipse.cpp) is the reference: same points in the same order, same starts,
// pattern search, constants and scoring; each evaluation sorts its keys with a bitonic sort in
// shared memory and sweeps them with a parallel prefix sum and an argmax.
//
// [SECTION] Points
//  - Flat base (Bending{}, zero curvature): the points are the projected upper directions
//    (d_i.z > 0), the same for every texel; they are uploaded once, and per texel only the lit
//    bits (lit iff S_i[p] == Visibility::kNoHit), one bit per point.
//  - Curved base: the points move per texel (the bent directions of the shadowed ones, ellipse.h
//    "Curved base"); they are computed on the CPU per batch of texels (TBB over rows, with
//    bent_direction, in the order of the CPU's bent_points) and uploaded with their lit bits.
// At most 1024 points per texel (the shader's shared memory; N = 1024 gives about 520 upper
// directions): more throw std::runtime_error.
//
// [SECTION] Batches
// The texels are dispatched in batches (row-major texel ranges) sized so that one dispatch
// stays well under a second on llvmpipe (at most 0.2 s measured, 2 cores); `progress` is called
// on the calling thread after each. The group size follows the renderer and the point count
// (ellipse_gpu.cpp, [SECTION] Group size). On llvmpipe (2 cores) the GPU fit is far slower than
// the CPU's: Bricks 128x128, N = 100 takes 2.4 s against 0.15 s (Release).
#include "core/microgeom/ellipse.h"

#include <functional>

namespace mesolab::gpu {

// The per-texel ellipses of core/microgeom/ellipse.h fit_ellipses(hf, dirs, vis, b), fitted on the GPU
// (ellipse_fit.comp). Same points, starts, pattern search and scoring as the CPU Fitter; agreement is
// stated in tests/microgeom/ellipse_gpu_test.cpp. Runs on the shared compute context (gpu/context.h
// ComputeScope, taken inside), so it may be called from any thread. Throws std::runtime_error without
// OpenGL; std::invalid_argument as the CPU for mismatched visibility. `progress` as the CPU's (fractions
// on the calling thread, may throw to cancel).
microgeom::EllipseMap fit_ellipses_gpu(const Heightfield& hf, const microgeom::DirectionSet& dirs,
                                       const microgeom::Visibility& vis, microgeom::Bending b = {},
                                       const std::function<void(double)>& progress = {});
}  // namespace mesolab::gpu
