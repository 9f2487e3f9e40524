// Visibility textures S_i on the GPU (gpu/microgeom/visibility_gpu.h, compute shader
// microgeom/visibility.comp) against the CPU's compute_visibility (core/microgeom/visibility.h),
// on a headless GL context (Mesa llvmpipe is enough).
//
// Tolerance: the GPU walks the same exact algorithm in float instead of double. Rays that graze
// the surface (f within float rounding of 0 along a piece, or passing within ~1e-5 texels of a
// vertex or edge) are genuinely ill-conditioned and may be classified differently, so we require
//   * classification (hit / no hit / below) equal for >= 99.9% of (direction, texel) pairs, and
//   * among pairs both call a hit, decoded hit points within 1/8 texel (twice the 1/16-texel
//     packing step; distance with wrap-around for periodic fields) for >= 99.9%.
// Measured on llvmpipe (printed per field): classification agrees on 100% of the pairs of the
// first test's five fields and common hits are at most one 1/16 packing step apart; the steep
// field has 1 disagreement in 947,200 pairs (a ray passing 2e-6 texels under a valley edge).
#include "core/heightfield/heightfield.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/visibility.h"
#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/microgeom/visibility_gpu.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

// [SECTION] Helpers
Heightfield random_field(int W, int H, bool periodic, uint32_t seed, float max_height) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, max_height);
    Heightfield f;
    f.width = W;
    f.height = H;
    f.periodic = periodic;
    f.h.resize(size_t(W) * size_t(H));
    for (float& x : f.h) x = u(rng);
    f.albedo.assign(f.h.size(), vec3(0.5f));
    return f;
}

Heightfield procedural(const std::string& name, int resolution) {
    ProceduralParams p;
    p.name = name;
    p.resolution = resolution;
    return make_procedural(p);
}

enum class Kind { Hit, NoHit, Below };
Kind kind(uint32_t v) { return v == Visibility::kNoHit ? Kind::NoHit : v == Visibility::kBelow ? Kind::Below : Kind::Hit; }

struct Agreement {
    size_t pairs = 0, class_mismatch = 0, hit_nohit = 0, below_mismatch = 0;
    size_t common_hits = 0, far_hits = 0, exact_hits = 0;
    double max_dist = 0;
    double class_rate() const { return pairs ? 1.0 - double(class_mismatch) / double(pairs) : 1.0; }
    double hit_rate() const { return common_hits ? 1.0 - double(far_hits) / double(common_hits) : 1.0; }
};

Agreement compare(const Heightfield& hf, const Visibility& cpu, const Visibility& gpu) {
    Agreement a;
    a.pairs = cpu.hit.size();
    for (size_t k = 0; k < cpu.hit.size(); ++k) {
        const uint32_t c = cpu.hit[k], g = gpu.hit[k];
        const Kind kc = kind(c), kg = kind(g);
        if (kc != kg) {
            ++a.class_mismatch;
            if (kc == Kind::Below || kg == Kind::Below) ++a.below_mismatch;
            else ++a.hit_nohit;
            continue;
        }
        if (kc != Kind::Hit) continue;
        ++a.common_hits;
        if (c == g) ++a.exact_hits;
        const vec2 pc = Visibility::decode(c), pg = Visibility::decode(g);
        double dx = std::abs(double(pc.x) - double(pg.x)), dy = std::abs(double(pc.y) - double(pg.y));
        if (hf.periodic) {
            dx = std::min(dx, double(hf.width) - dx);
            dy = std::min(dy, double(hf.height) - dy);
        }
        const double d = std::sqrt(dx * dx + dy * dy);
        a.max_dist = std::max(a.max_dist, d);
        if (d > 1.0 / 8.0) ++a.far_hits;
    }
    return a;
}

// [SECTION] Fixture: a headless context per test (skipped, with the reason, where none can be made;
// tests/gpu reports that failure).
class VisibilityGpu : public ::testing::Test {
protected:
    void SetUp() override {
        try {
            ctx_ = gpu::HeadlessContext::create();
        } catch (const std::exception& e) {
            GTEST_SKIP() << "no OpenGL context: " << e.what();
        }
    }
    void TearDown() override { ctx_.reset(); }
    std::unique_ptr<gpu::HeadlessContext> ctx_;
};

// Computes both, prints the agreement and checks it against the tolerance above.
void check_agreement(const gpu::VisibilityProgram& program, const std::string& name, const Heightfield& hf, const DirectionSet& dirs) {
    SCOPED_TRACE(name);
    const Visibility cpu = compute_visibility(hf, dirs);
    const Visibility gpu = program.compute(hf, dirs);
    ASSERT_EQ(gpu.width, cpu.width);
    ASSERT_EQ(gpu.height, cpu.height);
    ASSERT_EQ(gpu.count, cpu.count);
    ASSERT_EQ(gpu.hit.size(), cpu.hit.size());
    ASSERT_EQ(cpu.hit.size(), size_t(hf.width) * size_t(hf.height) * size_t(dirs.size())) << "nothing to compare";
    const Agreement a = compare(hf, cpu, gpu);
    EXPECT_GT(a.common_hits, 0u) << "no hits in common: the hit positions were not compared";
    std::printf("%-27s pairs %7zu  class agree %.5f%% (hit/no-hit %zu, below %zu)  common hits %zu: within 1/8 %.5f%%, "
                "identical %.3f%%, max dist %.4f texels\n",
                name.c_str(), a.pairs, 100.0 * a.class_rate(), a.hit_nohit, a.below_mismatch, a.common_hits, 100.0 * a.hit_rate(),
                a.common_hits ? 100.0 * double(a.exact_hits) / double(a.common_hits) : 100.0, a.max_dist);
    EXPECT_GE(a.class_rate(), 0.999);
    EXPECT_GE(a.hit_rate(), 0.999);
    // The below-horizon test is the same float expression on both sides.
    EXPECT_EQ(a.below_mismatch, 0u);
}

// [SECTION] Agreement with the CPU
TEST_F(VisibilityGpu, AgreesWithCpuOnRandomAndProceduralFields) {
    const DirectionSet dirs = make_direction_set(100);
    const gpu::VisibilityProgram program;
    check_agreement(program, "random 24x20 periodic", random_field(24, 20, true, 11, 3.f), dirs);
    check_agreement(program, "random 24x20 non-periodic", random_field(24, 20, false, 12, 3.f), dirs);
    check_agreement(program, "bricks 128", procedural("bricks", 128), dirs);
    check_agreement(program, "triangles 64", procedural("triangles", 64), dirs);
    check_agreement(program, "bumps 64", procedural("bumps", 64), dirs);
}

// Steep and tall fields: the lifted origin is then often within 1e-2 texels of the surface (the
// lift follows the central-difference normal, not the triangles), and heights of 1e4 texels
// dwarf the 1e-3 lift; the shader evaluates f about the origin texel to stay exact there.
TEST_F(VisibilityGpu, AgreesWithCpuOnSteepAndTallFields) {
    const DirectionSet dirs = make_direction_set(256);
    const gpu::VisibilityProgram program;
    check_agreement(program, "random 100x37 slopes ~20", random_field(100, 37, true, 7, 20.f), dirs);
    check_agreement(program, "random 16x16 heights 1e4", random_field(16, 16, false, 62, 1e4f), dirs);
}

// The texture path (filled on the GPU from the output buffer) holds exactly what compute() reads
// back, as one R32UI layer per direction.
TEST_F(VisibilityGpu, TextureMatchesReadBack) {
    const DirectionSet dirs = make_direction_set(20);
    const Heightfield hf = random_field(13, 9, true, 5, 2.f);  // odd sizes: rows not 8-byte aligned
    const gpu::VisibilityProgram program;
    const Visibility vis = program.compute(hf, dirs);
    const gpu::Texture tex = program.compute_texture(hf, dirs);
    ASSERT_TRUE(tex);
    glBindTexture(GL_TEXTURE_2D_ARRAY, tex.get());
    GLint w = 0, h = 0, d = 0, format = 0;
    glGetTexLevelParameteriv(GL_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_WIDTH, &w);
    glGetTexLevelParameteriv(GL_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_HEIGHT, &h);
    glGetTexLevelParameteriv(GL_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_DEPTH, &d);
    glGetTexLevelParameteriv(GL_TEXTURE_2D_ARRAY, 0, GL_TEXTURE_INTERNAL_FORMAT, &format);
    EXPECT_EQ(w, hf.width);
    EXPECT_EQ(h, hf.height);
    EXPECT_EQ(d, dirs.size());
    EXPECT_EQ(format, GL_R32UI);
    microgeom::HitArray texels(vis.hit.size(), 0u);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTexImage(GL_TEXTURE_2D_ARRAY, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, texels.data());
    EXPECT_NO_THROW(gpu::check_gl("read texture"));
    EXPECT_EQ(texels, vis.hit);
    // And the free function gives the same.
    EXPECT_EQ(gpu::compute_visibility_gpu(hf, dirs).hit, vis.hit);
}

// Degenerate inputs behave as on the CPU: empty results, no surface (one texel wide, or texel
// size 0) gives kBelow/kNoHit only, a wrong number of heights throws.
TEST_F(VisibilityGpu, DegenerateFieldsMatchCpu) {
    const DirectionSet dirs = make_direction_set(16);
    const gpu::VisibilityProgram program;
    Heightfield empty;
    const Visibility e = program.compute(empty, dirs);
    EXPECT_TRUE(e.hit.empty());
    EXPECT_EQ(e.count, dirs.size());
    EXPECT_FALSE(program.compute_texture(empty, dirs));

    Heightfield strip = random_field(1, 7, false, 3, 1.f);
    EXPECT_EQ(program.compute(strip, dirs).hit, compute_visibility(strip, dirs).hit);
    Heightfield flat = random_field(5, 4, true, 4, 0.f);
    EXPECT_EQ(program.compute(flat, dirs).hit, compute_visibility(flat, dirs).hit);

    Heightfield bad = random_field(4, 4, true, 5, 1.f);
    bad.h.pop_back();
    EXPECT_THROW(program.compute(bad, dirs), std::invalid_argument);
}

// [SECTION] One program, many dispatches: its buffers are reused for a field and direction set of
// another size and back, and every result is bit-identical to the first one's (and, for the small
// field, to a fresh program's). Bricks 128 x 100 directions is the bench's size; its agreement with
// the CPU is AgreesWithCpuOnRandomAndProceduralFields.
TEST_F(VisibilityGpu, ReusedProgramGivesIdenticalResultsForEveryDispatch) {
    const DirectionSet dirs = make_direction_set(100), few = make_direction_set(20);
    const Heightfield hf = procedural("bricks", 128);
    const Heightfield small = random_field(13, 9, true, 5, 2.f);
    const gpu::VisibilityProgram program;
    const Visibility first = program.compute(hf, dirs);
    ASSERT_EQ(first.hit.size(), size_t(128) * 128 * size_t(dirs.size()));
    const Visibility between = program.compute(small, few);
    EXPECT_EQ(between.hit, gpu::VisibilityProgram().compute(small, few).hit) << "a reused program differs from a fresh one";
    for (int k = 0; k < 3; ++k) {
        const Visibility again = program.compute(hf, dirs);
        ASSERT_EQ(again.hit.size(), first.hit.size());
        EXPECT_TRUE(again.hit == first.hit) << "dispatch " << k + 2 << " differs from the first";
    }
    // The field is not trivial: hits, sky and below-horizon entries all occur.
    size_t hits = 0, sky = 0, below = 0;
    for (uint32_t v : first.hit) (v == Visibility::kNoHit ? sky : v == Visibility::kBelow ? below : hits)++;
    EXPECT_GT(hits, 0u);
    EXPECT_GT(sky, 0u);
    EXPECT_GT(below, 0u);
}
}  // namespace

namespace {
// Small batches, two in flight: every output buffer is reused several times, and the results
// (read back, or copied into the texture on the GPU) are those of one batch per field.
TEST_F(VisibilityGpu, SmallBatchesInFlightGiveTheSameTextures) {
    const DirectionSet dirs = make_direction_set(40);
    const Heightfield hf = procedural("bricks", 64);
    const gpu::VisibilityProgram whole;
    gpu::VisibilityProgram small;
    const size_t per_dir = size_t(64) * 64;
    small.set_batching({.invocations = per_dir * 3, .batch_bytes = per_dir * 4 * 3, .in_flight_bytes = per_dir * 4 * 6});  // 14 batches, 2 buffers
    const Visibility a = whole.compute(hf, dirs), b = small.compute(hf, dirs);
    ASSERT_EQ(a.hit.size(), per_dir * size_t(dirs.size()));
    EXPECT_TRUE(a.hit == b.hit) << "batches in flight changed S_i";
    const gpu::Texture t = small.compute_texture(hf, dirs);
    microgeom::HitArray layers(a.hit.size());
    glGetTextureImage(t.get(), 0, GL_RED_INTEGER, GL_UNSIGNED_INT, GLsizei(layers.size() * sizeof(uint32_t)), layers.data());
    EXPECT_TRUE(layers == a.hit) << "the texture's layers differ from the read-back";
}
}  // namespace
