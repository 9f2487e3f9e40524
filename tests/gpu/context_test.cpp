// Headless EGL context, embedded shaders, RenderTarget read-back and compute (llvmpipe is enough).
#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/shaders.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>

namespace mesolab::gpu {
namespace {

// [SECTION] GL objects that outlive their context must not crash (libepoxy aborts when an entry
// point is first resolved with no current context); defined first so it runs before any other
// test has resolved glDeleteQueries and friends.
TEST(GpuLifetime, ObjectsMayOutliveTheContext) {
    Query q;
    Buffer b;
    {
        auto ctx = HeadlessContext::create();
        GLuint id = 0;
        glGenQueries(1, &id);
        q = Query(id);
        glGenBuffers(1, &id);
        b = Buffer(id);
    }
    q.reset();
    b.reset();
    EXPECT_FALSE(q);
    EXPECT_FALSE(b);
}

// [SECTION] Fixture: one context per test, so every test also exercises create/destroy.
class GpuTest : public ::testing::Test {
protected:
    void SetUp() override { ctx_ = HeadlessContext::create(); }
    void TearDown() override { ctx_.reset(); }
    std::unique_ptr<HeadlessContext> ctx_;
};

int gl_version() {
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    return major * 10 + minor;
}

// [SECTION] Context
TEST_F(GpuTest, ContextReportsCoreGl43OrNewer) {
    const GlInfo& info = ctx_->info();
    std::printf("GL: %s | %s | %s | GLSL %s | %s\n", info.vendor.c_str(), info.renderer.c_str(), info.version.c_str(),
                info.glsl_version.c_str(), info.platform.c_str());
    EXPECT_GE(gl_version(), 43);
    EXPECT_FALSE(info.renderer.empty());
    EXPECT_FALSE(info.version.empty());
    EXPECT_FALSE(info.glsl_version.empty());
    EXPECT_TRUE(info.platform == "egl-device" || info.platform == "egl-surfaceless" || info.platform == "egl-default")
        << info.platform;
    GLint profile = 0;
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
    EXPECT_NO_THROW(check_gl("context"));
}

TEST(GpuContext, CreateDestroyCreate) {
    for (int i = 0; i < 3; ++i) {
        auto ctx = HeadlessContext::create();
        ctx->make_current();
        EXPECT_GE(gl_version(), 43);
        RenderTarget rt;
        rt.resize(3, 2, 1);
        rt.bind();
        glClearColor(0.5f, 0.25f, 0.125f, float(i));
        glClear(GL_COLOR_BUFFER_BIT);
        const auto px = rt.read_rgba(0);
        ASSERT_EQ(px.size(), 3u * 2u * 4u);
        EXPECT_EQ(px[0], 0.5f);
        EXPECT_EQ(px[3], float(i));
    }
}

TEST(GpuContext, TwoContextsAtOnce) {
    auto a = HeadlessContext::create();
    auto b = HeadlessContext::create();
    a->make_current();
    EXPECT_GE(gl_version(), 43);
    b.reset();  // must not terminate the display under `a`
    a->make_current();
    RenderTarget rt;
    rt.resize(1, 1, 1);
    rt.bind();
    glClearColor(1.f, 2.f, 3.f, 4.f);
    glClear(GL_COLOR_BUFFER_BIT);
    EXPECT_EQ(rt.read_rgba(0)[2], 3.f);
}

// Each platform alone (MESOLAB_EGL_PLATFORM narrows the search); at least one must work, and
// an empty selection must fail with a message that points at the CPU backend.
TEST(GpuContext, PlatformsAndFailureMessage) {
    int working = 0;
    for (const char* p : {"device", "surfaceless", "default"}) {
        setenv("MESOLAB_EGL_PLATFORM", p, 1);
        try {
            auto ctx = HeadlessContext::create();
            std::printf("platform %-11s -> %s (%s)\n", p, ctx->info().platform.c_str(), ctx->info().renderer.c_str());
            EXPECT_EQ(ctx->info().platform, std::string("egl-") + p);
            ++working;
        } catch (const std::runtime_error& e) {
            std::printf("platform %-11s -> failed:\n%s\n", p, e.what());
        }
    }
    setenv("MESOLAB_EGL_PLATFORM", "none", 1);
    try {
        HeadlessContext::create();
        ADD_FAILURE() << "expected failure";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("use --backend cpu"), std::string::npos) << e.what();
    }
    unsetenv("MESOLAB_EGL_PLATFORM");
    EXPECT_GE(working, 1);
}

// [SECTION] Embedded shaders
TEST(GpuShaders, TableHasCommonAndTestShaders) {
    const auto names = shader_names();
    EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
    for (const char* n : {"shaders/common.glsl", "shaders/test/fullscreen.vert", "shaders/test/solid.frag", "shaders/test/fill.comp"})
        EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
    EXPECT_NE(shader_source("shaders/common.glsl").find("vec2 latlong_uv(vec3 dir)"), std::string_view::npos);
    EXPECT_THROW(shader_source("shaders/no_such_file.glsl"), std::runtime_error);
}

TEST_F(GpuTest, BrokenShaderThrowsWithFileName) {
    try {
        Program::graphics("shaders/test/fullscreen.vert", "shaders/test/solid.frag", {"BREAK_ME 1"});
        FAIL() << "expected a compile error";
    } catch (const std::runtime_error& e) {
        const std::string msg = e.what();
        std::printf("%s\n", msg.c_str());
        EXPECT_NE(msg.find("shaders/test/solid.frag"), std::string::npos) << msg;
    }
    try {
        Program::graphics("shaders/test/fullscreen.vert", "shaders/test/missing.frag");
        FAIL() << "expected a missing-file error";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("shaders/test/missing.frag"), std::string::npos) << e.what();
    }
}

// [SECTION] Rendering into a RenderTarget
TEST_F(GpuTest, FullScreenTriangleExactFloatsAndTopRowFirst) {
    const Program prog = Program::graphics("shaders/test/fullscreen.vert", "shaders/test/solid.frag");
    ASSERT_TRUE(prog);
    RenderTarget rt;
    rt.resize(17, 9, 2);
    ASSERT_EQ(rt.width(), 17);
    ASSERT_EQ(rt.height(), 9);
    ASSERT_EQ(rt.attachments(), 2);

    // resize() with the same parameters keeps the objects; a different count reallocates.
    const GLuint first = rt.color(0);
    rt.resize(17, 9, 2);
    EXPECT_EQ(rt.color(0), first);

    GLuint vao_id = 0;
    glGenVertexArrays(1, &vao_id);
    VertexArray vao(vao_id);
    rt.bind();
    const float clear[4] = {-1.f, -1.f, -1.f, -1.f};
    glClearBufferfv(GL_COLOR, 0, clear);
    glClearBufferfv(GL_COLOR, 1, clear);
    glDisable(GL_DEPTH_TEST);
    prog.use();
    const float color[4] = {0.1f, -2.25f, 1234.5678f, 1e-7f};  // not representable in 8 bits
    glUniform4fv(prog.uniform("u_color"), 1, color);
    glBindVertexArray(vao.get());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    check_gl("draw");

    const auto c = rt.read_rgba(0);
    const auto xy = rt.read_rgba(1);
    ASSERT_EQ(c.size(), size_t(17 * 9 * 4));
    ASSERT_EQ(xy.size(), size_t(17 * 9 * 4));
    int bad_color = 0, bad_coord = 0;
    for (int row = 0; row < 9; ++row) {
        for (int x = 0; x < 17; ++x) {
            const size_t i = (size_t(row) * 17 + size_t(x)) * 4;
            for (int k = 0; k < 4; ++k) bad_color += c[i + size_t(k)] != color[k];
            // Row 0 is the top: GL's y (bottom-up) is 8 - row; pixel centres are at +0.5.
            bad_coord += xy[i + 0] != float(x) + 0.5f;
            bad_coord += xy[i + 1] != float(8 - row) + 0.5f;
        }
    }
    EXPECT_EQ(bad_color, 0);
    EXPECT_EQ(bad_coord, 0);
    EXPECT_EQ(xy[1], 8.5f);                        // top-left pixel
    EXPECT_EQ(xy[(8 * 17) * 4 + 1], 0.5f);         // bottom-left pixel
    EXPECT_NEAR(xy[2], 3.14159265f, 1e-6f);        // PI from common.glsl

    rt.resize(17, 9, 1);
    EXPECT_EQ(rt.attachments(), 1);
    EXPECT_THROW(rt.read_rgba(1), std::out_of_range);
    EXPECT_THROW(rt.resize(0, 9, 1), std::invalid_argument);
}

// [SECTION] Compute
TEST_F(GpuTest, ComputeWritesSsboAndImage) {
    const Program prog = Program::compute("shaders/test/fill.comp", {"SCALE 2.0"});
    ASSERT_TRUE(prog);
    constexpr GLuint kCount = 100;
    constexpr int kW = 13, kH = 7;

    GLuint ids[1] = {};
    glGenBuffers(1, ids);
    Buffer ssbo(ids[0]);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, ssbo.get());
    std::vector<float> init(kCount, -1.f);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(kCount * sizeof(float)), init.data(), GL_DYNAMIC_READ);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ssbo.get());

    glGenTextures(1, ids);
    Texture image(ids[0]);
    glBindTexture(GL_TEXTURE_2D, image.get());
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, kW, kH);
    glBindImageTexture(0, image.get(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);

    prog.use();
    glUniform1ui(prog.uniform("u_count"), kCount);
    glDispatchCompute(4, 4, 1);  // 32 x 16 invocations
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    check_gl("dispatch");

    std::vector<float> values(kCount);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(kCount * sizeof(float)), values.data());
    const float offset = 0.5f * 3.14159265358979f;
    for (GLuint i = 0; i < kCount; ++i) EXPECT_NEAR(values[i], float(i) * 2.f + offset, 1e-4f) << i;

    // The image is rgba32f: the texel coordinates (conversions int -> float are exact) read back
    // exactly. latlong_uv(+y) = (phi / 2pi, theta / pi) with phi = atan(1, 0) = pi/2 and
    // theta = acos(0) = pi/2 is only as exact as the driver's atan and acos: GLSL leaves the
    // trigonometric functions' precision undefined (§4.7.1), so we allow what Vulkan requires of the
    // same built-ins, 4096 ULP for atan and, through atan2(sqrt(1 - x^2), x), for acos. At pi/2
    // (in [1, 2), 1 ULP = 2^-23) that is 2^-11 rad, plus 2.5 ULP of the division by 2pi or pi.
    // NVIDIA's acos (H100, driver 580) gives v = 0.49998; llvmpipe's, 0.5.
    const float angle = std::ldexp(1.f, -11);
    const float tol_u = angle / (2.f * 3.14159265f) + 2.5f * std::ldexp(1.f, -25);  // u = 0.25: 1 ULP = 2^-25
    const float tol_v = angle / 3.14159265f + 2.5f * std::ldexp(1.f, -24);          // v = 0.5: 1 ULP = 2^-24
    std::vector<float> texels(size_t(kW * kH * 4));
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, texels.data());
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const float* t = &texels[size_t(y * kW + x) * 4];
            EXPECT_EQ(t[0], float(x));
            EXPECT_EQ(t[1], float(y));
            EXPECT_NEAR(t[2], 0.25f, tol_u);  // latlong_uv(+y): phi = pi/2
            EXPECT_NEAR(t[3], 0.5f, tol_v);   // theta = pi/2
        }
    check_gl("readback");
}

// [SECTION] Timer queries
// A 64x64 target with `attachments` colour attachments bound, the solid test shader in use and an
// empty vertex array bound: glDrawArrays(GL_TRIANGLES, 0, 3) fills it.
struct SolidTriangle {
    Program prog = Program::graphics("shaders/test/fullscreen.vert", "shaders/test/solid.frag");
    RenderTarget rt;
    VertexArray vao;
    explicit SolidTriangle(int attachments) {
        rt.resize(64, 64, attachments);
        GLuint id = 0;
        glGenVertexArrays(1, &id);
        vao = VertexArray(id);
        rt.bind();
        prog.use();
        glBindVertexArray(vao.get());
    }
    ~SolidTriangle() { glBindVertexArray(0); }
};

TEST_F(GpuTest, TimerRangesNeverReportAnImpossibleTime) {
    const SolidTriangle draw(2);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glFinish();
    // A valid answer never exceeds the wall-clock time around it; an impossible one (llvmpipe under
    // load can lose the query's start) must come back as NaN, never as a figure. Every round is
    // logged, so that a failure shows the driver's answers and not just one line.
    std::string log;
    bool ok = true;
    GpuTimeline timeline(false);  // timer queries, whatever the renderer
    for (int round = 0; round < 20; ++round) {
        double ms = -2.0;
        int answers = 0;
        const auto t0 = std::chrono::steady_clock::now();
        timeline.begin();
        for (int i = 0; i < 10; ++i) glDrawArrays(GL_TRIANGLES, 0, 3);
        timeline.end([&](double v) { ms = v, ++answers; });
        timeline.wait();
        const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        const bool round_ok = answers == 1 && (std::isnan(ms) || (ms >= 0.0 && ms <= wall * 1.01 + 1.0));
        char line[160];
        std::snprintf(line, sizeof line, "round %2d: %d answer(s), gpu %.4f ms, wall %.4f ms%s\n", round, answers, ms, wall,
                      round_ok ? "" : "  <-- impossible");
        log += line;
        ok = ok && round_ok;
    }
    EXPECT_TRUE(ok) << log;
    std::printf("%s", log.c_str());
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR)) << log;
}

// The plausibility rule on its own, with the answers llvmpipe was seen to give.
TEST(GpuTimelineRule, RejectsAnswersLongerThanTheWallClock) {
    EXPECT_TRUE(GpuTimeline::plausible(0.0, 0.0));
    EXPECT_TRUE(GpuTimeline::plausible(5.0, 5.0));
    EXPECT_TRUE(GpuTimeline::plausible(1.3, 0.3));     // clock granularity: 1 ms of slack
    EXPECT_FALSE(GpuTimeline::plausible(3.6e9, 2.0));  // a lost start: about the uptime
    EXPECT_FALSE(GpuTimeline::plausible(1.8e16, 2.0)); // an end before the start, wrapped
    EXPECT_FALSE(GpuTimeline::plausible(std::numeric_limits<double>::quiet_NaN(), 2.0));
    EXPECT_FALSE(GpuTimeline::plausible(-1.0, 2.0));
}

// [SECTION] GpuTimeline
// Ranges answered without a wait: each callback runs once, in order, with a plausible time or
// NaN; a software timeline answers at end(). Ranges never nest.
TEST_F(GpuTest, GpuTimelineAnswersEachRangeOnceInOrder) {
    const SolidTriangle draw(1);
    for (bool software : {false, true}) {
        GpuTimeline timeline(software);
        std::vector<int> order;
        std::vector<double> times;
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < 6; ++i) {
            timeline.begin();
            for (int k = 0; k < 20; ++k) glDrawArrays(GL_TRIANGLES, 0, 3);
            timeline.end([&, i](double ms) {
                order.push_back(i);
                times.push_back(ms);
            });
            if (software) {
                EXPECT_EQ(order.size(), size_t(i + 1)) << "a software range answers at end()";
            }
            timeline.poll();  // whatever is ready; never more than was begun
            EXPECT_LE(order.size(), size_t(i + 1));
        }
        EXPECT_THROW(timeline.end({}), std::logic_error);
        timeline.begin();
        EXPECT_THROW(timeline.begin(), std::logic_error) << "ranges do not nest";
        timeline.end({});
        timeline.wait();
        const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        EXPECT_EQ(timeline.open(), 0u);
        ASSERT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4, 5})) << "software " << software;
        for (double ms : times) EXPECT_TRUE(std::isnan(ms) || (ms >= 0.0 && ms <= wall * 1.01 + 1.0)) << ms;
        if (software) {
            for (double ms : times) EXPECT_TRUE(std::isfinite(ms)) << "a wall time is always a figure";
        }
    }
    check_gl("GpuTimeline");
}

TEST(GpuTimelineRule, NamesSoftwareRenderers) {
    EXPECT_TRUE(is_software_renderer("llvmpipe (LLVM 15.0.6, 256 bits)"));
    EXPECT_TRUE(is_software_renderer("softpipe"));
    EXPECT_TRUE(is_software_renderer("Google SwiftShader"));
    EXPECT_FALSE(is_software_renderer("NVIDIA H100 80GB HBM3/PCIe/SSE2"));
    EXPECT_FALSE(is_software_renderer("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.6, DRM 3.49, 6.1.0)"));
}
}  // namespace
}  // namespace mesolab::gpu
