#pragma once
// [SECTION] Stage work on the GPU with a CPU fallback.
// Precomputations that can run as compute shaders (e.g. microgeom.device = gpu) go through
// gpu_or_cpu: gpu() where the user asks for the GPU, else cpu(). When the GPU cannot do the work
// (GpuUnavailable: this build or machine has no OpenGL compute; or any other std::runtime_error
// from the driver on the way: a compile error, a storage-buffer limit), cpu() runs instead and
// the stage warns "<what> computed on the CPU: the GPU could not (<first line of the reason>)".
// Cancellation (Cancelled) and bad input (InputError) are no GPU failure: they pass through
// untouched, as do programming errors (std::logic_error) and std::bad_alloc.
#include "core/error.h"
#include "core/stage.h"
#include <functional>
#include <stdexcept>
#include <string>

namespace mesolab {

struct GpuUnavailable : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Throws GpuUnavailable("this build has no GPU compute") unless `available`.
inline void require_gpu(bool available) {
    if (!available) throw GpuUnavailable("this build has no GPU compute");
}

template <class Gpu, class Cpu>
auto gpu_or_cpu(bool want_gpu, const std::string& what, const std::function<void(std::string)>& warn, Gpu&& gpu, Cpu&& cpu) -> decltype(cpu()) {
    if (want_gpu) {
        try {
            return gpu();
        } catch (const Cancelled&) {
            throw;
        } catch (const InputError&) {
            throw;
        } catch (const std::runtime_error& e) {
            const std::string reason = e.what();
            if (warn) warn(what + " computed on the CPU: the GPU could not (" + reason.substr(0, reason.find('\n')) + ")");
        }
    }
    return cpu();
}

// The same in a stage: the warning goes with the stage's result (StageContext::warn).
template <class Gpu, class Cpu>
auto gpu_or_cpu(StageContext& ctx, bool want_gpu, const std::string& what, Gpu&& gpu, Cpu&& cpu) -> decltype(cpu()) {
    return gpu_or_cpu(
        want_gpu, what,
        [&ctx](std::string m) {
            ctx.warn(std::move(m));
            ctx.fell_back_to_cpu();
        },
        std::forward<Gpu>(gpu), std::forward<Cpu>(cpu));
}
}  // namespace mesolab
