// The GPU resource cache: GL objects are keyed by the stage result they were made from (its
// control block, not its address) and go with it.
#include "app/workbench.h"
#include "gpu/context.h"
#include "gpu/renderer.h"
#include "gpu/resources.h"

#include <gtest/gtest.h>
#include <memory>

using namespace mesolab;
using namespace mesolab::gpu;

namespace {

std::vector<float> read_texture(GLuint tex, int w, int h) {
    std::vector<float> rgba(size_t(w) * size_t(h) * 4);
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, rgba.data());
    return rgba;
}

Image solid(float r, float g, float b) {
    Image img(2, 2, 3, 0.f);
    for (int i = 0; i < 4; ++i) img.data[size_t(i) * 3 + 0] = r, img.data[size_t(i) * 3 + 1] = g, img.data[size_t(i) * 3 + 2] = b;
    return img;
}
}  // namespace

// A result freed and a new one made at the same address (here forced: both alias one storage)
// must get a texture of its own content, never the old one's.
TEST(GpuResources, ANewResultAtAFreedResultsAddressGetsItsOwnTexture) {
    auto ctx = HeadlessContext::create();
    gpu::Renderer r;
    Image storage = solid(1.f, 0.f, 0.f);
    std::shared_ptr<const Image> first(&storage, [](const Image*) {});
    const std::vector<float> red = read_texture(r.texture(first), 2, 2);
    EXPECT_FLOAT_EQ(red[0], 1.f);
    EXPECT_FLOAT_EQ(red[2], 0.f);
    first.reset();
    storage = solid(0.f, 0.f, 1.f);
    std::shared_ptr<const Image> second(&storage, [](const Image*) {});
    ASSERT_EQ(second.get(), &storage) << "the test wants the address reused";
    const std::vector<float> blue = read_texture(r.texture(second), 2, 2);
    EXPECT_FLOAT_EQ(blue[0], 0.f) << "a stale texture of the freed result was handed back";
    EXPECT_FLOAT_EQ(blue[2], 1.f);
}

TEST(GpuResources, EntriesAreMadeOnceAndGoWithTheirResult) {
    auto ctx = HeadlessContext::create();
    GpuResources res;
    auto owner = std::make_shared<const int>(7);
    int makes = 0;
    const auto make = [&] {
        ++makes;
        GLuint id = 0;
        glGenBuffers(1, &id);
        return Buffer(id);
    };
    const GLuint a = res.get<Buffer>(owner, "slot", make).get();
    const GLuint b = res.get<Buffer>(owner, "slot", make).get();
    EXPECT_EQ(a, b);
    EXPECT_EQ(makes, 1);
    res.get<Buffer>(owner, "another slot", make);
    EXPECT_EQ(makes, 2);
    EXPECT_EQ(res.collect(), 0u) << "the result still exists";
    owner.reset();
    EXPECT_EQ(res.collect(), 2u);
    EXPECT_EQ(res.size(), 0u);
    EXPECT_THROW(res.get<Buffer>(std::shared_ptr<const int>(), "slot", make), std::logic_error);
}

// Through the renderer: the meshes of results the session no longer holds are freed.
TEST(GpuResources, TheRendererFreesWhatTheSessionEvicted) {
    Workbench wb;
    RenderRequest req;
    req.width = req.height = 16;
    Scene s = default_scene("basic");
    for (int res : {8, 9, 10, 11, 12, 13}) {
        apply_set(s, "geometry.resolution=" + std::to_string(res));
        wb.render(s, req);
    }
    // The session keeps a few tessellations (cache_capacity_per_stage); the GPU keeps no more.
    EXPECT_LE(wb.gpu().resources().size(), wb.session().cache_capacity_per_stage + 1);
    wb.session().cache().clear();
    apply_set(s, "geometry.resolution=20");
    wb.render(s, req);
    EXPECT_EQ(wb.gpu().resources().size(), 1u) << "only the mesh on screen";
}
