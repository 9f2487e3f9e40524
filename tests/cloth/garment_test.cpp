// Procedural garments (core/cloth/garment.h): uv over [0, 1]², unit normals facing the way the
// triangles wind, tangents along +u, and the curtain's u following arc length.
#include "core/cloth/garment.h"
#include "core/cloth/stages.h"
#include "core/error.h"

#include <gtest/gtest.h>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
void check_frames(const TriMesh& m, const std::string& name) {
    ASSERT_TRUE(m.has_uv) << name;
    ASSERT_EQ(m.uv.size(), m.position.size()) << name;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        ASSERT_NEAR(glm::length(m.normal[v]), 1.f, 1e-4f) << name;
        ASSERT_NEAR(glm::length(m.tangent[v]), 1.f, 1e-4f) << name;
        ASSERT_NEAR(glm::dot(m.normal[v], m.tangent[v]), 0.f, 1e-4f) << name;
        ASSERT_GE(m.uv[v].x, 0.f) << name;
        ASSERT_LE(m.uv[v].x, 1.f) << name;
        ASSERT_GE(m.uv[v].y, 0.f) << name;
        ASSERT_LE(m.uv[v].y, 1.f) << name;
    }
    size_t agree = 0;
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const uint32_t a = m.index[3 * f], b = m.index[3 * f + 1], c = m.index[3 * f + 2];
        const vec3 n = glm::cross(m.position[b] - m.position[a], m.position[c] - m.position[a]);
        const vec3 avg = m.normal[a] + m.normal[b] + m.normal[c];
        agree += glm::dot(n, avg) > 0.f;
    }
    EXPECT_EQ(agree, m.triangle_count()) << name;
}
}  // namespace

TEST(Garments, FramesUvAndWindingAgree) {
    check_frames(make_curtain(4, 0.18f, 64), "curtain");
    check_frames(make_curtain(0, 0.f, 16), "flat curtain");
    check_frames(make_sleeve(1.f, 48), "sleeve");
    check_frames(make_sleeve(0.f, 48), "straight sleeve");
    // The curtain faces −y (towards a camera in front of it).
    const TriMesh c = make_curtain(0, 0.f, 8);
    for (const vec3& n : c.normal) EXPECT_NEAR(n.y, -1.f, 1e-5f);
    // The sleeve's normals point away from its axis.
    const TriMesh s = make_sleeve(0.f, 16);
    for (size_t v = 0; v < s.vertex_count(); ++v) EXPECT_GT(glm::dot(s.normal[v], vec3(s.position[v].x, s.position[v].y, 0.f)), 0.3f);
}

TEST(Garments, CurtainUFollowsArcLength) {
    const TriMesh m = make_curtain(4, 0.25f, 128);
    // Along the bottom row, equal steps in u cover equal lengths of cloth.
    const int nu = 128;
    float total = 0.f;
    for (int i = 0; i < nu; ++i) total += glm::length(m.position[size_t(i + 1)] - m.position[size_t(i)]);
    for (int i = 0; i < nu; i += 16) {
        const float du = m.uv[size_t(i + 1)].x - m.uv[size_t(i)].x, len = glm::length(m.position[size_t(i + 1)] - m.position[size_t(i)]);
        EXPECT_NEAR(du, len / total, 0.02f / float(nu)) << i;
    }
}

TEST(Garments, BadNamesAndResolutionsNameTheirKey) {
    try {
        make_garment("dress", 32);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cloth.garment"), std::string::npos);
    }
    EXPECT_THROW(make_curtain(4, 0.2f, 2), InputError);
    EXPECT_EQ(make_garment("sleeve", 32).triangle_count(), 32u * 16u * 2u);
}
