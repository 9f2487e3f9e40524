// Shading with a fitted fabric (core/cloth/reflectance.h): the level follows the footprint, level 0
// reproduces the point's model, and mip blending reduces the flicker of a distant moving garment.
#include "core/cloth/acquire.h"
#include "core/cloth/reflectance.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
// A fitted pyramid over a real stitch: knit, 16 × 16 points, 8 × 8 directions, one lobe.
const BrdfPyramid& knit_pyramid() {
    static const BrdfPyramid p = [] {
        StitchParams sp;
        sp.stitch = "knit";
        const StitchMesh s = build_stitch_mesh(make_stitch(sp), 24);
        AcquireParams ap;
        ap.spatial = 16;
        ap.directions = 8;
        ap.visibility_rays = 16;
        FitOptions o;
        o.lobes = 1;
        return fit_pyramid(acquire(s, ap), o);
    }();
    return p;
}
}  // namespace

TEST(ClothShade, TheLevelFollowsTheFootprint) {
    const BrdfPyramid& p = knit_pyramid();
    ASSERT_EQ(p.level.size(), 5u);  // 16, 8, 4, 2, 1
    const dvec3 l = glm::normalize(dvec3(0.3, 0.2, 1.0)), v = glm::normalize(dvec3(-0.2, 0.1, 1.0)), E(1.0);
    // A pixel per point: level 0; 4 points per pixel: level 2; a whole tile or more: the top.
    EXPECT_EQ(shade(p, {0.3, 0.6}, 1.0 / 16.0, MipMode::Nearest, 0.0, l, v, E).level, 0.0);
    EXPECT_EQ(shade(p, {0.3, 0.6}, 4.0 / 16.0, MipMode::Nearest, 0.0, l, v, E).level, 2.0);
    EXPECT_EQ(shade(p, {0.3, 0.6}, 7.0, MipMode::Nearest, 0.0, l, v, E).level, 4.0);
    EXPECT_EQ(shade(p, {0.3, 0.6}, 7.0, MipMode::Off, 0.0, l, v, E).level, 0.0);
    EXPECT_NEAR(shade(p, {0.3, 0.6}, std::pow(2.0, 1.25) / 16.0, MipMode::Blend, 0.0, l, v, E).level, 1.25, 1e-12);
    EXPECT_NEAR(shade(p, {0.3, 0.6}, 1.0 / 16.0, MipMode::Blend, 1.5, l, v, E).level, 1.5, 1e-12);  // the bias
    // Level 0 reads the point under uv, in its own frame, times cos θ_l and E.
    const dvec2 uv(0.3 + 3.0, 0.6 - 2.0);  // repeats wrap
    const ClothSample s = shade(p, uv, 1e-3, MipMode::Blend, 0.0, l, v, dvec3(2.0, 1.0, 0.5));
    const size_t at = size_t(0.6 * 16) * 16 + size_t(0.3 * 16);
    EXPECT_EQ(s.index, int(at));
    const glm::dmat3& F = p.frame[0][at];
    const dvec3 want = p.level[0][at].f(F * l, F * v) * (F * l).z * dvec3(2.0, 1.0, 0.5);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.radiance[c], want[c], 1e-12 * std::max(1.0, want[c]));
    EXPECT_EQ(s.alpha, p.level[0][at].alpha(F * v));
    EXPECT_THROW(mip_mode_named("trilinear"), InputError);
}

// A distant garment moving by a fraction of a tile per frame, each pixel covering 0.2 tiles
// (3.2 sample points a side: levels 1 and 2 blended) or 2.3 tiles (the top level): without
// mip-mapping every pixel reads one point of the pattern, a different one each frame, and
// flickers; the levels average the pixel's footprint.
TEST(ClothShade, MipBlendingReducesTheFlickerOfADistantMovingGarment) {
    const BrdfPyramid& p = knit_pyramid();
    const dvec3 l = glm::normalize(dvec3(0.4, 0.3, 1.0)), v = glm::normalize(dvec3(-0.3, 0.2, 1.0)), E(1.0);
    const int W = 24, frames = 12;
    auto flicker = [&](MipMode mode, double footprint) {
        double var = 0.0;
        for (int y = 0; y < W; ++y)
            for (int x = 0; x < W; ++x) {
                double sum = 0.0, sum2 = 0.0;
                for (int f = 0; f < frames; ++f) {
                    const dvec2 uv = dvec2(x, y) * footprint + dvec2(0.137, 0.071) * double(f);
                    const ClothSample s = shade(p, uv, footprint, mode, 0.0, l, v, E);
                    const double lum = s.alpha * (s.radiance.x + s.radiance.y + s.radiance.z) / 3.0;  // over black
                    sum += lum, sum2 += lum * lum;
                }
                const double m = sum / frames;
                var += sum2 / frames - m * m;
            }
        return var / double(W * W);
    };
    for (const double footprint : {0.2, 2.3}) {
        const double off = flicker(MipMode::Off, footprint), nearest = flicker(MipMode::Nearest, footprint), blend = flicker(MipMode::Blend, footprint);
        std::printf("footprint %.1f tiles: mean pixel variance over %d frames: off %.3e, nearest %.3e, blend %.3e\n", footprint, frames, off, nearest, blend);
        RecordProperty("variance_off_" + std::to_string(footprint), std::to_string(off));
        RecordProperty("variance_blend_" + std::to_string(footprint), std::to_string(blend));
        EXPECT_GT(off, 0.0);
        EXPECT_LT(blend, 0.5 * off) << footprint;
        EXPECT_LT(nearest, off) << footprint;
    }
}
