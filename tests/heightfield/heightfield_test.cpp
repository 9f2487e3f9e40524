// Heightfields (core/heightfield): the procedural fields, the queries and float images.
#include "core/error.h"
#include "core/microgeom/stages.h"
#include "core/heightfield/heightfield.h"
#include "core/image.h"
#include "support/threads.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

using namespace mesolab;

namespace {

// InputError thrown by `f`, with a message containing `needle`.
template <class F>
void expect_input_error(F&& f, const std::string& needle) {
    try {
        f();
        ADD_FAILURE() << "no InputError (expected one mentioning '" << needle << "')";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

ProceduralParams params(const std::string& name, int resolution) {
    ProceduralParams p;
    p.name = name;
    p.resolution = resolution;
    return p;
}

std::string temp_path(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("mesolab-heightfield-test-" + std::to_string(long(::getpid())));
    std::filesystem::create_directories(dir);
    return (dir / name).string();
}

// [SECTION] Heightfields
TEST(Heightfield, ProceduralFieldsHaveTheRightSizeFiniteValuesAndTile) {
    ASSERT_EQ(procedural_names().size(), 6u) << "triangles, bricks, bumps, vgrooves, gaussian, flat";
    for (const std::string& name : procedural_names())
        for (int res : {8, 13, 32, 64}) {
            SCOPED_TRACE(name + " " + std::to_string(res));
            ProceduralParams p = params(name, res);
            p.texel_size = 0.25f;
            p.height_scale = 1.5f;
            const Heightfield f = make_procedural(p);
            ASSERT_EQ(f.width, res);
            ASSERT_EQ(f.height, res);
            ASSERT_EQ(f.h.size(), size_t(res) * size_t(res));
            ASSERT_EQ(f.albedo.size(), f.h.size());
            EXPECT_TRUE(f.periodic);
            EXPECT_EQ(f.texel_size, 0.25f);
            for (float v : f.h) ASSERT_TRUE(std::isfinite(v));
            for (vec3 a : f.albedo) ASSERT_TRUE(std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z) && a.x >= 0 && a.y >= 0 && a.z >= 0);

            // Seamless tiling: the step across the wrap is no larger than the steps inside.
            float inside = 0.f, border = 0.f;
            for (int y = 0; y < res; ++y)
                for (int x = 0; x < res; ++x) {
                    const float dx = std::abs(f.at(x + 1, y) - f.at(x, y)), dy = std::abs(f.at(x, y + 1) - f.at(x, y));
                    float& into_x = x == res - 1 ? border : inside;
                    into_x = std::max(into_x, dx);
                    float& into_y = y == res - 1 ? border : inside;
                    into_y = std::max(into_y, dy);
                }
            EXPECT_LE(border, 1.25f * inside + 1e-6f) << "inside " << inside << " border " << border;
        }
}

TEST(Heightfield, AtWrapsWhenPeriodicAndClampsOtherwise) {
    ProceduralParams p = params("gaussian", 16);
    Heightfield f = make_procedural(p);
    EXPECT_EQ(f.at(-1, 3), f.h[f.index(15, 3)]);
    EXPECT_EQ(f.at(16, -2), f.h[f.index(0, 14)]);
    EXPECT_EQ(f.at(35, 40), f.h[f.index(3, 8)]);
    f.periodic = false;
    EXPECT_EQ(f.at(-1, 3), f.h[f.index(0, 3)]);
    EXPECT_EQ(f.at(16, -2), f.h[f.index(15, 0)]);
    EXPECT_EQ(f.at(35, 40), f.h[f.index(15, 15)]);
}

TEST(Heightfield, NormalsAreUnitAndFollowTheLocalFrame) {
    for (const std::string& name : procedural_names())
        for (bool periodic : {true, false}) {
            SCOPED_TRACE(name);
            ProceduralParams p = params(name, 24);
            p.periodic = periodic;
            p.texel_size = 0.1f;
            const Heightfield f = make_procedural(p);
            EXPECT_EQ(f.periodic, periodic);
            for (int y = 0; y < f.height; ++y)
                for (int x = 0; x < f.width; ++x) {
                    const vec3 n = f.normal(x, y);
                    ASSERT_NEAR(glm::length(n), 1.f, 1e-5f);
                    ASSERT_GT(n.z, 0.f);
                }
        }
    // A plane rising along local +x (columns) and along local +y (towards the top row: row y lies
    // at local y = (5 - y) texels), written out here rather than through Heightfield::position.
    Heightfield f;
    f.width = 8;
    f.height = 6;
    f.texel_size = 0.5f;
    f.periodic = false;
    f.h.resize(48);
    f.albedo.assign(48, vec3(1.f));
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 8; ++x) f.h[f.index(x, y)] = 0.5f * (float(x) * 0.5f) + 0.25f * (float(5 - y) * 0.5f);
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 8; ++x) {
            const vec3 n = f.normal(x, y), expect = glm::normalize(vec3(-0.5f, -0.25f, 1.f));
            EXPECT_NEAR(n.x, expect.x, 1e-5f);
            EXPECT_NEAR(n.y, expect.y, 1e-5f);
            EXPECT_NEAR(n.z, expect.z, 1e-5f);
        }
    EXPECT_FLOAT_EQ(f.min_height(), f.h[f.index(0, 5)]);
    EXPECT_FLOAT_EQ(f.max_height(), f.h[f.index(7, 0)]);
}

TEST(Heightfield, FlatIsFlat) {
    for (bool periodic : {true, false}) {
        ProceduralParams p = params("flat", 16);
        p.periodic = periodic;
        p.albedo = vec3(0.2f, 0.3f, 0.4f);
        const Heightfield f = make_procedural(p);
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x) {
                EXPECT_EQ(f.at(x, y), 0.f);
                EXPECT_EQ(f.normal(x, y), vec3(0.f, 0.f, 1.f));
                EXPECT_EQ(f.albedo[f.index(x, y)], p.albedo);
            }
        EXPECT_EQ(f.min_height(), 0.f);
        EXPECT_EQ(f.max_height(), 0.f);
    }
}

TEST(Heightfield, TrianglesAreRedExactlyWhereTheSlopeIsPositive) {
    for (int res : {32, 13, 64})
        for (float scale : {1.f, 2.5f, -1.f}) {
            ProceduralParams p = params("triangles", res);
            p.height_scale = scale;
            p.texel_size = 0.5f;
            const Heightfield f = make_procedural(p);
            const vec3 red(0.8f, 0.08f, 0.08f), white(0.8f);
            int reds = 0;
            for (int y = 0; y < res; ++y)
                for (int x = 0; x < res; ++x) {
                    const bool rising = f.at(x + 1, y) - f.at(x - 1, y) > 0.f;
                    EXPECT_EQ(f.albedo[f.index(x, y)], rising ? red : white);
                    EXPECT_EQ(rising, f.normal(x, y).x < 0.f);
                    EXPECT_EQ(f.at(x, y), f.at(x, 0));  // constant along y
                    reds += rising;
                }
            EXPECT_NEAR(double(reds) / double(res * res), 0.5, 0.1);
        }
    // 45-degree faces at height scale 1: every step is one texel except across peaks / valleys;
    // peaks at half the period (32/4/2 = 4 texels).
    const Heightfield f = make_procedural(params("triangles", 32));
    int full = 0;
    for (int x = 0; x < 32; ++x) {
        const float d = std::abs(f.at(x + 1, 0) - f.at(x, 0));
        EXPECT_TRUE(std::abs(d - 1.f) < 1e-5f || d < 1e-5f) << d;
        full += d > 0.5f;
    }
    EXPECT_EQ(full, 32 - 8);
    EXPECT_NEAR(f.max_height(), 3.5f, 1e-5f);  // texel centres sit half a texel off the peak
    EXPECT_NEAR(f.min_height(), 0.5f, 1e-5f);
}

TEST(Heightfield, BricksHaveMortarAndVaryingBricks) {
    ProceduralParams p = params("bricks", 128);
    p.albedo = vec3(0.8f);
    const Heightfield f = make_procedural(p);
    const vec3 mortar(0.6f, 0.6f, 0.58f);
    int mortar_count = 0;
    float lo = 1e9f, hi = -1e9f;
    for (size_t i = 0; i < f.h.size(); ++i) {
        if (f.albedo[i] == mortar) {
            ++mortar_count;
            EXPECT_EQ(f.h[i], 0.f);
        } else {
            EXPECT_GT(f.h[i], 0.f);
            EXPECT_NEAR(f.albedo[i].x / f.albedo[i].y, 0.75f / 0.3f, 1e-4f);
            lo = std::min(lo, f.albedo[i].x);
            hi = std::max(hi, f.albedo[i].x);
            EXPECT_GE(f.albedo[i].x, 0.75f * 0.9f - 1e-5f);
            EXPECT_LE(f.albedo[i].x, 0.75f * 1.1f + 1e-5f);
        }
    }
    EXPECT_GT(mortar_count, 0);
    EXPECT_LT(mortar_count, int(f.h.size()) / 4);
    EXPECT_GT(hi - lo, 0.01f);                        // per-brick variation
    EXPECT_NEAR(f.max_height(), 128.f / 4.f / 6.f, 1e-4f);  // raised by 1/6 of the course height
    // Finite slopes: no step larger than the bevel allows (slope 2).
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 128; ++x) EXPECT_LE(std::abs(f.at(x + 1, y) - f.at(x, y)), 2.f + 1e-4f);
}

TEST(Heightfield, BumpsAreAFourByFourGrid) {
    const Heightfield f = make_procedural(params("bumps", 64));
    // Cell 16 texels, radius 6.4: the peak is at the cell centre (between texels 7 and 8).
    EXPECT_NEAR(f.max_height(), 6.4f, 0.2f);
    EXPECT_EQ(f.min_height(), 0.f);
    for (int cy = 0; cy < 4; ++cy)
        for (int cx = 0; cx < 4; ++cx) {
            EXPECT_EQ(f.at(16 * cx, 16 * cy), 0.f);
            EXPECT_GT(f.at(16 * cx + 8, 16 * cy + 8), 6.f);
        }
}

TEST(Heightfield, VgrooveWallsFollowTheOpeningAngle) {
    for (float angle : {90.f, 60.f, 120.f, 30.f, 170.f}) {
        SCOPED_TRACE(angle);
        ProceduralParams p = params("vgrooves", 64);
        p.vgroove_angle = angle;
        p.texel_size = 0.01f;
        p.height_scale = 1.f;
        const Heightfield f = make_procedural(p);
        const double slope = std::tan(radians(90.f - angle / 2.f));
        int walls = 0;
        for (int x = 0; x < 64; ++x) {
            const double d = std::abs(double(f.at(x + 1, 5)) - double(f.at(x, 5))) / 0.01;
            EXPECT_TRUE(std::abs(d - slope) < 1e-4 * std::max(1.0, slope) || d < 1e-4 * slope) << d << " vs " << slope;
            walls += d > 0.5 * slope;
            EXPECT_EQ(f.at(x, 5), f.at(x, 40));
        }
        EXPECT_EQ(walls, 64 - 8);  // 4 grooves: 4 bottoms and 4 ridges between texel pairs
        // The normal on a wall is tilted by 90 - angle/2 from the base normal.
        const vec3 n = f.normal(3, 0);
        EXPECT_NEAR(std::acos(double(n.z)), double(radians(90.f - angle / 2.f)), 1e-4);
        // Texel centres sit 0.5 to 7.5 texels from the groove bottom.
        EXPECT_NEAR(f.max_height() - f.min_height(), 0.01 * slope * 7.0, 1e-4 * std::max(1.0, slope));
    }
    for (float bad : {0.5f, 179.5f, 0.f, 180.f, std::nanf("")}) {
        ProceduralParams p = params("vgrooves", 16);
        p.vgroove_angle = bad;
        expect_input_error([&] { make_procedural(p); }, "microgeom.vgroove_angle");
    }
}

// RMS slope of a field in texel units (central differences over both axes, Beckmann convention
// m^2 = <|grad h|^2>), undoing height_scale * texel_size.
double rms_slope(const Heightfield& f, double unit) {
    double sum = 0.0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            const double gx = 0.5 * (double(f.at(x + 1, y)) - double(f.at(x - 1, y))) / unit;
            const double gy = 0.5 * (double(f.at(x, y + 1)) - double(f.at(x, y - 1))) / unit;
            sum += gx * gx + gy * gy;
        }
    return std::sqrt(sum / double(f.width * f.height));
}

TEST(Heightfield, GaussianHasTheRequestedRmsSlopeAndIsIndependentOfTheThreadCount) {
    struct Case {
        int res;
        float rms, corr, scale, texel;
        uint32_t seed;
    };
    for (const Case& c : {Case{64, 0.5f, 4.f, 1.f, 1.f, 1}, Case{37, 0.2f, 2.5f, 2.f, 0.01f, 7}, Case{128, 1.3f, 10.f, 0.5f, 3.f, 99},
                          Case{16, 0.05f, 0.7f, 1.f, 1.f, 3},
                          Case{16, 0.5f, 4.f, 1.f, 1.f, 5}, Case{8, 0.5f, 8.f, 1.f, 1.f, 6} /* kernels longer than the period: folded */}) {
        ProceduralParams p = params("gaussian", c.res);
        p.rms_slope = c.rms;
        p.correlation = c.corr;
        p.height_scale = c.scale;
        p.texel_size = c.texel;
        p.seed = c.seed;
        // The convolution runs in parallel blocks: one thread and many give the same heights.
        const Heightfield f = test::with_threads(test::kManyThreads, [&] { return make_procedural(p); });
        EXPECT_NEAR(rms_slope(f, double(c.scale) * double(c.texel)), double(c.rms), 1e-4);
        const Heightfield g = test::with_threads(1, [&] { return make_procedural(p); });
        EXPECT_EQ(f.h, g.h);
        p.seed = c.seed + 1;
        const Heightfield h = make_procedural(p);
        EXPECT_NE(f.h, h.h);
        EXPECT_NEAR(rms_slope(h, double(c.scale) * double(c.texel)), double(c.rms), 1e-4);
        double mean = 0.0;
        for (float v : f.h) mean += double(v);
        EXPECT_NEAR(mean / double(f.h.size()), 0.0, 1e-4 * double(c.scale) * double(c.texel) * double(c.res));
    }
    ProceduralParams p = params("gaussian", 32);
    p.rms_slope = -0.1f;
    expect_input_error([&] { make_procedural(p); }, "microgeom.rms_slope");
    p = params("gaussian", 32);
    p.correlation = 0.f;
    expect_input_error([&] { make_procedural(p); }, "microgeom.correlation");
    p.correlation = 32.5f;  // more than the resolution
    expect_input_error([&] { make_procedural(p); }, "microgeom.correlation");
    p = params("gaussian", 256);
    p.correlation = 65.f;  // more than 64
    expect_input_error([&] { make_procedural(p); }, "microgeom.correlation");
    p.correlation = 64.f;
    EXPECT_NO_THROW(make_procedural(p));
}

TEST(Heightfield, BadParametersAreInputErrors) {
    expect_input_error([] { make_procedural(params("bricks", 7)); }, "microgeom.resolution");
    expect_input_error([] { make_procedural(params("bricks", 4097)); }, "microgeom.resolution");
    expect_input_error([] { make_procedural(params("brick", 32)); }, "microgeom.heightfield");  // the key
    expect_input_error([] { make_procedural(params("brick", 32)); }, "did you mean 'bricks'");
    ProceduralParams p = params("bumps", 32);
    p.texel_size = 0.f;
    expect_input_error([&] { make_procedural(p); }, "microgeom.texel_size");
    EXPECT_NO_THROW(make_procedural(params("bricks", 8)));
    EXPECT_NO_THROW(make_procedural(params("flat", 4096)));
}

TEST(Heightfield, LoadsFloatExrAndRejectsNaN) {
    Image img(5, 4, 1);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 5; ++x) img.at(x, y)[0] = float(x) * 0.5f - float(y) + 0.125f;
    const std::string good = temp_path("good.exr");
    write_exr(good, img);
    const Heightfield f = load_heightfield(good, 2.f, 0.25f, false, vec3(0.1f, 0.2f, 0.3f));
    ASSERT_EQ(f.width, 5);
    ASSERT_EQ(f.height, 4);
    EXPECT_FALSE(f.periodic);
    EXPECT_EQ(f.texel_size, 0.25f);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 5; ++x) {
            EXPECT_FLOAT_EQ(f.at(x, y), img.at(x, y)[0] * 0.5f);
            EXPECT_EQ(f.albedo[f.index(x, y)], vec3(0.1f, 0.2f, 0.3f));
        }

    Image rgb(3, 3, 3, 0.5f);
    rgb.at(1, 1)[0] = 2.f;
    rgb.at(1, 1)[1] = 7.f;
    const std::string colour = temp_path("rgb.exr");
    write_exr(colour, rgb);
    const Heightfield c = load_heightfield(colour, 1.f, 1.f, true, vec3(1.f));
    EXPECT_EQ(c.at(1, 1), 2.f);  // the first channel
    EXPECT_EQ(c.at(0, 0), 0.5f);

    img.at(2, 1)[0] = std::nanf("");
    const std::string bad = temp_path("nan.exr");
    write_exr(bad, img);
    expect_input_error([&] { load_heightfield(bad, 1.f, 1.f, true, vec3(1.f)); }, bad);
    expect_input_error([&] { load_heightfield(bad, 1.f, 1.f, true, vec3(1.f)); }, "NaN");
    const std::string missing = temp_path("missing.exr");
    expect_input_error([&] { load_heightfield(missing, 1.f, 1.f, true, vec3(1.f)); }, missing);
    const std::string text = temp_path("not-an-image.exr");
    {
        FILE* fp = std::fopen(text.c_str(), "w");
        ASSERT_NE(fp, nullptr);
        std::fputs("hello", fp);
        std::fclose(fp);
    }
    expect_input_error([&] { load_heightfield(text, 1.f, 1.f, true, vec3(1.f)); }, text);
    std::error_code ec;
    std::filesystem::remove_all(std::filesystem::path(good).parent_path(), ec);
}
}  // namespace
