// Tests for core/image (sRGB, PNG/EXR I/O), core/env (lookup, SH irradiance), core/plot and core/text.
#include "core/env.h"
#include "core/error.h"
#include "core/image.h"
#include "core/plot.h"
#include "core/text.h"

#include <OpenImageIO/imageio.h>
#include "support/errors.h"
#include "support/threads.h"
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <thread>

namespace fs = std::filesystem;
using namespace mesolab;
using mesolab::test::expect_input_error;

namespace {

// A fresh folder per test, removed afterwards.
class TempDir : public ::testing::Test {
  protected:
    void SetUp() override {
        static int counter = 0;
        dir = fs::temp_directory_path() /
              ("mesolab_img_test_" + std::to_string(long(::getpid())) + "_" + std::to_string(counter++));
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir, ec);
    }
    std::string path(const std::string& name) const { return (dir / name).string(); }
    fs::path dir;
};

std::string file_bytes(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

void write_text(const std::string& p, const std::string& text) {
    std::ofstream f(p, std::ios::binary);
    f << text;
}

Image random_image(int w, int h, int c, unsigned seed, float lo = -4.f, float hi = 1000.f) {
    Image img(w, h, c);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> d(lo, hi);
    for (float& v : img.data) v = d(rng);
    return img;
}

bool all_finite(const Image& img) {
    for (float v : img.data)
        if (!std::isfinite(v)) return false;
    return true;
}
}  // namespace

// sRGB
TEST(Srgb, RoundTripAll256Codes) {
    for (int c = 0; c < 256; ++c) {
        const float lin = srgb_to_linear(float(c) / 255.f);
        EXPECT_EQ(int(linear_to_srgb8(lin)), c) << "code " << c;
        EXPECT_NEAR(linear_to_srgb(lin), float(c) / 255.f, 1e-6f);
    }
}

TEST(Srgb, KnownValuesAndClamping) {
    EXPECT_EQ(linear_to_srgb(0.f), 0.f);
    EXPECT_EQ(linear_to_srgb(1.f), 1.f);
    EXPECT_NEAR(srgb_to_linear(0.5f), 0.2140411f, 1e-6f);
    EXPECT_NEAR(linear_to_srgb(0.0031308f), 0.0404500f, 1e-6f);
    EXPECT_NEAR(linear_to_srgb(0.001f), 0.01292f, 1e-7f);  // linear segment
    EXPECT_EQ(linear_to_srgb8(-1.f), 0);
    EXPECT_EQ(linear_to_srgb8(7.f), 255);
    EXPECT_EQ(linear_to_srgb8(std::numeric_limits<float>::quiet_NaN()), 0);
    EXPECT_EQ(linear_to_srgb8(0.5f), 188);  // 0.735357 * 255 = 187.52
}

// PNG
using PngIo = TempDir;

TEST_F(PngIo, WriteReadGivesBackCodesExactly) {
    Image img(16, 16, 3);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> d(-0.1f, 1.2f);
    for (int i = 0; i < 256; ++i) {
        float* p = img.at(i % 16, i / 16);
        p[0] = srgb_to_linear(float(i) / 255.f);  // every code once
        p[1] = d(rng);
        p[2] = d(rng);
    }
    const std::string p = path("codes.png");
    write_png_srgb(p, img);

    const Image raw = read_image(p);  // stored codes / 255
    ASSERT_EQ(raw.width, 16);
    ASSERT_EQ(raw.height, 16);
    ASSERT_EQ(raw.channels, 3);
    for (size_t i = 0; i < img.data.size(); ++i)
        ASSERT_EQ(int(std::lround(raw.data[i] * 255.f)), int(linear_to_srgb8(img.data[i]))) << "value " << i;

    const Image lin = read_image(p, /*srgb_to_linear_8bit=*/true);
    for (size_t i = 0; i < img.data.size(); ++i)
        ASSERT_EQ(linear_to_srgb8(lin.data[i]), linear_to_srgb8(img.data[i])) << "value " << i;
    for (int i = 0; i < 256; ++i) EXPECT_FLOAT_EQ(lin.at(i % 16, i / 16)[0], srgb_to_linear(float(i) / 255.f));
}

TEST_F(PngIo, GreyAndStraightAlpha) {
    Image grey(5, 3, 1);
    for (size_t i = 0; i < grey.data.size(); ++i) grey.data[i] = float(i) / 14.f;
    write_png_srgb(path("grey.png"), grey);
    const Image g = read_image(path("grey.png"));
    ASSERT_EQ(g.channels, 1);
    for (size_t i = 0; i < grey.data.size(); ++i) EXPECT_EQ(int(std::lround(g.data[i] * 255.f)), linear_to_srgb8(grey.data[i]));

    Image rgba(4, 2, 4);
    for (int i = 0; i < 8; ++i) {
        float* p = rgba.at(i % 4, i / 4);
        p[0] = 1.f, p[1] = 0.5f, p[2] = 0.f, p[3] = float(i) / 7.f;  // alpha is written linearly
    }
    write_png_srgb(path("rgba.png"), rgba);
    const Image a = read_image(path("rgba.png"), true);
    ASSERT_EQ(a.channels, 4);
    for (int i = 0; i < 8; ++i) {
        const float* p = a.at(i % 4, i / 4);
        EXPECT_EQ(int(std::lround(p[3] * 255.f)), int(std::lround(float(i) / 7.f * 255.f)));
        if (i > 0) {  // colour stays as written (not premultiplied)
            EXPECT_EQ(linear_to_srgb8(p[0]), 255);
            EXPECT_EQ(linear_to_srgb8(p[1]), 188);
        }
    }
}

TEST_F(PngIo, Rgba8WithFlip) {
    const int w = 3, h = 2;
    std::vector<uint8_t> px(size_t(w * h * 4));
    for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t(i * 10 + 1);
    write_png_rgba8(path("flip.png"), w, h, px.data(), true);
    write_png_rgba8(path("noflip.png"), w, h, px.data(), false);
    const Image f = read_image(path("flip.png")), n = read_image(path("noflip.png"));
    ASSERT_EQ(f.channels, 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 4; ++c) {
                EXPECT_EQ(int(std::lround(n.at(x, y)[c] * 255.f)), px[size_t((y * w + x) * 4 + c)]);
                EXPECT_EQ(int(std::lround(f.at(x, y)[c] * 255.f)), px[size_t(((h - 1 - y) * w + x) * 4 + c)]);
            }
}

// EXR
using ExrIo = TempDir;

TEST_F(ExrIo, BitExactRoundTripForAnyChannelCount) {
    for (int c : {1, 2, 3, 4, 5, 12}) {
        Image img = random_image(7, 5, c, unsigned(c));
        img.data[0] = 1e-40f;  // denormal
        img.data[1] = -0.f;
        img.data[2] = 3.4e38f;
        const std::string p = path("img" + std::to_string(c) + ".exr");
        write_exr(p, img);
        const Image back = read_image(p);
        ASSERT_EQ(back.width, 7);
        ASSERT_EQ(back.height, 5);
        ASSERT_EQ(back.channels, c);
        ASSERT_EQ(back.data.size(), img.data.size());
        EXPECT_EQ(std::memcmp(back.data.data(), img.data.data(), img.data.size() * sizeof(float)), 0)
            << c << " channels";
    }
}

TEST_F(ExrIo, IdenticalInputGivesIdenticalBytes) {
    const Image img = random_image(33, 17, 4, 3, 0.f, 1.f);
    int debug_before = -1, debug_after = -2;
    OIIO::getattribute("debug", debug_before);
    write_exr(path("a.exr"), img);
    write_png_srgb(path("a.png"), img);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // a timestamp would differ
    write_exr(path("b.exr"), img);
    write_png_srgb(path("b.png"), img);
    const std::string exr = file_bytes(path("a.exr")), png = file_bytes(path("a.png"));
    ASSERT_FALSE(exr.empty());
    ASSERT_FALSE(png.empty());
    EXPECT_EQ(exr, file_bytes(path("b.exr")));
    EXPECT_EQ(png, file_bytes(path("b.png")));
    EXPECT_EQ(exr.find("capDate"), std::string::npos);
    EXPECT_EQ(exr.find("DateTime"), std::string::npos);
    EXPECT_EQ(png.find("tIME"), std::string::npos);
    OIIO::getattribute("debug", debug_after);  // the writer restores OIIO's debug level
    EXPECT_EQ(debug_before, debug_after);
    const Image back = read_image(path("a.exr"));
    EXPECT_EQ(std::memcmp(back.data.data(), img.data.data(), img.data.size() * sizeof(float)), 0);
}

TEST_F(ExrIo, NonFiniteTexelIsInputErrorNamingFileAndTexel) {
    Image img(4, 3, 3, 0.5f);
    img.at(2, 1)[1] = std::numeric_limits<float>::quiet_NaN();
    const std::string p = path("nan.exr");
    write_exr(p, img);
    expect_input_error([&] { read_image(p); }, {p, "texel (2, 1) channel 1 is NaN", "finite values expected"});
    const Image raw = read_image(p, false, /*reject_nonfinite=*/false);
    EXPECT_TRUE(std::isnan(raw.at(2, 1)[1]));

    img.at(2, 1)[1] = 0.f;
    img.at(0, 2)[2] = -std::numeric_limits<float>::infinity();
    write_exr(p, img);
    expect_input_error([&] { read_image(p); }, {p, "texel (0, 2) channel 2 is -Inf"});
}

// Read errors
using ReadErrors = TempDir;

TEST_F(ReadErrors, MissingFile) {
    const std::string p = path("missing.exr");
    expect_input_error([&] { read_image(p); }, {p + ": no such file"});
}

TEST_F(ReadErrors, TextFileNamedPng) {
    const std::string p = path("not_an_image.png");
    write_text(p, "this is plain text, not a PNG\n");
    expect_input_error([&] { read_image(p); }, {p + ": cannot read image"});
}

TEST_F(ReadErrors, Folder) {
    expect_input_error([&] { read_image(dir.string()); }, {dir.string() + ": cannot read image"});
}

// Atomic writing
using AtomicWrite = TempDir;

TEST_F(AtomicWrite, CreatesParentFolders) {
    const std::string p = path("a/b/c/out.png");
    write_png_srgb(p, Image(2, 2, 3, 0.25f));
    EXPECT_TRUE(fs::is_regular_file(p));
    write_exr(path("d/e/out.exr"), Image(2, 2, 3, 0.25f));
    EXPECT_TRUE(fs::is_regular_file(path("d/e/out.exr")));
}

TEST_F(AtomicWrite, ParentIsARegularFile) {
    write_text(path("blocker"), "x");
    const std::string png = path("blocker/out.png"), exr = path("blocker/sub/out.exr");
    expect_input_error([&] { write_png_srgb(png, Image(2, 2, 3)); }, {png});
    expect_input_error([&] { write_exr(exr, Image(2, 2, 3)); }, {exr});
    std::vector<uint8_t> px(16, 255);
    expect_input_error([&] { write_png_rgba8(png, 2, 2, px.data(), false); }, {png});
    EXPECT_EQ(file_bytes(path("blocker")), "x");
}

TEST_F(AtomicWrite, FailureLeavesExistingFileUntouched) {
    // The writer fails half-way (its temporary file cannot be created because a folder of that
    // name is in the way); the file already at the target must keep its bytes.
    const std::string png = path("keep.png"), exr = path("keep.exr");
    write_png_srgb(png, Image(4, 4, 3, 0.2f));
    write_exr(exr, Image(4, 4, 3, 0.2f));
    const std::string png_before = file_bytes(png), exr_before = file_bytes(exr);
    const std::string suffix = ".tmp-" + std::to_string(long(::getpid()));
    fs::create_directories(png + suffix + "/occupied");
    fs::create_directories(exr + suffix + "/occupied");
    expect_input_error([&] { write_png_srgb(png, Image(4, 4, 3, 0.9f)); }, {png, "cannot write image"});
    expect_input_error([&] { write_exr(exr, Image(4, 4, 3, 0.9f)); }, {exr, "cannot write image"});
    EXPECT_EQ(file_bytes(png), png_before);
    EXPECT_EQ(file_bytes(exr), exr_before);

    // Target is a folder: the rename fails and the temporary file is cleaned up.
    const std::string folder = path("folder.png");
    fs::create_directories(folder + "/inside");
    expect_input_error([&] { write_png_srgb(folder, Image(4, 4, 3, 0.9f)); }, {folder, "cannot write image"});
    EXPECT_FALSE(fs::exists(folder + suffix));
    EXPECT_TRUE(fs::is_directory(folder + "/inside"));
}

TEST_F(AtomicWrite, EmptyImageIsRejected) {
    const std::string p = path("empty.png");
    expect_input_error([&] { write_png_srgb(p, Image()); }, {p});
    expect_input_error([&] { write_exr(p, Image()); }, {p});
    EXPECT_FALSE(fs::exists(p));
}

// Environment
namespace {
constexpr double kPiD = 3.14159265358979323846;

// Brute-force irradiance: midpoint quadrature of radiance * max(0, n.w) over the sphere.
vec3 brute_force_irradiance(const Environment& env, vec3 n, int nt = 400, int np = 800) {
    n = glm::normalize(n);
    double e[3] = {};
    const double dt = kPiD / nt, dp = 2 * kPiD / np;
    for (int j = 0; j < nt; ++j) {
        const double t = (j + 0.5) * dt;
        for (int i = 0; i < np; ++i) {
            const double p = (i + 0.5) * dp;
            const vec3 w(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)), float(std::cos(t)));
            const double c = glm::dot(n, w);
            if (c <= 0) continue;
            const vec3 L = env.radiance(w);
            for (int k = 0; k < 3; ++k) e[k] += L[k] * c * std::sin(t) * dt * dp;
        }
    }
    return vec3(float(e[0]), float(e[1]), float(e[2]));
}

const vec3 kNormals[] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}, {0.3f, -0.5f, 0.2f}, {-1, -1, -1}, {0, 0, 7}};
}  // namespace

TEST(Env, ConstantIrradianceIsPiL) {
    Environment env;
    env.color = vec3(0.3f, 0.5f, 0.7f);
    env.intensity = 2.f;
    const SH9 sh = project_sh9(env);
    for (const vec3& n : kNormals) {
        const vec3 e = sh9_irradiance(sh, n);
        for (int k = 0; k < 3; ++k) {
            const float want = kPi * env.color[k] * env.intensity;
            EXPECT_NEAR(e[k], want, 1e-5f * want) << "normal " << n.x << "," << n.y << "," << n.z;
        }
    }
    EXPECT_EQ(env.radiance(vec3(0.f, 1.f, 0.f)), env.color * env.intensity);
}

TEST(Env, ConstantMapMatchesClosedForm) {
    Environment env;
    env.intensity = 2.f;
    auto map_img = std::make_shared<Image>(64, 32, 3);
    env.map = map_img;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) {
            float* p = map_img->at(x, y);
            p[0] = 0.3f, p[1] = 0.5f, p[2] = 0.7f;
        }
    const SH9 sh = project_sh9(env);
    for (const vec3& n : kNormals) {
        const vec3 e = sh9_irradiance(sh, n);
        for (int k = 0; k < 3; ++k) {
            const float want = kPi * map_img->data[size_t(k)] * env.intensity;
            EXPECT_NEAR(e[k], want, 1e-3f * want);
        }
    }
    EXPECT_NEAR(env.radiance(vec3(0.2f, -0.3f, 0.4f)).y, 1.0f, 1e-6f);
}

TEST(Env, UpperHemisphereMatchesQuadrature) {
    Environment env;
    env.intensity = 1.5f;
    auto map_img = std::make_shared<Image>(128, 64, 3, 0.f);
    env.map = map_img;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 128; ++x) {
            float* p = map_img->at(x, y);
            p[0] = 1.f, p[1] = 0.5f, p[2] = 0.25f;
        }
    const SH9 sh = project_sh9(env);
    const vec3 up = sh9_irradiance(sh, vec3(0, 0, 1)), down = sh9_irradiance(sh, vec3(0, 0, -1));
    EXPECT_GT(up.x, down.x + 1.f);
    const float scale = brute_force_irradiance(env, vec3(0, 0, 1)).x;  // ~ pi * 1.5
    EXPECT_NEAR(scale, kPi * 1.5f, 0.03f * kPi * 1.5f);
    for (const vec3& n : {vec3(0, 0, 1), vec3(0, 0, -1), vec3(1, 0, 0), vec3(0, 1, 0), vec3(1, 1, 0), vec3(1, 0, 1),
                          vec3(-1, 0.5f, -1)}) {
        const vec3 bf = brute_force_irradiance(env, n), e = sh9_irradiance(sh, n);
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(e[k], bf[k], 0.03f * scale * map_img->data[size_t(k)])
                << "normal " << n.x << "," << n.y << "," << n.z << " channel " << k;
    }
}

TEST(Env, SmoothMapMatchesQuadratureEverywhere) {
    // Radiance linear in the direction (1 + 0.5x - 0.3y + 0.8z): its irradiance is captured
    // exactly by bands 0 and 1, so the SH result must match the quadrature closely.
    Environment env;
    auto map_img = std::make_shared<Image>(256, 128, 4, 1.f);
    env.map = map_img;
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 256; ++x) {
            const float t = (y + 0.5f) / 128.f * kPi, p = (x + 0.5f) / 256.f * 2.f * kPi;
            const vec3 w(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
            const float v = 1.f + 0.5f * w.x - 0.3f * w.y + 0.8f * w.z;
            float* px = map_img->at(x, y);
            px[0] = v, px[1] = 2.f * v, px[2] = 0.5f * v;
        }
    const SH9 sh = project_sh9(env);
    for (const vec3& n : kNormals) {
        const vec3 bf = brute_force_irradiance(env, n), e = sh9_irradiance(sh, n);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(e[k], bf[k], 0.01f * bf[k] + 1e-3f);
    }
}

TEST(Env, RadianceLookupMapping) {
    Environment env;
    env.intensity = 2.f;
    const int w = 8, h = 4;
    auto map_img = std::make_shared<Image>(w, h, 3);
    env.map = map_img;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = map_img->at(x, y);
            p[0] = float(x), p[1] = float(y), p[2] = (y == 0) ? 5.f : 1.f;
        }
    // Straight up: the top row (v clamped), whatever phi.
    EXPECT_FLOAT_EQ(env.radiance(vec3(0, 0, 1)).y, 0.f);
    EXPECT_FLOAT_EQ(env.radiance(vec3(0, 0, 3)).z, 10.f);
    // +x: phi = 0, the seam between column 0 and the last column, halfway down.
    const vec3 px = env.radiance(vec3(1, 0, 0));
    EXPECT_FLOAT_EQ(px.x, 2.f * 0.5f * (0.f + float(w - 1)));
    EXPECT_FLOAT_EQ(px.y, 2.f * 0.5f * (1.f + 2.f));
    // Texel centres are read exactly: column 0 row 1, column 5 row 2.
    for (auto [x, y] : {std::pair{0, 1}, std::pair{5, 2}}) {
        const float theta = (y + 0.5f) / h * 180.f, phi = (x + 0.5f) / w * 360.f;
        const vec3 r = env.radiance(direction_from_degrees(theta, phi));
        EXPECT_NEAR(r.x, 2.f * x, 1e-4f);
        EXPECT_NEAR(r.y, 2.f * y, 1e-4f);
    }
    // Zero-length direction: the constant colour, no NaN.
    env.color = vec3(0.25f);
    const vec3 z = env.radiance(vec3(0.f));
    EXPECT_TRUE(std::isfinite(z.x) && std::isfinite(z.y) && std::isfinite(z.z));
    EXPECT_EQ(z, vec3(0.25f) * env.intensity);
    // Zero-length normal: no direction, so the irradiance averaged over all normals, pi times the
    // mean radiance = intensity * sum over texels of L * Omega / 4, each texel constant over its
    // solid angle Omega = (2 pi / w)(cos theta0 - cos theta1).
    double want[3] = {0, 0, 0};
    for (int y = 0; y < h; ++y) {
        const double omega = 2.0 * kPiD / w * (std::cos(kPiD * y / h) - std::cos(kPiD * (y + 1) / h));
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < 3; ++k) want[k] += double(map_img->at(x, y)[k]) * omega / 4.0 * double(env.intensity);
    }
    const vec3 e0 = sh9_irradiance(project_sh9(env), vec3(0.f));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(e0[k], want[k], 1e-5 * want[k]) << "channel " << k;
}

TEST(Env, DirectionFromDegreesIsThetaFromZAndPhiFromX) {
    // (theta, phi) in degrees: theta from +z, phi from +x towards +y (the lights' and the camera's
    // convention): (sin t cos p, sin t sin p, cos t), here at values known exactly.
    const float h = std::sqrt(0.5f);
    const std::pair<vec2, vec3> cases[] = {{{0.f, 123.f}, {0.f, 0.f, 1.f}},  {{90.f, 0.f}, {1.f, 0.f, 0.f}},  {{90.f, 90.f}, {0.f, 1.f, 0.f}},
                                           {{90.f, 180.f}, {-1.f, 0.f, 0.f}}, {{90.f, -90.f}, {0.f, -1.f, 0.f}}, {{180.f, 0.f}, {0.f, 0.f, -1.f}},
                                           {{45.f, 0.f}, {h, 0.f, h}},       {{90.f, 45.f}, {h, h, 0.f}},       {{60.f, 90.f}, {0.f, 0.8660254f, 0.5f}}};
    for (const auto& [angles, want] : cases) {
        const vec3 d = direction_from_degrees(angles.x, angles.y);
        EXPECT_NEAR(glm::distance(d, want), 0.f, 1e-6f) << angles.x << ", " << angles.y;
    }
}

TEST(Env, ProjectionIsIndependentOfTheThreadCount) {
    // The projection sums rows in parallel: one thread and many threads must give the same bits
    // (the stage cache and the CPU/GPU comparisons assume one answer per map).
    Environment env;
    env.map = std::make_shared<Image>(random_image(1024, 512, 3, 11, 0.f, 4.f));
    const SH9 a = test::with_threads(test::kManyThreads, [&] { return project_sh9(env); });
    const SH9 b = test::with_threads(1, [&] { return project_sh9(env); });
    EXPECT_GT(a.c[0][0], 0.f);
    for (int i = 0; i < 9; ++i)
        for (int k = 0; k < 3; ++k) EXPECT_EQ(a.c[size_t(i)][k], b.c[size_t(i)][k]) << "coefficient " << i << " channel " << k;
}

// Plot
namespace {
bool pixels_ok(const Image& img) {
    for (float v : img.data)
        if (!std::isfinite(v) || v < 0.f || v > 1.f) return false;
    return true;
}

// Ink of text drawn on a white canvas: the pixels that changed, their bounding box.
struct Ink {
    Image img;
    int count = 0, partial = 0;  // inked pixels; of which neither white nor the full text colour
    int x0 = INT_MAX, y0 = INT_MAX, x1 = INT_MIN, y1 = INT_MIN;  // [x0, x1) x [y0, y1)
    int width() const { return count ? x1 - x0 : 0; }
};
Ink ink_of(const std::string& text, int scale, int w = 400, int h = 120, int x = 20, int y = 20) {
    Ink k{Image(w, h, 3, 1.f)};
    draw_text(k.img, x, y, text, 0.f, 0.f, 0.f, scale);
    for (int py = 0; py < h; ++py)
        for (int px = 0; px < w; ++px) {
            const float v = k.img.at(px, py)[0];
            if (v >= 1.f) continue;
            ++k.count;
            k.partial += v > 0.02f;
            k.x0 = std::min(k.x0, px), k.x1 = std::max(k.x1, px + 1);
            k.y0 = std::min(k.y0, py), k.y1 = std::max(k.y1, py + 1);
        }
    return k;
}
bool same_pixels(const Image& a, const Image& b) { return a.width == b.width && a.height == b.height && a.data == b.data; }

}  // namespace

TEST(Plot, DegenerateInputsNeverProduceNaN) {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    PlotSpec spec;
    spec.title = "degenerate";
    spec.xlabel = "time [ms]";
    spec.ylabel = "error";
    spec.series.push_back({"empty", {}, {}, {}});
    spec.series.push_back({"single", {3.0}, {0.5}, {"k=1"}});
    spec.series.push_back({"equal", {2, 2, 2}, {1, 1, 1}, {}});
    spec.series.push_back({"bad", {-1, 0, nan, inf, 5, 1e-320}, {1, 2, 3, 4, -inf, 7}, {"a"}});
    spec.series.push_back({"", {1, 10, 100}, {1e-3, 1e-4}, {"x", "y", "z", "w"}});  // lengths differ
    spec.series.push_back({"huge", {1e300, -1e300}, {1e-300, 1e300}, {}});
    for (bool lx : {false, true})
        for (bool ly : {false, true})
            for (auto [w, h] : {std::pair{900, 600}, std::pair{320, 200}, std::pair{40, 30}, std::pair{1, 1},
                                std::pair{3000, 2000}}) {
                spec.log_x = lx, spec.log_y = ly;
                const Image img = render_plot(spec, w, h);
                ASSERT_EQ(img.width, w);
                ASSERT_EQ(img.height, h);
                ASSERT_EQ(img.channels, 3);
                EXPECT_TRUE(pixels_ok(img)) << lx << ly << " " << w << "x" << h;
            }
    EXPECT_TRUE(render_plot(PlotSpec{}, 0, 0).empty());
    EXPECT_TRUE(pixels_ok(render_plot(PlotSpec{})));
    PlotSpec only_bad;
    only_bad.series.push_back({"bad", {nan, -1}, {1, 1}, {}});
    EXPECT_TRUE(pixels_ok(render_plot(only_bad)));
}

TEST(Plot, TitleTextIsDrawn) {
    // Title area at the default size: the top 40 rows, the middle third of the width.
    auto title_ink = [](const Image& img) {
        int n = 0;
        for (int y = 0; y < 40; ++y)
            for (int x = img.width / 3; x < 2 * img.width / 3; ++x) {
                const float* p = img.at(x, y);
                n += p[0] < 0.1f && p[1] < 0.1f && p[2] < 0.1f;
            }
        return n;
    };
    PlotSpec spec;
    spec.title = "Error against time";
    EXPECT_GT(title_ink(render_plot(spec, 900, 600)), 50);
    spec.title.clear();
    EXPECT_EQ(title_ink(render_plot(spec, 900, 600)), 0);

    spec.title = "Error against time";
    spec.series.push_back({"bdpt", {1, 2, 4, 8}, {0.1, 0.05, 0.03, 0.012}, {"1", "2", "4", "8"}});
    const Image with = render_plot(spec, 900, 600);
    EXPECT_GT(title_ink(with), 50);
    EXPECT_TRUE(pixels_ok(with));
    // The series colour (palette blue) appears: markers and line.
    int coloured = 0;
    for (size_t i = 0; i < with.data.size(); i += 3) coloured += with.data[i + 2] > 0.3f && with.data[i] < 0.1f;
    EXPECT_GT(coloured, 50);
}


TEST(Plot, DrawTextAndWidth) {
    EXPECT_EQ(text_width(""), 0);
    EXPECT_GT(text_width("Hi"), 0);
    EXPECT_GT(text_width("Hi", 3), 2 * text_width("Hi"));  // sizes scale with the plot
    EXPECT_GT(text_height(2), text_height(1));
    EXPECT_EQ(text_em_px(2), 2 * text_em_px(1));
    Image img(40, 40, 4, 0.f);
    draw_text(img, 2, 3, "A", 1.f, 0.f, 0.f, 2);
    int inside = 0, outside = 0, opaque = 0;
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x) {
            const float* p = img.at(x, y);
            const bool ink = p[0] > 0.f;
            const bool in_box = x >= 2 && x < 2 + text_width("A", 2) && y >= 3 && y < 3 + text_height(2);
            (in_box ? inside : outside) += ink;
            if (ink) {
                EXPECT_GT(p[3], 0.f);
                EXPECT_LE(p[3], 1.f);
            }
            opaque += p[3] == 1.f;
        }
    EXPECT_GT(inside, 20);
    EXPECT_EQ(outside, 0);
    EXPECT_GT(opaque, 5);  // fully covered pixels are opaque
    draw_text(img, -5, 15, "clipped \x01\x7f \xce\xb1\xff", 0.f, 1.f, 0.f, 4);  // partly outside, control bytes, bad UTF-8
    EXPECT_TRUE(all_finite(img));
    Image grey(30, 20, 1, 1.f);
    draw_text(grey, 1, 1, "\xce\xb8", 0.f, 0.f, 0.f, 2);  // θ into a single-channel image
    EXPECT_TRUE(all_finite(grey));
    EXPECT_LT(*std::min_element(grey.data.begin(), grey.data.end()), 0.5f);
}

TEST(Plot, TextWidthIsTheInkedExtent) {
    // The box text_width x text_height at (x, y) holds the ink; its width matches the ink's.
    for (int scale : {1, 2, 3, 5})
        for (const char* t : {"Hi", "0.005", "time per frame incl. stages (ms)", "\xce\xb1 = 0.08 rad",
                              "\xce\xb8 [\xc2\xb0]", "t [\xc2\xb5s]", "area [m\xc2\xb2]", "2 \xc3\x97 3 \xe2\x80\x93 4",
                              "\xce\xa3 \xce\xb4 \xcf\x80 \xce\xa9", "WAVE,jy"}) {
            const Ink k = ink_of(t, scale, 1400, 200, 20, 30);
            ASSERT_GT(k.count, 0) << t;
            EXPECT_NEAR(k.width(), text_width(t, scale), 1) << t << " scale " << scale;
            EXPECT_NEAR(k.x0, 20, 1) << t << " scale " << scale;
            EXPECT_GE(k.y0, 30 - 2) << t << " scale " << scale;  // accents may reach a little above the box
            EXPECT_LE(k.y1, 30 + text_height(scale)) << t << " scale " << scale;
        }
    // The width grows with the string, by the real advance of each glyph.
    int prev = 0;
    std::string s;
    for (const char* piece : {"\xce\xb1", "\xce\xb2", "\xce\xb3", " ", "\xce\xb4", "\xce\xb5", "M", "i"}) {
        s += piece;
        const int w = text_width(s, 2);
        EXPECT_GT(w, prev) << s;
        prev = w;
    }
    // Proportional, not monospaced: "i" is narrower than "M", and "iii" than "MMM".
    EXPECT_LT(text_width("i", 3), text_width("M", 3));
    EXPECT_LT(text_width("iii", 3), text_width("MMM", 3));
}

TEST(Plot, NonAsciiDrawsRealGlyphs) {
    // Greek letters and unit signs draw their own glyphs: ink, anti-aliased, different from the
    // '?' placeholder and from each other, and the font has every one of them (no missing-glyph box).
    const std::vector<std::string> letters = {"\xce\xb1", "\xce\xb2", "\xce\xb8", "\xc2\xb5", "\xc2\xb2",  "\xc2\xb0",
                                              "\xc3\x97", "\xe2\x80\x93", "\xce\xa3", "\xcf\x80", "\xce\xa9", "?"};
    std::vector<Ink> inks;
    for (const std::string& l : letters) {
        inks.push_back(ink_of(l, 3, 80, 80, 10, 10));
        EXPECT_GT(inks.back().count, 3) << l;
        EXPECT_GT(inks.back().partial, 0) << l << ": anti-aliased edges";
        const std::u32string cps = decode_utf8(l);
        ASSERT_EQ(cps.size(), 1u) << l;
        EXPECT_TRUE(plot_font().has_glyph(cps[0])) << l;
    }
    for (size_t i = 0; i < letters.size(); ++i)
        for (size_t j = i + 1; j < letters.size(); ++j)
            EXPECT_FALSE(same_pixels(inks[i].img, inks[j].img)) << letters[i] << " vs " << letters[j];
    // A whole unit: "µs" is not "?s", and not one '?' per byte either.
    EXPECT_FALSE(same_pixels(ink_of("t [\xc2\xb5s]", 2).img, ink_of("t [?s]", 2).img));
    EXPECT_FALSE(same_pixels(ink_of("t [\xc2\xb5s]", 2).img, ink_of("t [??s]", 2).img));
    // In a plot: the title's ink depends on which Greek letter it names.
    PlotSpec spec;
    spec.series.push_back({"s", {1, 2}, {1, 2}, {}});
    spec.title = "roughness \xce\xb1";
    const Image alpha = render_plot(spec, 600, 400);
    spec.title = "roughness \xce\xb2";
    const Image beta = render_plot(spec, 600, 400);
    spec.title = "roughness ?";
    const Image question = render_plot(spec, 600, 400);
    EXPECT_FALSE(same_pixels(alpha, beta));
    EXPECT_FALSE(same_pixels(alpha, question));
}

TEST(Plot, TwoThreadsDrawingAtOnceGiveTheFirstDrawingsPixels) {
    // The font's glyph caches are shared: two plots drawn at once on two threads (cached glyphs,
    // concurrent look-ups) must equal the first one, drawn alone.
    PlotSpec spec;
    spec.title = "error vs time: \xce\xb1 (\xce\xb8 = 30\xc2\xb0)";
    spec.xlabel = "time [\xc2\xb5s]";
    spec.ylabel = "\xc2\xbd \xce\xa3 |p \xe2\x88\x92 q|";
    spec.series.push_back({"\xce\xb1_x", {1, 2, 4, 8}, {0.1, 0.05, 0.03, 0.012}, {"1", "2", "4", "8"}});
    const Image a = render_plot(spec, 900, 600);
    Image b, c;
    std::thread t1([&] { b = render_plot(spec, 900, 600); });
    std::thread t2([&] { c = render_plot(spec, 900, 600); });
    t1.join();
    t2.join();
    EXPECT_TRUE(same_pixels(a, b));
    EXPECT_TRUE(same_pixels(a, c));
    EXPECT_TRUE(pixels_ok(a));
}

TEST(Plot, SvgHasTheSameChartWithTextAsText) {
    auto count = [](const std::string& s, const std::string& what) {
        size_t n = 0;
        for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
        return n;
    };
    PlotSpec spec;
    spec.title = "error vs time: \xce\xb1 < \xce\xb2 & \xc2\xb5s";
    spec.xlabel = "time [\xc2\xb5s]";
    spec.ylabel = "RMSE \xe2\x80\x93 m\xc2\xb2";
    spec.series.push_back({"\xce\xb8 sweep", {1, 2, 4, 8}, {0.1, 0.05, 0.03, 0.012}, {"1", "2", "4", "8"}});
    spec.series.push_back({"floor", {1, 8}, {0.02, 0.02}, {}});
    spec.series.push_back({"bad \xff\x01", {1}, {0.5}, {}});  // one point: no line
    const std::string svg = render_plot_svg(spec, 900, 600);
    EXPECT_EQ(svg.rfind("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg ", 0), 0u);
    EXPECT_NE(svg.find("width=\"900\" height=\"600\""), std::string::npos);
    EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
    // Text as text, UTF-8 kept, markup escaped, malformed bytes and control characters replaced.
    EXPECT_NE(svg.find(">error vs time: \xce\xb1 &lt; \xce\xb2 &amp; \xc2\xb5s</text>"), std::string::npos) << svg;
    EXPECT_NE(svg.find(">time [\xc2\xb5s]</text>"), std::string::npos);
    EXPECT_NE(svg.find(">RMSE \xe2\x80\x93 m\xc2\xb2</text>"), std::string::npos);
    EXPECT_NE(svg.find(">\xce\xb8 sweep</text>"), std::string::npos);
    EXPECT_NE(svg.find(">bad \xef\xbf\xbd\xef\xbf\xbd</text>"), std::string::npos);
    for (char c = 1; c < 0x20; ++c) {
        if (c != '\n') {
            EXPECT_EQ(svg.find(c), std::string::npos) << int(c);
        }
    }
    // One line per series with two or more points, each clipped to the plot area; four point labels.
    EXPECT_EQ(count(svg, "<polyline"), 2u);
    EXPECT_EQ(count(svg, "<clipPath"), 2u);
    for (const char* l : {">1</text>", ">2</text>", ">4</text>", ">8</text>"}) EXPECT_GE(count(svg, l), 1u) << l;
    EXPECT_EQ(count(svg, "<text"), count(svg, "</text>"));
    // The title sits where the PNG's is (scale 3, 12 px down at 900x600): centred by its inked width,
    // the pen left of the ink by its bearing.
    const int ts = 3, x = (900 - text_width(spec.title, ts)) / 2;
    const int pen = x - plot_font().left_bearing(spec.title, text_em_px(ts));
    EXPECT_NE(svg.find("<text x=\"" + std::to_string(pen) + "\" y=\"" + std::to_string(12 + plot_font().ascent(text_em_px(ts))) +
                       "\" font-size=\"" + std::to_string(text_em_px(ts)) + "\""),
              std::string::npos)
        << svg;
    // The same text on another thread, after other sizes and glyphs went through the font's caches.
    std::string again;
    std::thread other([&] {
        PlotSpec before;
        before.title = "\xce\xa3 \xce\xb4 \xcf\x80 \xce\xa9 WAVE";
        before.series.push_back({"x", {1, 3}, {2, 1}, {}});
        render_plot(before, 320, 200);
        render_plot_svg(before, 2000, 1500);
        again = render_plot_svg(spec, 900, 600);
    });
    other.join();
    EXPECT_EQ(svg, again);
    const std::string empty = render_plot_svg(spec, 0, 0);
    EXPECT_EQ(count(empty, "<text"), 0u);
    EXPECT_EQ(empty.substr(empty.size() - 7), "</svg>\n");
}

TEST(Plot, Utf8Decoding) {
    EXPECT_EQ(decode_utf8("a\xce\xb1\xe2\x80\x93\xf0\x9f\x98\x80"), std::u32string(U"a\u03B1\u2013\U0001F600"));
    EXPECT_EQ(decode_utf8("\xff"), std::u32string(U"\uFFFD"));
    EXPECT_EQ(decode_utf8("\x80x"), std::u32string(U"\uFFFDx"));        // stray continuation byte
    EXPECT_EQ(decode_utf8("\xce"), std::u32string(U"\uFFFD"));          // truncated
    EXPECT_EQ(decode_utf8("\xe2\x80x"), std::u32string(U"\uFFFDx"));    // truncated before an ASCII byte
    EXPECT_EQ(decode_utf8("\xc0\xaf"), std::u32string(U"\uFFFD"));      // overlong
    EXPECT_EQ(decode_utf8("\xed\xa0\x80"), std::u32string(U"\uFFFD"));  // surrogate
    EXPECT_EQ(decode_utf8(""), std::u32string());
}

TEST(Plot, MissingFontNamesTheFileAndThePackage) {
    const std::string path = "/nonexistent/mesolab-test/NoSuchFont.ttf";
    try {
        Font f(path);
        FAIL() << "no error for a missing font";
    } catch (const std::runtime_error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
        EXPECT_NE(msg.find("fonts-dejavu-core"), std::string::npos) << msg;
    }
    // Not a font at all: the same kind of message.
    const std::string not_font = (fs::temp_directory_path() / ("mesolab_not_a_font_" + std::to_string(long(::getpid())) + ".ttf")).string();
    { std::ofstream(not_font) << "plain text"; }
    try {
        Font f(not_font);
        ADD_FAILURE() << "no error for a file that is not a font";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(not_font), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("fonts-dejavu-core"), std::string::npos) << e.what();
    }
    fs::remove(not_font);
    // The plot font itself is the configured file and loads.
    EXPECT_EQ(plot_font().path(), std::string(plot_font_path()));
    EXPECT_GT(plot_font().line_height(12), 12);
}
