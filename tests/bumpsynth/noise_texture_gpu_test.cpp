// The noise texture's look-up on the GPU (gpu/bumpsynth/noise_texture.glsl, what bumpsynth.frag
// samples) against the CPU's NoiseTexture::bilinear (core/bumpsynth/noise.cpp), on a texture
// whose neighbouring texels differ by up to 1.
//
// Tolerance: none. The same float expressions on both sides, `precise` in the GLSL so that no
// multiply-add is fused: the same bits (a fused lerp is a few ULP off, enough to pick another
// look-up-table entry now and then). A filtered texture look-up whose weights have 8 bits
// (NVIDIA's) errs by up to 1/512 here.
//
// llvmpipe filters in float, so a filtered look-up would pass the first check here as well; the
// second sets the texture's filters to GL_NEAREST, the coarsest a GL implementation may filter with
// and one llvmpipe does: the look-up must not change, i.e. must not depend on the filter.
#include "core/bumpsynth/noise.h"
#include "gpu/context.h"
#include "gpu/gl.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

using namespace mesolab;
using namespace mesolab::bumpsynth;

namespace {
// A 16 x 16 noise texture of 5 levels (16 .. 1 texels), every value uniform in [0, 1].
NoiseTexture random_texture() {
    NoiseTexture t;
    t.size = 16;
    t.octaves_max = 5;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int s = t.size; s >= 1; s >>= 1) {
        t.levels.emplace_back(size_t(s) * size_t(s));
        for (vec2& v : t.levels.back()) v = vec2(u(rng), u(rng));
    }
    return t;
}
}  // namespace

TEST(BumpsynthNoiseTexture, GpuLookUpIsTheCpuBilinearWhateverTheFilter) {
    std::unique_ptr<gpu::ComputeScope> scope;
    try {
        scope = std::make_unique<gpu::ComputeScope>();
    } catch (const std::runtime_error&) {
        GTEST_SKIP() << "no OpenGL context";
    }
    const NoiseTexture tex = random_texture();
    const int levels = int(tex.levels.size());

    // Points all over a level's texels and beyond [0, 1] (wrapping), at sub-texel offsets that are
    // no multiples of 1/256, and at the texel centres and edges.
    std::vector<vec4> points;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> uv(-1.f, 2.f);
    for (int l = 0; l < levels; ++l) {
        for (int i = 0; i < 2000; ++i) points.emplace_back(uv(rng), uv(rng), float(l), 0.f);
        const int s = std::max(1, tex.size >> l);
        for (int i = 0; i <= 4 * s; ++i) points.emplace_back(float(i) / float(4 * s), float(4 * s - i) / float(4 * s), float(l), 0.f);
    }
    std::vector<vec2> cpu(points.size());
    for (size_t i = 0; i < points.size(); ++i) cpu[i] = tex.bilinear(int(points[i].z), vec2(points[i]));

    const gpu::TextureSpec spec{.format = GL_RG32F, .width = tex.size, .height = tex.size, .levels = levels};
    const gpu::Texture t = gpu::make_texture(spec);
    for (int l = 0; l < levels; ++l) gpu::upload_texture(t, spec, l, {GL_RG, GL_FLOAT, tex.levels[size_t(l)].data()});
    const gpu::Program prog = gpu::Program::compute("shaders/test/noise_texture.comp");
    const gpu::Buffer in = gpu::make_storage_buffer(points.data(), points.size() * sizeof(vec4));
    const gpu::Buffer out = gpu::make_storage_buffer(nullptr, points.size() * sizeof(vec2), GL_DYNAMIC_READ);

    auto worst_difference = [&](GLint min_filter, GLint mag_filter) {
        glTextureParameteri(t.get(), GL_TEXTURE_MIN_FILTER, min_filter);
        glTextureParameteri(t.get(), GL_TEXTURE_MAG_FILTER, mag_filter);
        prog.use();
        prog.bind_texture(0, GL_TEXTURE_2D, t.get(), "u_noise");
        glUniform1ui(prog.uniform("u_count"), GLuint(points.size()));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.get());
        glDispatchCompute(GLuint((points.size() + 63) / 64), 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<vec2> gpu(points.size());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, out.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(gpu.size() * sizeof(vec2)), gpu.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        gpu::check_gl("noise texture look-up");
        double worst = 0;
        for (size_t i = 0; i < points.size(); ++i)
            for (int c = 0; c < 2; ++c) worst = std::max(worst, std::fabs(double(cpu[i][c]) - double(gpu[i][c])));
        return worst;
    };
    const double linear = worst_difference(GL_LINEAR_MIPMAP_NEAREST, GL_LINEAR);
    const double nearest = worst_difference(GL_NEAREST_MIPMAP_NEAREST, GL_NEAREST);
    std::printf("noise texture look-up: worst difference %.2g (linear filters), %.2g (nearest)\n", linear, nearest);
    EXPECT_EQ(linear, 0.0);
    EXPECT_EQ(nearest, 0.0) << "the look-up depends on the texture's filter";
}
