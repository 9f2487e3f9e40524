// microgeom heightfields (procedural and from images) and direction sets (Fibonacci lattice,
// convex-hull triangulation, solid-angle shares, locate / nearest queries).
#include "core/error.h"
#include "core/image.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/heightfield.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <unistd.h>

using namespace mesolab;
using namespace mesolab::microgeom;

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

double det3(vec3 a, vec3 b, vec3 c) {
    const glm::dvec3 da(a), db(b), dc(c);
    return glm::dot(da, glm::cross(db, dc));
}

std::string temp_path(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / ("mesolab-microgeom-test-" + std::to_string(long(::getpid())));
    std::filesystem::create_directories(dir);
    return (dir / name).string();
}

// [SECTION] Heightfields
TEST(Heightfield, ProceduralFieldsHaveTheRightSizeFiniteValuesAndTile) {
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
    // A plane rising along local +x and along local +y (towards the top row).
    Heightfield f;
    f.width = 8;
    f.height = 6;
    f.texel_size = 0.5f;
    f.periodic = false;
    f.h.resize(48);
    f.albedo.assign(48, vec3(1.f));
    for (int y = 0; y < 6; ++y)
        for (int x = 0; x < 8; ++x) f.h[f.index(x, y)] = f.position(x, y).x * 0.5f + f.position(x, y).y * 0.25f;
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

TEST(Heightfield, GaussianHasTheRequestedRmsSlopeAndIsDeterministic) {
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
        const Heightfield f = make_procedural(p);
        EXPECT_NEAR(rms_slope(f, double(c.scale) * double(c.texel)), double(c.rms), 1e-4);
        const Heightfield g = make_procedural(p);
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
    expect_input_error([] { make_procedural(params("brick", 32)); }, "microgeom.heightfield");
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

// [SECTION] Direction sets
TEST(Directions, BadCountsAreInputErrors) {
    for (int n : {-1, 0, 3, 65537}) expect_input_error([n] { make_direction_set(n); }, "microgeom.directions");
}

TEST(Directions, SphericalTriangleArea) {
    EXPECT_NEAR(spherical_triangle_area({1, 0, 0}, {0, 1, 0}, {0, 0, 1}), kPi / 2.f, 1e-6f);
    EXPECT_NEAR(spherical_triangle_area({1, 0, 0}, {0, 0, 1}, {0, 1, 0}), kPi / 2.f, 1e-6f);  // orientation-free
    const vec3 a = glm::normalize(vec3(1e-3f, 0, 1)), b = glm::normalize(vec3(0, 1e-3f, 1)), c(0, 0, 1);
    EXPECT_NEAR(spherical_triangle_area(a, b, c), 0.5e-6f, 1e-9f);  // small: the planar area
    // Three points on the equator 120 degrees apart bound a hemisphere (negative denominator).
    EXPECT_NEAR(spherical_triangle_area({1, 0, 0}, {-0.5f, 0.8660254f, 0}, {-0.5f, -0.8660254f, 0}), 2.f * kPi, 1e-5f);
    // A large triangle (> pi) against Girard's theorem (angle excess).
    const vec3 v[3] = {glm::normalize(vec3(1, 0, -0.2f)), glm::normalize(vec3(-0.5f, 0.866f, -0.2f)), glm::normalize(vec3(-0.5f, -0.866f, -0.3f))};
    double excess = -3.14159265358979323846;
    for (int k = 0; k < 3; ++k) {
        const glm::dvec3 a(v[k]), b(v[(k + 1) % 3]), c(v[(k + 2) % 3]);
        const glm::dvec3 tb = glm::normalize(b - glm::dot(a, b) * a), tc = glm::normalize(c - glm::dot(a, c) * a);
        excess += std::acos(glm::dot(tb, tc));
    }
    const float big = spherical_triangle_area(v[0], v[1], v[2]);
    EXPECT_GT(big, kPi);
    EXPECT_NEAR(double(big), excess, 1e-5);
}

void check_triangulation(const DirectionSet& s, int n, bool uniformity) {
    ASSERT_EQ(s.size(), n);
    for (vec3 d : s.d) ASSERT_NEAR(glm::length(d), 1.f, 1e-6f);
    ASSERT_EQ(s.triangles.size(), size_t(2 * n - 4));
    std::map<std::pair<int, int>, int> edges;  // directed edge -> count
    for (const auto& t : s.triangles) {
        ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]);
        for (int k = 0; k < 3; ++k) {
            ASSERT_GE(t[size_t(k)], 0);
            ASSERT_LT(t[size_t(k)], n);
            ++edges[{t[size_t(k)], t[size_t((k + 1) % 3)]}];
        }
        // Counter-clockwise seen from outside.
        EXPECT_GT(det3(s.d[size_t(t[0])], s.d[size_t(t[1])], s.d[size_t(t[2])]), 0.0);
    }
    // Every edge is shared by exactly two triangles, once in each direction.
    EXPECT_EQ(edges.size(), size_t(3 * (2 * n - 4)));
    for (const auto& [e, count] : edges) {
        ASSERT_EQ(count, 1);
        const auto it = edges.find({e.second, e.first});
        ASSERT_TRUE(it != edges.end()) << e.first << "-" << e.second;
        ASSERT_EQ(it->second, 1);
    }
    // Convex hull: no direction lies above a triangle's plane.
    if (n <= 1024)
        for (const auto& t : s.triangles) {
            const glm::dvec3 a(s.d[size_t(t[0])]), b(s.d[size_t(t[1])]), c(s.d[size_t(t[2])]);
            const glm::dvec3 nrm = glm::cross(b - a, c - a);
            for (int i = 0; i < n; ++i) ASSERT_LE(glm::dot(nrm, glm::dvec3(s.d[size_t(i)]) - a), 1e-9);
        }
    // Shares: positive, sum to 4 pi, nearly uniform; fans list the adjacent triangles.
    ASSERT_EQ(s.solid_angle.size(), size_t(n));
    ASSERT_EQ(s.fan.size(), size_t(n));
    double sum = 0.0;
    float lo = 1e9f, hi = 0.f;
    for (int i = 0; i < n; ++i) {
        EXPECT_GT(s.solid_angle[size_t(i)], 0.f);
        sum += double(s.solid_angle[size_t(i)]);
        lo = std::min(lo, s.solid_angle[size_t(i)]);
        hi = std::max(hi, s.solid_angle[size_t(i)]);
        ASSERT_GE(s.fan[size_t(i)].size(), 3u);
        for (int t : s.fan[size_t(i)]) {
            const auto& tri = s.triangles[size_t(t)];
            EXPECT_TRUE(tri[0] == i || tri[1] == i || tri[2] == i);
        }
    }
    EXPECT_NEAR(sum, 4.0 * 3.14159265358979323846, 1e-4);
    if (uniformity) {
        EXPECT_LT(hi / lo, 2.5f) << "min " << lo << " max " << hi;
    }
}

TEST(Directions, FibonacciTriangulationIsAValidHull) {
    for (int n : {4, 5, 6, 7, 16, 100, 1024}) {
        SCOPED_TRACE(n);
        const DirectionSet s = make_direction_set(n);
        check_triangulation(s, n, n >= 16);
        for (int i = 0; i < n; ++i) EXPECT_NEAR(s.d[size_t(i)].z, 1.f - (2.f * float(i) + 1.f) / float(n), 1e-6f);
    }
}

TEST(Directions, LargeSetsAreValidAndDeterministic) {
    const DirectionSet a = make_direction_set(16384), b = make_direction_set(16384);
    check_triangulation(a, 16384, true);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.solid_angle, b.solid_angle);
}

TEST(Directions, LocateFindsTheContainingTriangle) {
    for (int n : {4, 16, 100, 1024}) {
        SCOPED_TRACE(n);
        const DirectionSet s = make_direction_set(n);
        std::mt19937 rng(42);
        std::normal_distribution<float> g;
        const float size = std::sqrt(4.f * kPi / float(n));  // typical spacing
        for (int k = 0; k < 10000; ++k) {
            vec3 w(g(rng), g(rng), g(rng));
            if (glm::length(w) < 1e-3f) continue;
            w = glm::normalize(w);
            vec3 bary;
            const int t = s.locate(w, bary);
            ASSERT_GE(t, 0);
            ASSERT_LT(t, int(s.triangles.size()));
            const auto& tri = s.triangles[size_t(t)];
            const vec3 a = s.d[size_t(tri[0])], b = s.d[size_t(tri[1])], c = s.d[size_t(tri[2])];
            ASSERT_GE(det3(a, b, w), -1e-6);
            ASSERT_GE(det3(b, c, w), -1e-6);
            ASSERT_GE(det3(c, a, w), -1e-6);
            ASSERT_GE(bary.x, 0.f);
            ASSERT_GE(bary.y, 0.f);
            ASSERT_GE(bary.z, 0.f);
            ASSERT_NEAR(bary.x + bary.y + bary.z, 1.f, 1e-5f);
            const vec3 r = glm::normalize(bary.x * a + bary.y * b + bary.z * c);
            ASSERT_LT(glm::length(r - w), 1e-4f * std::max(1.f, size));
            // nearest() agrees with brute force (up to ties).
            const int near = s.nearest(w);
            float best = -2.f;
            for (vec3 d : s.d) best = std::max(best, glm::dot(d, w));
            ASSERT_GE(glm::dot(s.d[size_t(near)], w), best - 1e-6f);
        }
        // At a direction itself: all the weight on that corner.
        for (int i = 0; i < n; ++i) {
            vec3 bary;
            const int t = s.locate(s.d[size_t(i)], bary);
            const auto& tri = s.triangles[size_t(t)];
            float wi = 0.f;
            for (int k = 0; k < 3; ++k)
                if (tri[size_t(k)] == i) wi = bary[k];
            EXPECT_NEAR(wi, 1.f, 1e-4f) << "direction " << i;
            EXPECT_EQ(s.nearest(s.d[size_t(i)]), i);
        }
    }
}
}  // namespace
