// A pixel's look-up-table inputs and table entries on the GPU (gpu/bumpsynth/synthesis.glsl, what
// bumpsynth.frag computes) against the CPU's (synthesis_inputs, Lut::entry), from the same uv: the
// same bits, so the same entries. The nearest entry is a discontinuous function of the inputs, so
// only equality makes a frame's entries equal wherever the rasterisers' uv are; with fused
// multiply-adds (no `precise`), a division the implementation rounds, or GLSL's mix, the inputs
// differ in the last bits and a few of these points get another entry.
// Points: random uv (also outside [0, 1]: wrapping), uv on the noise lattices' cell edges and on the
// index texture's texel centres, every octave count, with and without the fine octave.
#include "core/bumpsynth/bumpsynth.h"
#include "core/scene.h"
#include "core/session.h"
#include "gpu/bumpsynth/synthesis.h"
#include "gpu/context.h"
#include "gpu/gl.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <cstdio>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

using namespace mesolab;
using namespace mesolab::bumpsynth;

namespace {

struct Case {
    const char* preset;
    std::vector<std::pair<const char*, const char*>> sets;
};

// Points (u, v, k, fine) for octave counts 1..K.
std::vector<vec4> points_for(const Synthesis& syn, int K) {
    std::vector<vec4> p;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> uv(-0.5f, 1.5f), unit(0.f, 1.f);
    for (int k = 1; k <= K; ++k)
        for (int i = 0; i < 4000; ++i) p.emplace_back(i < 3000 ? unit(rng) : uv(rng), i < 3000 ? unit(rng) : uv(rng), float(k), float(k < K && i % 2 == 0));
    // On the cell edges of the first octaves' lattices (or the index texture's texel centres), and at 0 and 1.
    const NoiseOctaves& oc = syn.index_map ? syn.index_detail.octaves : syn.cdfs->octaves;
    for (int o = 0; o < std::min(oc.count, 3); ++o)
        for (int j = 0; j <= oc.period[o][0]; j += std::max(1, oc.period[o][0] / 64)) {
            const float e = (float(j) - oc.offset[o][0].x) / float(oc.period[o][0]);
            for (int k = 1; k <= K; ++k) p.emplace_back(e, unit(rng), float(k), float(k < K)), p.emplace_back(unit(rng), e, float(k), 0.f);
        }
    if (syn.index_map)
        for (int x = 0; x < syn.index_map->width; x += 3)
            p.emplace_back((float(x) + 0.5f) / float(syn.index_map->width), unit(rng), 1.f, 1.f);
    for (float e : {0.f, 1.f})
        for (int k = 1; k <= K; ++k) p.emplace_back(e, e, float(k), float(k < K));
    return p;
}
}  // namespace

TEST(BumpsynthInputsGpu, SameUvGivesTheCpuBitsAndTableEntries) {
    std::unique_ptr<gpu::ComputeScope> scope;
    try {
        scope = std::make_unique<gpu::ComputeScope>();
    } catch (const std::runtime_error&) {
        GTEST_SKIP() << "no OpenGL context";
    }
    const gpu::Program prog = gpu::Program::compute("shaders/test/bumpsynth_inputs.comp");
    // Procedural noise (48 cells, 8 octaves; and 5 cells with lut_size 100, not a power of two), the
    // noise texture, and an index map with detail noise.
    const std::vector<Case> cases = {{"fig4-teapot-ndf", {}},
                                     {"fig4-teapot-ndf", {{"bumpsynth.noise_frequency", "5"}, {"bumpsynth.lut_size", "100"}}},
                                     {"fig5-teapot-hardware", {{"bumpsynth.noise_texture_size", "256"}}},
                                     {"sec7-index-map-zoom", {}}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.preset);
        Scene s = load_preset(test::source_path(std::string("presets/bumpsynth/") + c.preset + ".json"));
        for (const auto& [k, v] : c.sets) apply_set(s, k, v);
        Session session;
        const Evaluation ev = session.evaluate_frame(s);
        const Synthesis syn = synthesis_for(s, ev, 0);
        const int K = syn.octaves_max;
        const std::vector<vec4> points = points_for(syn, K);

        // The GL objects, as bumpsynth_pass.cpp makes them.
        gpu::Buffer cdf;
        gpu::Texture noise, index;
        gpu::SynthesisObjects objects;
        if (syn.cdfs && !syn.index_map) cdf = gpu::make_storage_buffer(syn.cdfs->table.data(), syn.cdfs->table.size() * sizeof(float)), objects.cdf = cdf.get();
        if (syn.noise_texture) {
            const NoiseTexture& n = *syn.noise_texture;
            const gpu::TextureSpec spec{.format = GL_RG32F, .width = n.size, .height = n.size, .levels = int(n.levels.size()),
                                        .min_filter = GL_NEAREST_MIPMAP_NEAREST, .mag_filter = GL_NEAREST};
            noise = gpu::make_texture(spec);
            for (int l = 0; l < spec.levels; ++l) gpu::upload_texture(noise, spec, l, {GL_RG, GL_FLOAT, n.levels[size_t(l)].data()});
            objects.noise = noise.get();
        }
        if (syn.index_map) {
            index = gpu::make_texture({.format = GL_RG32F, .width = syn.index_map->width, .height = syn.index_map->height},
                                      {GL_RG, GL_FLOAT, syn.index_map->u.data()});
            objects.index = index.get();
        }
        prog.use();
        gpu::set_synthesis_uniforms(prog, syn, objects, 0, 1);
        glUniform1ui(prog.uniform("u_count"), GLuint(points.size()));
        const gpu::Buffer in = gpu::make_storage_buffer(points.data(), points.size() * sizeof(vec4));
        const gpu::Buffer out_inputs = gpu::make_storage_buffer(nullptr, points.size() * sizeof(vec4), GL_DYNAMIC_READ);
        const gpu::Buffer out_entries = gpu::make_storage_buffer(nullptr, points.size() * sizeof(glm::ivec4), GL_DYNAMIC_READ);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, in.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, out_inputs.get());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, out_entries.get());
        glDispatchCompute(GLuint((points.size() + 63) / 64), 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<vec4> gpu_inputs(points.size());
        std::vector<glm::ivec4> gpu_entries(points.size());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, out_inputs.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(points.size() * sizeof(vec4)), gpu_inputs.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, out_entries.get());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(points.size() * sizeof(glm::ivec4)), gpu_entries.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        gpu::check_gl("bumpsynth inputs");

        size_t other_bits = 0, other_entries = 0;
        for (size_t i = 0; i < points.size(); ++i) {
            const vec2 uv(points[i]);
            const int k = int(points[i].z);
            const bool fine = points[i].w != 0.f;
            const vec2 cc = synthesis_inputs(syn, uv, k), cf = fine ? synthesis_inputs(syn, uv, k + 1) : vec2(0.5f);
            const vec4 cpu(cc, cf), g = gpu_inputs[i];
            const glm::ivec4 ce(syn.lut->entry(cc), syn.lut->entry(cf)), ge = gpu_entries[i];
            const bool same_bits = std::memcmp(&cpu, &g, sizeof(vec4)) == 0;
            other_bits += !same_bits;
            other_entries += ce != ge;
            if (!same_bits && other_bits <= 5)
                ADD_FAILURE() << "uv (" << uv.x << ", " << uv.y << "), k " << k << (fine ? " + 1" : "") << ": CPU inputs (" << cpu.x << ", " << cpu.y << ", "
                              << cpu.z << ", " << cpu.w << "), GPU (" << g.x << ", " << g.y << ", " << g.z << ", " << g.w << ")";
        }
        std::printf("%s: %zu points, %zu with other input bits, %zu with other entries\n", c.preset, points.size(), other_bits, other_entries);
        EXPECT_EQ(other_bits, 0u);
        EXPECT_EQ(other_entries, 0u);
    }
}
