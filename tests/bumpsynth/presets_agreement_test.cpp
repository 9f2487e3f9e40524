// The bumpsynth presets as the gallery renders them (512 x 512), CPU against GPU (llvmpipe), to the
// technique's tolerances (BumpsynthTechnique::agreement): the quick part of tests/gallery for this
// technique, and a check that the tolerances still catch a few wrong pixels.
#include "core/scene.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <string>

using namespace mesolab;

namespace {
const char* const kPresets[] = {"fig1-sphere-distances", "fig4-teapot-ndf", "fig4-teapot-uniform", "fig5-teapot-hardware", "sec7-index-map-zoom",
                                "sec7-same-surface"};
const std::vector<std::string> kAovs = {"radiance", "normal", "entry", "entry_fine"};

Scene preset(const std::string& name) { return load_preset(test::source_path("presets/bumpsynth/" + name + ".json")); }
}  // namespace

TEST(BumpsynthCpuGpu, PresetsAgreeAtTheGallerySize) {
    Workbench wb;
    for (const char* name : kPresets) {
        SCOPED_TRACE(name);
        const Scene s = preset(name);
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 512, 512, kAovs);
        test::expect_frames_agree(s, cpu, gpu, {"radiance", "normal"});
    }
}

// Three pixels inside a face made wrong on the GPU side fail: off by 2e-3 with the same table
// entries, or with an entry two steps away; an entry one step away is a flip, counted apart.
TEST(BumpsynthCpuGpu, AFewWrongInteriorPixelsFail) {
    Workbench wb;
    const Scene s = preset("fig1-sphere-distances");
    auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 256, 256, kAovs);
    const FrameAgreement tol = test::agreement_of("bumpsynth");
    const auto figures = [&] { return test::compare_aov(cpu, gpu, "radiance", [&](int) -> const FrameAgreement& { return tol; }); };
    const test::AgreementFigures before = figures();
    ASSERT_EQ(before.interior_beyond_max, 0u);
    // Interior pixels whose entries agree, at bumps (k > 0).
    std::vector<std::pair<int, int>> picked;
    for (int y = 0; y < cpu.height && picked.size() < 3; y += 7)
        for (int x = 0; x < cpu.width && picked.size() < 3; x += 7) {
            const size_t p = size_t(y) * size_t(cpu.width) + size_t(x);
            if (!cpu.coverage.covered(p) || cpu.coverage.edge[p] || cpu.aov("entry").at(x, y)[2] < 1.f) continue;
            if (!test::is_flip(cpu, gpu, tol, x, y) && cpu.aov("entry").at(x, y)[0] == gpu.aov("entry").at(x, y)[0]) picked.emplace_back(x, y);
        }
    ASSERT_EQ(picked.size(), 3u);
    const auto [x0, y0] = picked[0];
    const auto [x1, y1] = picked[1];
    const auto [x2, y2] = picked[2];
    gpu.aov("radiance").at(x0, y0)[1] += 2e-3f;  // same entries, shading off
    gpu.aov("radiance").at(x1, y1)[0] += 0.5f;   // an entry two steps away
    gpu.aov("entry").at(x1, y1)[0] += 2.f;
    gpu.aov("radiance").at(x2, y2)[0] += 0.5f;   // the neighbouring entry: a flip
    gpu.aov("entry_fine").at(x2, y2)[1] += 1.f;
    const test::AgreementFigures after = figures();
    EXPECT_EQ(after.interior_beyond_max, 2u);
    EXPECT_EQ(after.interior_flips, before.interior_flips + 1);
}
