// Image heightfields in integer formats (OpenImageIO: 8/16-bit, float EXR/TIFF; a single channel,
// or the first channel): 8- and 16-bit PNG and TIFF, grey and RGB, written with OpenImageIO, come
// back from load_heightfield normalised to [0, 1] (not sRGB-decoded) times height_scale *
// texel_size, and through microgeom's stage graph as value * height_scale / texel_size texels
// (microgeom.texel_size, heightfield_from_material).
#include "app/workbench.h"
#include "core/microgeom/stages.h"
#include "core/heightfield/heightfield.h"
#include "core/scene.h"
#include "support/cli.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::test;

namespace {

constexpr int kW = 7, kH = 5;

// Integer code of texel (x, y), channel c, spread over the whole range [0, max] (0 and max
// included) so that both ends and a non-trivial in-between are checked. Channels 1 and 2 differ
// from channel 0, so reading the wrong channel fails.
uint32_t code(int x, int y, int c, uint32_t max) {
    const int i = y * kW + x, n = kW * kH - 1;
    const int k = c == 0 ? i : (c == 1 ? n - i : (i * 7) % (n + 1));
    return uint32_t((uint64_t(k) * max + uint64_t(n) / 2) / uint64_t(n));
}

// Writes a kW x kH image with `channels` channels of integer type T (UINT8 or UINT16) to `path`;
// the format follows the extension (.png, .tif).
template <class T>
void write_integer_image(const std::string& path, int channels) {
    const uint32_t max = sizeof(T) == 1 ? 255u : 65535u;
    std::vector<T> px(size_t(kW * kH * channels));
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            for (int c = 0; c < channels; ++c) px[size_t((y * kW + x) * channels + c)] = T(code(x, y, c, max));
    const OIIO::TypeDesc type = sizeof(T) == 1 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(kW, kH, channels, type);
    ASSERT_TRUE(out->open(path, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(type, px.data())) << out->geterror();
    ASSERT_TRUE(out->close()) << out->geterror();
}
}  // namespace

TEST(Heightfield, Loads8And16BitPngAndTiffNormalisedTimesHeightScale) {
    TempDir dir("mg-int-heightfields");
    struct Case {
        const char* file;
        int bits, channels;
    };
    const float height_scale = 3.5f, texel_size = 0.25f;
    for (const Case& c : {Case{"g8.png", 8, 1}, Case{"g16.png", 16, 1}, Case{"g8.tif", 8, 1}, Case{"g16.tif", 16, 1}, Case{"rgb8.png", 8, 3},
                          Case{"rgb16.png", 16, 3}, Case{"rgb16.tif", 16, 3}}) {
        SCOPED_TRACE(c.file);
        const std::string path = dir / c.file;
        if (c.bits == 8) write_integer_image<uint8_t>(path, c.channels);
        else write_integer_image<uint16_t>(path, c.channels);
        const Heightfield f = load_heightfield(path, height_scale, texel_size, true, vec3(0.5f));
        ASSERT_EQ(f.width, kW);
        ASSERT_EQ(f.height, kH);
        EXPECT_EQ(f.texel_size, texel_size);
        const uint32_t max = c.bits == 8 ? 255u : 65535u;
        // Normalised integer codes are exact to float rounding: 1e-6 relative to the largest height.
        const float scale = height_scale * texel_size, tol = 1e-6f * scale;
        float lo = 1e30f, hi = -1e30f;
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) {
                const float want = float(code(x, y, 0, max)) / float(max) * scale;
                ASSERT_NEAR(f.at(x, y), want, tol) << x << "," << y << " (an sRGB decode or a wrong channel would be off by up to " << scale << ")";
                lo = std::min(lo, f.at(x, y)), hi = std::max(hi, f.at(x, y));
            }
        EXPECT_NEAR(lo, 0.f, tol);    // code 0 -> 0
        EXPECT_NEAR(hi, scale, tol);  // code max -> 1 x height_scale x texel_size
    }
}

// Through the stage graph (microgeom.heightfield = a 16-bit TIFF): heights in texels are
// value * height_scale / texel_size (heightfield_from_material).
TEST(Heightfield, A16BitTiffThroughTheStagesUsesHeightScaleOverTexelSize) {
    TempDir dir("mg-int-heightfield-stage");
    const std::string path = dir / "h16.tif";
    write_integer_image<uint16_t>(path, 1);
    Scene s = default_scene("microgeom");
    apply_set(s, "camera.mode=texture");
    apply_set(s, "geometry.type=plane");
    apply_set(s, "microgeom.heightfield", path);
    apply_set(s, "microgeom.height_scale=6");
    apply_set(s, "microgeom.texel_size=0.5");
    apply_set(s, "microgeom.depth=0");
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    const RenderResult r = wb.render(s, req);
    EXPECT_EQ(r.frame.width, kW);
    const auto field = r.eval.get(microgeom::stages::heightfield, 0);
    ASSERT_TRUE(field);
    const Heightfield& f = *field;
    ASSERT_EQ(f.width, kW);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) ASSERT_NEAR(f.at(x, y), float(code(x, y, 0, 65535u)) / 65535.f * 12.f, 12e-6f) << x << "," << y;
}
