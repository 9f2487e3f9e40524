#pragma once
// The same scene rendered by both backends, for CPU vs GPU agreement tests.
#include "app/workbench.h"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
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

// For each AOV, at least `frac_tight` of all values within `tight` and `frac_loose` within `loose` (absolute).
inline void expect_frames_agree(const Frame& cpu, const Frame& gpu, std::initializer_list<const char*> aovs, double tight, double loose,
                                double frac_tight, double frac_loose) {
    for (const char* aov : aovs) {
        const Image &a = cpu.aov(aov), &b = gpu.aov(aov);
        ASSERT_EQ(a.data.size(), b.data.size()) << aov;
        size_t n_tight = 0, n_loose = 0;
        for (size_t i = 0; i < a.data.size(); ++i) {
            const double d = std::fabs(double(a.data[i]) - double(b.data[i]));
            n_tight += d <= tight;
            n_loose += d <= loose;
        }
        const double n = double(a.data.size());
        EXPECT_GE(double(n_tight), frac_tight * n) << aov << ": " << n - double(n_tight) << " of " << n << " values differ by more than " << tight;
        EXPECT_GE(double(n_loose), frac_loose * n) << aov << ": " << n - double(n_loose) << " of " << n << " values differ by more than " << loose;
    }
}
}  // namespace mesolab::test
