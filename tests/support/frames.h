#pragma once
// The same scene rendered by both backends, for CPU vs GPU agreement tests.
#include "app/workbench.h"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace mesolab::test {

// {CPU frame, GPU frame} of `s` at width x height (0 x 0: the request's default size), holding
// radiance and `aovs` (empty: every AOV of the scene).
inline std::pair<Frame, Frame> render_cpu_and_gpu(Workbench& wb, const Scene& s, int width = 0, int height = 0, const std::vector<std::string>& aovs = {}) {
    RenderRequest req;
    req.aovs = aovs;
    if (width > 0) req.width = width;
    if (height > 0) req.height = height;
    req.backend = Backend::Cpu;
    Frame cpu = wb.render(s, req).frame;
    req.backend = Backend::Gpu;
    Frame gpu = wb.render(s, req).frame;
    return {std::move(cpu), std::move(gpu)};
}

// For each AOV, at least `frac_tight` of all values within `tight` and `frac_loose` within `loose`
// (absolute). Fails when an AOV is missing, empty, or zero everywhere in both frames: two black
// frames agree about nothing.
inline void expect_frames_agree(const Frame& cpu, const Frame& gpu, std::initializer_list<const char*> aovs, double tight, double loose,
                                double frac_tight, double frac_loose) {
    for (const char* aov : aovs) {
        ASSERT_TRUE(cpu.has(aov)) << "the CPU frame has no AOV " << aov;
        ASSERT_TRUE(gpu.has(aov)) << "the GPU frame has no AOV " << aov;
        const Image &a = cpu.aov(aov), &b = gpu.aov(aov);
        ASSERT_EQ(a.data.size(), b.data.size()) << aov;
        ASSERT_FALSE(a.data.empty()) << aov << ": empty frames";
        size_t nonzero = 0;
        for (size_t i = 0; i < a.data.size(); ++i) nonzero += a.data[i] != 0.f || b.data[i] != 0.f;
        EXPECT_GT(nonzero, 0u) << aov << ": zero everywhere in both frames (nothing was drawn, so nothing is compared)";
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
// Every value of an AOV is 0 (e.g. no octaves of noise beyond the detail distance).
inline void expect_all_zero(const Frame& f, const char* aov) {
    ASSERT_TRUE(f.has(aov)) << aov;
    size_t nonzero = 0;
    for (float v : f.aov(aov).data) nonzero += v != 0.f;
    EXPECT_EQ(nonzero, 0u) << aov;
}
}  // namespace mesolab::test
