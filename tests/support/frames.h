#pragma once
// The same scene rendered by both backends, for CPU vs GPU agreement tests.
#include "app/workbench.h"

#include <utility>

namespace mesolab::test {

// {CPU frame, GPU frame} of `s` at width x height (0 x 0: the request's default size).
inline std::pair<Frame, Frame> render_cpu_and_gpu(Workbench& wb, const Scene& s, int width = 0, int height = 0) {
    RenderRequest req;
    if (width > 0) req.width = width;
    if (height > 0) req.height = height;
    req.backend = Backend::Cpu;
    Frame cpu = wb.render(s, req).frame;
    req.backend = Backend::Gpu;
    Frame gpu = wb.render(s, req).frame;
    return {std::move(cpu), std::move(gpu)};
}
}  // namespace mesolab::test
