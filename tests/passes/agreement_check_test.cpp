// The CPU/GPU agreement check itself (tests/support/frames.h) fails where it must: a few wrong
// pixels inside a face, black frames, a wrong silhouette band beyond the allowed fraction; and
// counts only the pixels the objects cover.
#include "core/scene.h"
#include "support/frames.h"

#include <gmock/gmock.h>
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

using namespace mesolab;

namespace {

// A basic sphere on both backends, 160 x 120, with coverage.
const std::pair<Frame, Frame>& sphere_frames() {
    static const std::pair<Frame, Frame> frames = [] {
        Workbench wb;
        Scene s = default_scene("basic");
        apply_set(s, "geometry.resolution", "16");  // large triangles: many interior pixels
        return test::render_cpu_and_gpu(wb, s, 160, 120, {"radiance", "normal"});
    }();
    return frames;
}

// The failure messages of a check (none when it passes).
template <class F>
std::string failures_of(F&& check) {
    ::testing::TestPartResultArray results;
    {
        ::testing::ScopedFakeTestPartResultReporter reporter(::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
        check();
    }
    std::string all;
    for (int i = 0; i < results.size(); ++i) all += std::string(results.GetTestPartResult(i).message()) + "\n";
    return all;
}

// The first `n` covered pixels off edges, in scan order, spread over the frame.
std::vector<size_t> interior_pixels(const Coverage& c, size_t n) {
    std::vector<size_t> all;
    for (size_t p = 0; p < c.object.size(); ++p)
        if (c.covered(p) && !c.edge[p]) all.push_back(p);
    std::vector<size_t> r;
    for (size_t k = 0; k < n && !all.empty(); ++k) r.push_back(all[k * all.size() / n]);
    return r;
}
}  // namespace

TEST(AgreementCheck, TheSphereAgreesToBasicsTolerances) {
    const auto& [cpu, gpu] = sphere_frames();
    ASSERT_GT(interior_pixels(cpu.coverage, 1000).size(), 999u);
    test::expect_frames_agree(cpu, gpu, {"radiance", "normal"}, test::agreement_of("basic"));
}

TEST(AgreementCheck, ThreeWrongPixelsInsideAFaceFail) {
    const auto& [cpu, gpu] = sphere_frames();
    Frame wrong = gpu;
    for (size_t p : interior_pixels(cpu.coverage, 3)) wrong.aov("radiance").data[p * 3 + 1] += 0.1f;
    EXPECT_THAT(failures_of([&] { test::expect_frames_agree(cpu, wrong, {"radiance"}, test::agreement_of("basic")); }), ::testing::HasSubstr("off silhouettes and triangle edges"));
}

// The techniques that allow a fraction of outliers for discrete choices still fail when one
// interior pixel in a hundred is wrong.
TEST(AgreementCheck, OnePercentOfWrongInteriorPixelsFailsEveryTechniquesTolerances) {
    const auto& [cpu, gpu] = sphere_frames();
    Frame wrong = gpu;
    size_t interior = 0;
    for (size_t p = 0; p < cpu.coverage.object.size(); ++p) interior += cpu.coverage.covered(p) && !cpu.coverage.edge[p];
    for (size_t p : interior_pixels(cpu.coverage, interior / 100)) wrong.aov("radiance").data[p * 3] += 0.5f;
    std::vector<std::pair<std::string, FrameAgreement>> tolerances;  // every technique's and every method's
    for (const Technique* t : Registry::instance().techniques()) {
        tolerances.emplace_back(t->name(), t->agreement());
        for (const Method* m : t->methods()) tolerances.emplace_back(t->name() + "/" + m->name(), m->agreement());
    }
    for (auto& [name, tol] : tolerances) {
        SCOPED_TRACE(name);
        // A wrong value shows the same discrete choices (table entries) as the CPU, so it is never
        // counted as a flip: these frames have no choice AOVs to compare.
        tol.choices.clear();
        EXPECT_THAT(failures_of([&] { test::expect_frames_agree(cpu, wrong, {"radiance"}, tol); }), ::testing::HasSubstr("off silhouettes and triangle edges"));
    }
}

TEST(AgreementCheck, BlackFramesAgreeAboutNothing) {
    const auto& [cpu, gpu] = sphere_frames();
    Frame black_cpu = cpu, black_gpu = gpu;
    for (float& v : black_cpu.aov("radiance").data) v = 0.f;
    for (float& v : black_gpu.aov("radiance").data) v = 0.f;
    EXPECT_THAT(failures_of([&] { test::expect_frames_agree(black_cpu, black_gpu, {"radiance"}, test::agreement_of("basic")); }), ::testing::HasSubstr("is 0 on every object pixel"));
    // A black GPU frame against a lit CPU frame fails too.
    EXPECT_THAT(failures_of([&] { test::expect_frames_agree(cpu, black_gpu, {"radiance"}, test::agreement_of("basic")); }), ::testing::Not(::testing::IsEmpty()));
}

TEST(AgreementCheck, TheBackgroundIsNotCounted) {
    const auto& [cpu, gpu] = sphere_frames();
    Frame other = gpu;
    for (size_t p = 0; p < cpu.coverage.object.size(); ++p)
        if (!cpu.coverage.covered(p)) other.aov("radiance").data[p * 3] = 7.f;
    EXPECT_EQ(failures_of([&] { test::expect_frames_agree(cpu, other, {"radiance"}, test::agreement_of("basic")); }), "");
}

// Edges may differ, but only in the fraction the tolerances allow: wrong values on every edge
// pixel fail.
TEST(AgreementCheck, EveryEdgePixelWrongFails) {
    const auto& [cpu, gpu] = sphere_frames();
    Frame wrong = gpu;
    for (size_t p = 0; p < cpu.coverage.object.size(); ++p)
        if (cpu.coverage.covered(p) && cpu.coverage.edge[p]) wrong.aov("radiance").data[p * 3] += 0.5f;
    EXPECT_THAT(failures_of([&] { test::expect_frames_agree(cpu, wrong, {"radiance"}, test::agreement_of("basic")); }), ::testing::HasSubstr("covered values beyond loose"));
}
