// Tests for core/image (sRGB, PNG/EXR I/O, atomic writes) and core/env (lookup, SH irradiance).
#include "core/env.h"
#include "core/error.h"
#include "core/image.h"

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
