#pragma once
// The same scene rendered by both backends, for CPU vs GPU agreement tests.
#include "app/workbench.h"
#include "core/technique.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace mesolab::test {

// {CPU frame, GPU frame} of `s` at width x height (0 x 0: the request's default size), holding
// radiance and `aovs` (empty: every AOV of the scene), each with its coverage (Frame::coverage).
inline std::pair<Frame, Frame> render_cpu_and_gpu(Workbench& wb, const Scene& s, int width = 0, int height = 0, const std::vector<std::string>& aovs = {}) {
    RenderRequest req;
    req.aovs = aovs;
    req.coverage = true;
    if (width > 0) req.width = width;
    if (height > 0) req.height = height;
    req.renderer = "cpu";
    Frame cpu = wb.render(s, req).frame;
    req.renderer = "gpu";
    Frame gpu = wb.render(s, req).frame;
    return {std::move(cpu), std::move(gpu)};
}

// What one AOV's comparison found, over the pixels the objects cover (the CPU frame's coverage).
struct AgreementFigures {
    size_t values = 0, interior_values = 0;  // covered values (pixels x channels), those off edges
    size_t within_tight = 0, within_loose = 0;
    size_t interior_beyond_max = 0;
    double interior_allowed = 0;  // the outliers the tolerances allow (sum of interior_outliers)
    double worst_interior = 0, worst = 0;  // worst_interior: off edges, flips left out
    int worst_interior_x = -1, worst_interior_y = -1;
    size_t nonzero_cpu = 0, nonzero_gpu = 0;  // covered values that are not 0
    size_t interior_pixels = 0, interior_flips = 0;  // covered pixels off edges, those that are flips
    double flips_allowed = 0;     // the flips the tolerances allow (sum of interior_flips)
    double worst_flip = 0;        // the largest difference at a flip
};

// Whether pixel (x, y) is a flip under `tol` (FrameAgreement::choices): some index of the choice
// AOVs differs between the frames, and none by more than 1.
inline bool is_flip(const Frame& cpu, const Frame& gpu, const FrameAgreement& tol, int x, int y) {
    bool differs = false;
    for (const std::string& name : tol.choices) {
        if (!cpu.has(name) || !gpu.has(name)) return false;
        const Image &a = cpu.aov(name), &b = gpu.aov(name);
        for (int c = 0; c < a.channels; ++c) {
            const float va = a.at(x, y)[c], vb = b.at(x, y)[c];
            if (va == vb) continue;
            if (!(std::fabs(double(va) - double(vb)) <= 1.0)) return false;
            differs = true;
        }
    }
    return differs;
}

// The comparison of one AOV, over covered pixels only; `tol` for a pixel is tolerance(object).
template <class Tolerance>
AgreementFigures compare_aov(const Frame& cpu, const Frame& gpu, const char* aov, Tolerance&& tolerance) {
    AgreementFigures f;
    const Coverage& cov = cpu.coverage;
    const Image &a = cpu.aov(aov), &b = gpu.aov(aov);
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const size_t p = size_t(y) * size_t(a.width) + size_t(x);
            if (!cov.covered(p)) continue;
            const FrameAgreement& tol = tolerance(cov.object[p]);
            const bool interior = !cov.edge[p], flip = interior && is_flip(cpu, gpu, tol, x, y);
            if (interior) {
                ++f.interior_pixels;
                f.interior_flips += flip;
                f.flips_allowed += tol.interior_flips;
            }
            for (int c = 0; c < a.channels; ++c) {
                const float va = a.at(x, y)[c], vb = b.at(x, y)[c];
                const double d = std::isfinite(va) && std::isfinite(vb) ? std::fabs(double(va) - double(vb)) : INFINITY;
                ++f.values;
                f.nonzero_cpu += va != 0.f;
                f.nonzero_gpu += vb != 0.f;
                f.within_tight += d <= tol.tight;
                f.within_loose += d <= tol.loose;
                f.worst = std::max(f.worst, d);
                if (!interior) continue;
                ++f.interior_values;
                if (flip) {
                    f.worst_flip = std::max(f.worst_flip, d);
                    continue;
                }
                f.interior_beyond_max += d > tol.interior_max;
                f.interior_allowed += tol.interior_outliers;
                if (d > f.worst_interior || f.worst_interior_x < 0) f.worst_interior = d, f.worst_interior_x = x, f.worst_interior_y = y;
            }
        }
    return f;
}

inline void print_figures(const char* what, const char* aov, const AgreementFigures& f) {
    const double n = double(std::max<size_t>(f.values, 1));
    std::printf("[ cpu/gpu ] %-40s %-11s covered %7zu (interior %7zu): within tight %.5f, loose %.5f; worst %.2e, interior %.2e at (%d,%d), %zu over max (%.0f allowed)",
                what, aov, f.values, f.interior_values, double(f.within_tight) / n, double(f.within_loose) / n, f.worst, f.worst_interior,
                f.worst_interior_x, f.worst_interior_y, f.interior_beyond_max, std::floor(f.interior_allowed + 1e-9));
    if (f.interior_flips > 0 || f.flips_allowed > 0)
        std::printf("; flips %zu of %zu pixels (%.0f allowed), worst %.2e", f.interior_flips, f.interior_pixels, std::floor(f.flips_allowed + 1e-9), f.worst_flip);
    std::printf("\n");
}

// Checks one AOV's figures against the tolerances: content in both frames, the fractions within
// `tight` and `loose`, and every value off edges within `interior_max`.
inline void expect_figures_agree(const char* aov, const AgreementFigures& f, double frac_tight, double frac_loose) {
    EXPECT_GT(f.values, 0u) << aov << ": no pixel shows an object (nothing is compared)";
    EXPECT_GT(f.nonzero_cpu, 0u) << aov << ": the CPU frame is 0 on every object pixel";
    EXPECT_GT(f.nonzero_gpu, 0u) << aov << ": the GPU frame is 0 on every object pixel";
    const double n = double(f.values);
    EXPECT_GE(double(f.within_tight), frac_tight * n) << aov << ": " << n - double(f.within_tight) << " of " << n << " covered values beyond tight";
    EXPECT_GE(double(f.within_loose), frac_loose * n) << aov << ": " << n - double(f.within_loose) << " of " << n << " covered values beyond loose";
    EXPECT_LE(double(f.interior_beyond_max), std::floor(f.interior_allowed + 1e-9))
        << aov << ": " << f.interior_beyond_max << " values off silhouettes and triangle edges beyond interior_max (" << std::floor(f.interior_allowed + 1e-9)
        << " allowed); worst " << f.worst_interior << " at pixel (" << f.worst_interior_x << ", " << f.worst_interior_y << ")";
    EXPECT_LE(double(f.interior_flips), std::floor(f.flips_allowed + 1e-9))
        << aov << ": " << f.interior_flips << " of " << f.interior_pixels << " pixels off edges are flips (discrete choices one step apart; "
        << std::floor(f.flips_allowed + 1e-9) << " allowed)";
}

// For each AOV, over the pixels the objects cover (the CPU frame's coverage, which must be filled:
// render_cpu_and_gpu does), the CPU and GPU frames agree to the tolerances of the object a pixel
// shows, tolerance(object) (core/technique.h, FrameAgreement): fractions within tight and loose,
// every value off edges within interior_max but for the allowed outliers and flips (the frames must
// hold the AOVs of the discrete choices the tolerances name), and content (a value other than 0) in
// both frames: two black frames agree about nothing.
template <class Tolerance>
void expect_frames_agree_by_object(const Frame& cpu, const Frame& gpu, std::initializer_list<const char*> aovs, Tolerance&& tolerance,
                                   std::string label = "") {
    if (label.empty()) label = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    ASSERT_FALSE(cpu.coverage.empty()) << "the CPU frame has no coverage (render it with RenderRequest::coverage)";
    ASSERT_EQ(cpu.coverage.width, cpu.width);
    ASSERT_EQ(cpu.coverage.height, cpu.height);
    double frac_tight = 1, frac_loose = 1;
    for (int o : cpu.coverage.object)
        if (o >= 0) frac_tight = std::min(frac_tight, tolerance(o).frac_tight), frac_loose = std::min(frac_loose, tolerance(o).frac_loose);
    for (int o : cpu.coverage.object)
        if (o >= 0)
            for (const std::string& name : tolerance(o).choices) {
                ASSERT_TRUE(cpu.has(name)) << "the CPU frame has no AOV " << name << ", the discrete choices its agreement names";
                ASSERT_TRUE(gpu.has(name)) << "the GPU frame has no AOV " << name << ", the discrete choices its agreement names";
            }
    for (const char* aov : aovs) {
        ASSERT_TRUE(cpu.has(aov)) << "the CPU frame has no AOV " << aov;
        ASSERT_TRUE(gpu.has(aov)) << "the GPU frame has no AOV " << aov;
        ASSERT_EQ(cpu.aov(aov).data.size(), gpu.aov(aov).data.size()) << aov;
        const AgreementFigures f = compare_aov(cpu, gpu, aov, tolerance);
        print_figures(label.c_str(), aov, f);
        expect_figures_agree(aov, f, frac_tight, frac_loose);
    }
}

// The same with one set of tolerances for every pixel.
inline void expect_frames_agree(const Frame& cpu, const Frame& gpu, std::initializer_list<const char*> aovs, const FrameAgreement& tol) {
    expect_frames_agree_by_object(cpu, gpu, aovs, [&](int) -> const FrameAgreement& { return tol; });
}

// The same with each technique's own tolerances (Technique::agreement), pixel by pixel after the
// object it shows.
inline void expect_frames_agree(const Scene& s, const Frame& cpu, const Frame& gpu, std::initializer_list<const char*> aovs) {
    std::vector<FrameAgreement> tol;
    for (const SceneObject& o : s.objects) tol.push_back(Registry::instance().technique(o.technique)->agreement_for(o));
    expect_frames_agree_by_object(cpu, gpu, aovs, [&](int o) -> const FrameAgreement& { return tol.at(size_t(o)); }, s.name);
}

// A technique's own tolerances.
inline FrameAgreement agreement_of(const std::string& technique) { return Registry::instance().technique(technique)->agreement(); }

// Every value of an AOV is 0 (e.g. no octaves of noise beyond the detail distance).
inline void expect_all_zero(const Frame& f, const char* aov) {
    ASSERT_TRUE(f.has(aov)) << aov;
    size_t nonzero = 0;
    for (float v : f.aov(aov).data) nonzero += v != 0.f;
    EXPECT_EQ(nonzero, 0u) << aov;
}
}  // namespace mesolab::test
