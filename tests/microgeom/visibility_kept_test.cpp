// S_i kept on the GPU after the GPU computed it (VisibilityProgram::compute's keep_on_gpu,
// gpu/microgeom/chunks.h ResidentHits): the kept copy holds exactly what was read back, the
// passes that read S_i next (scattering, light images, a curved base's importance) read it there
// instead of uploading it and give bit-identical results, the
// copy's buffers are freed on the compute context whichever thread drops the last Visibility, and
// the stages render the same frame whether S_i was kept or not.
//
// On llvmpipe S_i is not kept by default (visibility_gpu.h KeepOnGpu::Automatic); these tests ask
// for it, so that the path a hardware GPU takes runs here too.
#include "app/workbench.h"
#include "core/microgeom/curvature.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/scatter.h"
#include "core/microgeom/stages.h"
#include "core/microgeom/visibility.h"
#include "core/scene.h"
#include "gpu/context.h"
#include "gpu/gl.h"
#include "gpu/microgeom/chunks.h"
#include "gpu/microgeom/importance_gpu.h"
#include "gpu/microgeom/lights_gpu.h"
#include "gpu/microgeom/scatter_gpu.h"
#include "gpu/microgeom/visibility_gpu.h"
#include "agreement.h"
#include "support/cli.h"

#include <gtest/gtest.h>

#include <memory>
#include <thread>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

// [SECTION] Helpers
constexpr int kRes = 48, kDirections = 40;
constexpr size_t kPerDirection = size_t(kRes) * kRes * sizeof(uint32_t);

Heightfield bricks() {
    ProceduralParams p;
    p.name = "bricks";
    p.resolution = kRes;
    return make_procedural(p);
}

// A program whose batches (4 directions) straddle the kept copy's chunks (3 directions), two
// batches in flight. Call it holding the compute scope: the program belongs to that context.
gpu::VisibilityProgram& straddling_program() {
    static gpu::VisibilityProgram* program = [] {
        auto* p = new gpu::VisibilityProgram();
        p->set_batching({.invocations = kPerDirection, .batch_bytes = kPerDirection * 4, .in_flight_bytes = kPerDirection * 8,
                         .kept_chunk_bytes = kPerDirection * 3});
        return p;
    }();
    return *program;
}

// S_i computed on the compute context, kept there in chunks of 3 directions.
Visibility compute_kept(const Heightfield& hf, const DirectionSet& dirs) {
    gpu::ComputeScope scope;
    return straddling_program().compute(hf, dirs, true);
}

std::vector<uint32_t> read_buffer(GLuint b, size_t words) {
    std::vector<uint32_t> v(words);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(words * sizeof(uint32_t)), v.data());
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    return v;
}

struct KeepAlways {
    KeepAlways() { gpu::set_keep_visibility_on_gpu(gpu::KeepOnGpu::Always); }
    ~KeepAlways() { gpu::set_keep_visibility_on_gpu(gpu::KeepOnGpu::Automatic); }
};

}  // namespace

// [SECTION] The kept copy
TEST(VisibilityKept, CopyOnTheGpuEqualsTheReadBack) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = bricks();
    const DirectionSet dirs = make_direction_set(kDirections);
    const Visibility vis = compute_kept(hf, dirs);
    const auto kept = std::dynamic_pointer_cast<const gpu::ResidentHits>(vis.device);
    ASSERT_TRUE(kept) << "S_i was not kept";
    std::vector<int> expected;
    for (int j = 0; j < kDirections; j += 3) expected.push_back(j);
    ASSERT_EQ(kept->begin(), expected);
    gpu::ComputeScope scope;
    size_t differing = 0;
    for (size_t c = 0; c < expected.size(); ++c) {
        const int j0 = expected[c], j1 = c + 1 < expected.size() ? expected[c + 1] : kDirections;
        const std::vector<uint32_t> words = read_buffer(kept->buffer(c), size_t(j1 - j0) * kPerDirection / 4);
        for (size_t i = 0; i < words.size(); ++i) differing += words[i] != vis.hit[size_t(j0) * kPerDirection / 4 + i];
    }
    EXPECT_EQ(differing, 0u) << "the kept copy differs from the read-back";
    // And both equal what the program computes without keeping anything.
    EXPECT_TRUE(straddling_program().compute(hf, dirs).hit == vis.hit);
    EXPECT_TRUE(gpu::VisibilityProgram().compute(hf, dirs).hit == vis.hit);
    // Its size counts where it lives: in the host's memory on a renderer that runs on the CPU.
    EXPECT_EQ(vis.bytes(), vis.hit.size() * 4 * (gpu::current_renderer_is_software() ? 2 : 1));
}

TEST(VisibilityKept, OnlyTheComputeContextKeepsIt) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const auto ctx = gpu::HeadlessContext::create();
    const gpu::VisibilityProgram program;
    EXPECT_THROW(program.compute(bricks(), make_direction_set(8), true), std::logic_error);
}

// [SECTION] Its readers
TEST(VisibilityKept, PassesOnTheComputeContextBindItInsteadOfUploading) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Visibility vis = compute_kept(bricks(), make_direction_set(kDirections));
    ASSERT_TRUE(vis.device);
    {
        gpu::ComputeScope scope;
        const gpu::DirectionChunks alike = gpu::upload_direction_chunks(vis, nullptr, kPerDirection * 3, "test");
        EXPECT_TRUE(alike.resident) << "chunked alike on the same context: bound, not uploaded";
        EXPECT_TRUE(alike.uploaded.empty());
        EXPECT_EQ(alike.S(1), std::dynamic_pointer_cast<const gpu::ResidentHits>(vis.device)->buffer(1));
        const gpu::DirectionChunks other = gpu::upload_direction_chunks(vis, nullptr, kPerDirection * 5, "test");
        EXPECT_FALSE(other.resident) << "chunked otherwise: uploaded";
        EXPECT_EQ(other.uploaded.size(), other.size());
    }
    // Another context cannot see the compute context's buffers: it uploads.
    const auto ctx = gpu::HeadlessContext::create();
    const gpu::DirectionChunks elsewhere = gpu::upload_direction_chunks(vis, nullptr, kPerDirection * 3, "test");
    EXPECT_FALSE(elsewhere.resident);
    EXPECT_EQ(elsewhere.uploaded.size(), elsewhere.size());
}

TEST(VisibilityKept, ScatteringAndLightImagesFromTheKeptCopyEqualTheUploadedOnes) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = bricks();
    const DirectionSet dirs = make_direction_set(kDirections);
    const Visibility kept = compute_kept(hf, dirs);
    Visibility uploaded = kept;
    uploaded.device.reset();
    ASSERT_TRUE(kept.device);
    Environment env;
    env.color = vec3(0.3f, 0.5f, 0.8f);
    ScatterSettings s;
    s.light_dir = normalize(vec3(0.3f, 0.2f, 0.9f));
    s.light_E = vec3(1.f);
    s.env = &env;
    s.depth = 3;
    const auto bounces = [&](const Visibility& vis) {
        const auto g = gpu::make_gpu_gatherer(kPerDirection * 3);
        ScatterSettings st = s;
        st.gatherer = g.get();
        return scatter(hf, dirs, vis, st).E_indirect;
    };
    const std::vector<vec3> a = bounces(kept), b = bounces(uploaded);
    ASSERT_EQ(a.size(), size_t(kRes) * kRes);
    EXPECT_TRUE(a == b) << "the scattering differs with S_i kept";
    double largest = 0;
    for (const vec3& e : a) largest = std::max(largest, double(e.x + e.y + e.z));
    EXPECT_GT(largest, 0.0) << "no irradiance anywhere: two zero results agree about nothing";

    const std::vector<vec3> wis = {normalize(vec3(0.f, 0.f, 1.f)), normalize(vec3(0.6f, -0.2f, 0.7f))};
    const auto images = [&](const Visibility& vis) {
        ScatterSettings st = s;
        st.env = nullptr;
        const auto solver = gpu::make_gpu_light_solver(hf, dirs, vis, st, kPerDirection * 3);
        std::vector<std::vector<vec3>> L;
        std::vector<std::vector<float>> shadow;
        solver->solve(wis, L, shadow);
        return L;
    };
    const auto La = images(kept), Lb = images(uploaded);
    ASSERT_EQ(La.size(), wis.size());
    EXPECT_TRUE(La == Lb) << "the light images differ with S_i kept";
}

TEST(VisibilityKept, CurvedImportanceFromTheKeptCopyEqualsTheUploadedOne) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const Heightfield hf = bricks();
    const DirectionSet dirs = make_direction_set(kDirections);
    const Visibility kept = compute_kept(hf, dirs);
    Visibility uploaded = kept;
    uploaded.device.reset();
    ASSERT_TRUE(kept.device);
    const Bending b = Bending::from_degrees(60.f, -30.f, hf.width, hf.height);
    const Importance a = gpu::compute_importance_gpu(hf, dirs, kept, b), c = gpu::compute_importance_gpu(hf, dirs, uploaded, b);
    ASSERT_EQ(a.w.size(), size_t(kRes) * kRes * kDirections);
    EXPECT_TRUE(a.I == c.I && a.w == c.w && a.folded == c.folded) << "the importance differs with S_i kept";
    size_t bent = 0;
    for (float i : a.I) bent += i != 1.f;
    EXPECT_GT(bent, a.I.size() / 20) << "the bend changed too few fan areas to tell";  // 4,864 of 46,080 here
}

// [SECTION] Its lifetime
TEST(VisibilityKept, DroppedOnAnotherThreadItsBuffersGoOnTheComputeContext) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    auto vis = std::make_unique<Visibility>(compute_kept(bricks(), make_direction_set(kDirections)));
    std::vector<GLuint> names;
    std::weak_ptr<const gpu::ResidentHits> watch;
    {
        const auto kept = std::dynamic_pointer_cast<const gpu::ResidentHits>(vis->device);
        ASSERT_TRUE(kept);
        for (size_t c = 0; c < kept->begin().size(); ++c) names.push_back(kept->buffer(c));
        watch = kept;
    }
    {
        gpu::ComputeScope scope;
        for (GLuint n : names) EXPECT_TRUE(glIsBuffer(n));
    }
    std::thread([v = std::move(vis)]() mutable { v.reset(); }).join();  // the last owner, on a thread without the compute context
    ASSERT_TRUE(watch.expired());
    gpu::ComputeScope scope;  // deletes what was dropped elsewhere
    for (GLuint n : names) EXPECT_FALSE(glIsBuffer(n)) << "buffer " << n << " outlived its Visibility";
}

// [SECTION] Through the stages
TEST(VisibilityKept, StagesRenderTheSameFrameWhetherSiIsKeptOrNot) {
    if (!test::have_compute_gl()) GTEST_SKIP() << "no OpenGL context";
    const auto render = [](gpu::KeepOnGpu k) {
        gpu::set_keep_visibility_on_gpu(k);
        Scene scene = load_preset(test::source_path("presets/microgeom/bricks-texture.json"));
        for (const char* set : {"microgeom.resolution=64", "microgeom.device=gpu"}) apply_set(scene, set);
        Workbench wb;  // a cache of its own: S_i computed anew
        RenderRequest req;
        req.renderer = "cpu";
        RenderResult r = wb.render(scene, req);
        const Evaluation ev = wb.evaluate(scene, {microgeom::stages::visibility});
        EXPECT_EQ(bool(ev.get(microgeom::stages::visibility, 0)->device), k == gpu::KeepOnGpu::Always);
        return r;
    };
    const RenderResult never = render(gpu::KeepOnGpu::Never);
    RenderResult always;
    {
        KeepAlways keep;
        always = render(gpu::KeepOnGpu::Always);
    }
    test::expect_ran_on_the_gpu(always, {microgeom::stages::visibility, microgeom::stages::scatter});
    for (const char* aov : {"radiance", "indirect"}) {
        ASSERT_TRUE(never.frame.has(aov) && always.frame.has(aov)) << aov;
        EXPECT_TRUE(never.frame.aov(aov).data == always.frame.aov(aov).data) << aov << " differs with S_i kept";
    }
}
