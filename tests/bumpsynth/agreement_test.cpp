// bumpsynth CPU and GPU (llvmpipe) agree on every AOV: the same noise bits, input CDFs, nearest
// look-up-table entries and BRDF (core/bumpsynth vs gpu/bumpsynth/bumpsynth.frag).
#include "core/scene.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>

using namespace mesolab;

namespace {

// Frames of the Fig. 1 preset with `sets`, on both backends, at 160 x 120. Beyond the detail
// distance (4 in the preset) there are no octaves: the AOV is 0 on both.
void expect_agree(std::initializer_list<std::pair<const char*, const char*>> sets) {
    Workbench wb;
    Scene s = load_preset(test::source_path("presets/bumpsynth/fig1-sphere-distances.json"));
    for (const auto& [k, v] : sets) apply_set(s, k, v);
    const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 160, 120);
    if (s.camera.get_float("distance") > s.objects[0].material.get_float("detail_distance") + 1.0) {
        test::expect_frames_agree(cpu, gpu, {"radiance", "normal"}, test::agreement_of("bumpsynth"));
        test::expect_all_zero(cpu, "octaves");
        test::expect_all_zero(gpu, "octaves");
    } else {
        test::expect_frames_agree(cpu, gpu, {"radiance", "normal", "octaves"}, test::agreement_of("bumpsynth"));
    }
}
}  // namespace

// The technique's own tolerances (BumpsynthTechnique::agreement): the rasterisers' uv and position
// differ by a few ULP, which moves the noise slightly; where the inputs sit on a look-up-table cell
// edge the nearest entry changes to its neighbour (a flip, told apart by the AOVs entry and
// entry_fine), elsewhere the shading agrees to float rounding.
TEST(BumpsynthCpuGpu, AgreeAtSeveralDistances) {
    for (const char* d : {"40", "3", "0.3", "0.02"}) {
        SCOPED_TRACE(d);
        expect_agree({{"camera.distance", d}});
    }
}

// GGX's heavy tail puts far-apart normals in neighbouring table entries, so a changed entry moves
// the normal further than Beckmann's does.
TEST(BumpsynthCpuGpu, AgreeWithMaskingFresnelAndAnIsotropicGgx) {
    expect_agree({{"bumpsynth.ndf", "ggx"}, {"bumpsynth.alpha_x", "0.3"}, {"bumpsynth.alpha_y", "0.3"}, {"bumpsynth.masking", "true"}, {"bumpsynth.fresnel", "true"}});
}

// The shader reads the noise texture texel by texel and interpolates as the CPU does
// (gpu/bumpsynth/noise_texture.glsl, checked alone in noise_texture_gpu_test.cpp), so the
// technique's tolerances hold on any GL implementation, whatever its filtering.
TEST(BumpsynthCpuGpu, AgreeWithTheNoiseTexture) {
    expect_agree({{"bumpsynth.noise", "texture"}, {"bumpsynth.noise_texture_size", "256"}});
}

TEST(BumpsynthCpuGpu, AgreeInTextureSpaceAtFullDetail) {
    expect_agree({{"camera.mode", "texture"}, {"bumpsynth.octaves_max", "4"}});
}
