// The one GPU-or-CPU fallback: a GPU failure falls back to the CPU with a warning, while
// cancellation and bad input pass through untouched.
#include "core/error.h"
#include "core/gpu_or_cpu.h"

#include <gtest/gtest.h>
#include <string>
#include <vector>

using namespace mesolab;

namespace {
struct Log {
    std::vector<std::string> warnings;
    std::function<void(std::string)> fn() {
        return [this](std::string w) { warnings.push_back(std::move(w)); };
    }
};
}  // namespace

TEST(GpuOrCpu, TheGpuWhenAskedAndItWorks) {
    Log log;
    EXPECT_EQ(gpu_or_cpu(true, "S_i", log.fn(), [] { return 1; }, [] { return 2; }), 1);
    EXPECT_EQ(gpu_or_cpu(false, "S_i", log.fn(), [] { return 1; }, [] { return 2; }), 2);
    EXPECT_TRUE(log.warnings.empty());
}

TEST(GpuOrCpu, AGpuFailureFallsBackToTheCpuAndSaysWhy) {
    Log log;
    const int r = gpu_or_cpu(true, "S_i", log.fn(), []() -> int { throw std::runtime_error("EGL: no display\nplatform 2: ..."); }, [] { return 2; });
    EXPECT_EQ(r, 2);
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_EQ(log.warnings[0], "S_i computed on the CPU: the GPU could not (EGL: no display)");
    log.warnings.clear();
    EXPECT_EQ(gpu_or_cpu(true, "the ellipses", log.fn(), []() -> int { require_gpu(false); return 1; }, [] { return 2; }), 2);
    ASSERT_EQ(log.warnings.size(), 1u);
    EXPECT_NE(log.warnings[0].find("this build has no GPU compute"), std::string::npos);
}

TEST(GpuOrCpu, CancellationAndBadInputPassThroughUntouched) {
    Log log;
    int cpu_runs = 0;
    const auto cpu = [&] { return ++cpu_runs; };
    EXPECT_THROW(gpu_or_cpu(true, "S_i", log.fn(), []() -> int { throw Cancelled(); }, cpu), Cancelled);
    EXPECT_THROW(gpu_or_cpu(true, "S_i", log.fn(), []() -> int { throw InputError("h.exr: not an image"); }, cpu), InputError);
    EXPECT_THROW(gpu_or_cpu(true, "S_i", log.fn(), []() -> int { throw std::logic_error("a bug"); }, cpu), std::logic_error);
    EXPECT_EQ(cpu_runs, 0) << "none of these may run the CPU path";
    EXPECT_TRUE(log.warnings.empty());
    // The CPU path's own cancellation passes too.
    EXPECT_THROW(gpu_or_cpu(false, "S_i", log.fn(), [] { return 1; }, []() -> int { throw Cancelled(); }), Cancelled);
}
