#pragma once
// Where microgeom's precomputations run: `microgeom.device = cpu | gpu`. The core holds only
// this hook; the GPU layer (gpu/microgeom/scatter_gpu.cpp, at registration) fills it with
// implementations that run on an OpenGL compute context of their own (gpu/context.h,
// ComputeScope), so they work from any thread (the GUI evaluates stages off the UI thread) and
// return the same CPU-side results as the CPU code: the stages' consumers never know. Where the
// hook is empty or fails (no OpenGL), the stage falls back to the CPU and warns.
#include "core/heightfield/heightfield.h"
#include "core/microgeom/curvature.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/ellipse.h"
#include "core/microgeom/scatter.h"
#include "core/microgeom/visibility.h"
#include <functional>
#include <memory>

namespace mesolab::microgeom {

struct GpuCompute {
    // S_i on the GPU (visibility.comp), read back. Throws std::runtime_error without OpenGL.
    std::function<Visibility(const Heightfield&, const DirectionSet&)> visibility;
    // A gatherer running the bounces on the GPU (scatter.comp); it holds the compute context
    // while it lives. Throws std::runtime_error without OpenGL.
    std::function<std::unique_ptr<Gatherer>()> gatherer;
    // A solver for many lights' images at once (the goniometer's and the BTF's), made for these
    // inputs and settings (uploaded once); it holds the compute context while it lives. Throws
    // std::runtime_error without OpenGL or when the inputs exceed a storage-buffer limit.
    std::function<std::unique_ptr<LightSolver>(const Heightfield&, const DirectionSet&, const Visibility&, const ScatterSettings&)> light_solver;
    // The curved base's importance (curvature.h compute_importance) and one curvature's ellipse
    // fit (ellipse.h fit_ellipses) on the GPU, with the CPU functions' arguments and results.
    // Throw std::runtime_error without OpenGL.
    std::function<Importance(const Heightfield&, const DirectionSet&, const Visibility&, Bending, const std::function<void(double)>&)> importance;
    std::function<EllipseMap(const Heightfield&, const DirectionSet&, const Visibility&, Bending, const std::function<void(double)>&)> ellipses;
    explicit operator bool() const { return bool(visibility) && bool(gatherer); }
};

void set_gpu_compute(GpuCompute g);
const GpuCompute& gpu_compute();
}  // namespace mesolab::microgeom
