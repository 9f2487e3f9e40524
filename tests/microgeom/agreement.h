#pragma once
// Shared by the microgeom GPU tests. CPU vs GPU frame agreement: for each AOV, at least `frac_tight` of all
// values within `tight` and `frac_loose` within `loose` (absolute).
#include "core/microgeom/heightfield.h"
#include "core/render.h"
#include "gpu/context.h"

#include <gtest/gtest.h>
#include <cmath>
#include <stdexcept>

namespace mesolab::test {

// Whether the shared compute context (gpu/context.h) can be made: the GPU tests skip without it.
inline bool have_compute_gl() {
    try {
        gpu::ComputeScope scope;
        return true;
    } catch (const std::runtime_error&) {
        return false;
    }
}

// A procedural heightfield by name at res x res texels, periodic or not (default: the procedural default).
inline microgeom::Heightfield procedural_field(const char* name, int res, bool periodic = microgeom::ProceduralParams{}.periodic) {
    microgeom::ProceduralParams p;
    p.name = name;
    p.resolution = res;
    microgeom::Heightfield hf = microgeom::make_procedural(p);
    hf.periodic = periodic;
    return hf;
}

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
