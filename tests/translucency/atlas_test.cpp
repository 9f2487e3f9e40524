// The texture atlas (core/translucency/atlas.h): every triangle covered, no overlaps, borders as
// wide as promised, one texel size everywhere, continuity across chunk borders, the hard cases.
#include "core/error.h"
#include "core/mesh.h"
#include "core/translucency/atlas.h"
#include "core/translucency/mesh_prep.h"
#include "core/translucency/translucency.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
struct Mesh {
    std::vector<vec3> p;
    std::vector<uint32_t> i;
};

// Welds a primitive's seam and pole duplicates (equal positions), as the technique's mesh preparation does.
Mesh welded(const TriMesh& m) {
    Mesh out;
    std::map<std::tuple<float, float, float>, uint32_t> id;
    std::vector<uint32_t> remap(m.position.size());
    for (size_t v = 0; v < m.position.size(); ++v) {
        const vec3 q = m.position[v];
        auto [it, fresh] = id.emplace(std::make_tuple(q.x, q.y, q.z), uint32_t(out.p.size()));
        if (fresh) out.p.push_back(q);
        remap[v] = it->second;
    }
    for (uint32_t k : m.index) out.i.push_back(remap[k]);
    return out;
}

double cross2(vec2 a, vec2 b) { return double(a.x) * b.y - double(a.y) * b.x; }

// Is p strictly inside the triangle (by more than eps texels from every edge)?
bool strictly_inside(vec2 p, vec2 a, vec2 b, vec2 c, double eps) {
    const double s = cross2(b - a, c - a) > 0 ? 1.0 : -1.0;
    const vec2 q[3] = {a, b, c};
    for (int e = 0; e < 3; ++e) {
        const vec2 d = q[(e + 1) % 3] - q[e];
        const double w = s * cross2(d, p - q[e]) / std::max(1e-12, double(glm::length(d)));
        if (w <= eps) return false;
    }
    return true;
}

vec3 face_normal(const Mesh& m, size_t f) {
    const vec3 a = m.p[m.i[3 * f]], b = m.p[m.i[3 * f + 1]], c = m.p[m.i[3 * f + 2]];
    return glm::normalize(glm::cross(b - a, c - a));
}

const AtlasParams kParams{256, 4, 30.f};
}  // namespace

class AtlasOnShapes : public ::testing::TestWithParam<Primitive> {
protected:
    void SetUp() override {
        mesh = welded(make_primitive(GetParam(), GetParam() == Primitive::Teapot ? 48 : 40));
        atlas = build_atlas(mesh.p, mesh.i, kParams);
    }
    Mesh mesh;
    Atlas atlas;
};

TEST_P(AtlasOnShapes, EveryTriangleLiesInItsChunksRectangleAndLargeOnesOwnTexels) {
    const size_t F = mesh.i.size() / 3;
    std::vector<int> texels(F, 0);
    for (size_t t = 0; t < atlas.texel_kind.size(); ++t)
        if (atlas.texel_kind[t] == Atlas::kInner) ++texels[size_t(atlas.texel_face[t])];
    int placed = 0;
    for (size_t f = 0; f < F; ++f) {
        if (atlas.face_chunk[f] < 0) continue;
        ++placed;
        const AtlasChunk& c = atlas.chunks[size_t(atlas.face_chunk[f])];
        vec2 q[3];
        for (int j = 0; j < 3; ++j) {
            q[j] = atlas.corner_uv[3 * f + size_t(j)];
            EXPECT_GE(q[j].x, float(c.offset.x) - 1e-3f);
            EXPECT_GE(q[j].y, float(c.offset.y) - 1e-3f);
            EXPECT_LE(q[j].x, float(c.offset.x + c.extent.x) + 1e-3f);
            EXPECT_LE(q[j].y, float(c.offset.y + c.extent.y) + 1e-3f);
        }
        const double area = 0.5 * std::abs(cross2(q[1] - q[0], q[2] - q[0]));
        if (area >= 8.0) {
            EXPECT_GT(texels[f], 0) << "triangle " << f << " of " << area << " texels";
            // Texels owned ~ projected area (within the edges' share).
            EXPECT_NEAR(texels[f], area, 2.0 + 3.0 * std::sqrt(area));
        }
    }
    EXPECT_EQ(placed + atlas.skipped_degenerate, int(F));
    // Measured at 256²: sphere 0.33, torus 0.20, teapot 0.17 (small chunks, each with its border).
    EXPECT_GT(atlas.fill_ratio, 0.15);
    EXPECT_LT(atlas.fill_ratio, 1.0);
}

TEST_P(AtlasOnShapes, NoTwoChunksOverlapAndNoChunkFoldsOver) {
    const int B = atlas.border;
    for (size_t a = 0; a < atlas.chunks.size(); ++a) {
        const AtlasChunk& ca = atlas.chunks[a];
        EXPECT_GE(ca.offset.x - B, 0);
        EXPECT_GE(ca.offset.y - B, 0);
        EXPECT_LE(ca.offset.x + ca.extent.x + B, atlas.size);
        EXPECT_LE(ca.offset.y + ca.extent.y + B, atlas.size);
        for (size_t b = a + 1; b < atlas.chunks.size(); ++b) {
            const AtlasChunk& cb = atlas.chunks[b];
            const bool apart = ca.offset.x + ca.extent.x + B <= cb.offset.x - B || cb.offset.x + cb.extent.x + B <= ca.offset.x - B ||
                               ca.offset.y + ca.extent.y + B <= cb.offset.y - B || cb.offset.y + cb.extent.y + B <= ca.offset.y - B;
            EXPECT_TRUE(apart) << "chunks " << a << " and " << b;
        }
    }
    // No texel centre strictly inside two triangles (any chunk).
    std::vector<int> hits(atlas.texel_kind.size(), 0);
    for (size_t f = 0; f < mesh.i.size() / 3; ++f) {
        if (atlas.face_chunk[f] < 0) continue;
        const vec2 a = atlas.corner_uv[3 * f], b = atlas.corner_uv[3 * f + 1], c = atlas.corner_uv[3 * f + 2];
        const vec2 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
        for (int y = std::max(0, int(lo.y) - 1); y <= std::min(atlas.size - 1, int(hi.y) + 1); ++y)
            for (int x = std::max(0, int(lo.x) - 1); x <= std::min(atlas.size - 1, int(hi.x) + 1); ++x)
                if (strictly_inside(vec2(x + 0.5f, y + 0.5f), a, b, c, 1e-3)) ++hits[atlas.texel(x, y)];
    }
    for (int h : hits) ASSERT_LE(h, 1);
}

TEST_P(AtlasOnShapes, BordersAreAsWideAsPromised) {
    // A K x K kernel (K = 2 (border - 1) + 1) centred on any inner texel reads texels of the same
    // chunk that sample the surface.
    const int R = atlas.border - 1;
    for (int y = 0; y < atlas.size; ++y)
        for (int x = 0; x < atlas.size; ++x) {
            const size_t t = atlas.texel(x, y);
            if (atlas.texel_kind[t] != Atlas::kInner) continue;
            for (int dy = -R; dy <= R; ++dy)
                for (int dx = -R; dx <= R; ++dx) {
                    ASSERT_TRUE(x + dx >= 0 && y + dy >= 0 && x + dx < atlas.size && y + dy < atlas.size);
                    const size_t n = atlas.texel(x + dx, y + dy);
                    ASSERT_EQ(atlas.texel_chunk[n], atlas.texel_chunk[t]) << x << "," << y << " +" << dx << "," << dy;
                    ASSERT_GE(atlas.texel_face[n], 0);
                }
        }
}

TEST_P(AtlasOnShapes, EveryChunkHasTheSameTexelSize) {
    // Independent check of the global scale: each triangle's atlas edge = scale x its edge
    // projected along its chunk's normal.
    for (size_t f = 0; f < mesh.i.size() / 3; ++f) {
        if (atlas.face_chunk[f] < 0) continue;
        const AtlasChunk& c = atlas.chunks[size_t(atlas.face_chunk[f])];
        for (int j = 0; j < 3; ++j) {
            const vec3 e = mesh.p[mesh.i[3 * f + size_t((j + 1) % 3)]] - mesh.p[mesh.i[3 * f + size_t(j)]];
            const vec3 ep = e - glm::dot(e, c.normal) * c.normal;
            const float atlas_len = glm::length(atlas.corner_uv[3 * f + size_t((j + 1) % 3)] - atlas.corner_uv[3 * f + size_t(j)]);
            EXPECT_NEAR(atlas_len, atlas.scale * glm::length(ep), 1e-3f * std::max(1.f, atlas_len));
        }
        // Every triangle is within the chunk angle of its chunk's normal.
        EXPECT_GE(glm::dot(face_normal(mesh, f), c.normal), std::cos(glm::radians(kParams.chunk_angle)) - 1e-5f);
    }
    // Inner texels: 1/scale² in the plane, 1/(scale² cos θ) on the surface.
    for (size_t t = 0; t < atlas.texel_kind.size(); ++t) {
        if (atlas.texel_kind[t] != Atlas::kInner) continue;
        const AtlasChunk& c = atlas.chunks[size_t(atlas.texel_chunk[t])];
        const float cos_t = glm::dot(face_normal(mesh, size_t(atlas.texel_face[t])), c.normal);
        ASSERT_NEAR(atlas.texel_area[t] * cos_t * atlas.scale * atlas.scale, 1.f, 1e-3f);
    }
}

TEST_P(AtlasOnShapes, NeighbouringTexelsSampleNeighbouringSurfacePointsAcrossChunkEdges) {
    // Border texels hold the surface beyond the chunk's edge (unfolded): a step of one texel is a
    // step of about 1/scale on the surface, inside a chunk and across its edge alike. Unfolding is
    // exact only on developable surfaces, so the checks are on percentiles, per kind of pair.
    const float step = 1.f / atlas.scale;
    std::vector<float> inner, across, border;  // surface distance / step
    for (int y = 0; y + 1 < atlas.size; ++y)
        for (int x = 0; x + 1 < atlas.size; ++x) {
            const size_t t = atlas.texel(x, y);
            const uint8_t k = atlas.texel_kind[t];
            if (k != Atlas::kInner && k != Atlas::kBorder) continue;
            for (const size_t n : {atlas.texel(x + 1, y), atlas.texel(x, y + 1)}) {
                const uint8_t kn = atlas.texel_kind[n];
                if ((kn != Atlas::kInner && kn != Atlas::kBorder) || atlas.texel_chunk[n] != atlas.texel_chunk[t]) continue;
                const float d = glm::length(texel_position(atlas, mesh.p, mesh.i, t) - texel_position(atlas, mesh.p, mesh.i, n)) / step;
                (k != kn ? across : k == Atlas::kInner ? inner : border).push_back(d);
            }
        }
    const auto quantile = [](std::vector<float> v, double q) {
        std::sort(v.begin(), v.end());
        return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
    };
    ASSERT_GT(across.size(), 100u);
    // Inside a chunk a step is 1/cos θ of the tilt: at most 1/cos 30° = 1.155 (more only across
    // a crack in the surface, as between the teapot's patches).
    EXPECT_LT(quantile(inner, 0.999), 1.16f);
    EXPECT_LT(quantile(inner, 1.0), 1.5f);
    // Across the chunk's edge: about one step, rarely more than three.
    EXPECT_GT(quantile(across, 0.5), 0.7f);
    EXPECT_LT(quantile(across, 0.5), 1.3f);
    EXPECT_LT(quantile(across, 0.99), 3.f);
    // Inside the border: mostly one step; where two unfolding paths meet, up to the border's width.
    EXPECT_LT(quantile(border, 0.5), 1.3f);
    EXPECT_LT(quantile(border, 0.95), 3.f);
    EXPECT_LT(quantile(border, 0.99), 2.f * float(atlas.border));
    EXPECT_GT(atlas.unfolded_border_texels, 0);
}

INSTANTIATE_TEST_SUITE_P(Shapes, AtlasOnShapes, ::testing::Values(Primitive::Sphere, Primitive::Torus, Primitive::Teapot),
                         [](const auto& info) { return info.param == Primitive::Sphere ? "Sphere" : info.param == Primitive::Torus ? "Torus" : "Teapot"; });

TEST(Atlas, AWiderChunkAngleMakesFewerChunks) {
    const Mesh m = welded(make_primitive(Primitive::Sphere, 40));
    const size_t n15 = build_atlas(m.p, m.i, {256, 4, 15.f}).chunks.size();
    const size_t n30 = build_atlas(m.p, m.i, {256, 4, 30.f}).chunks.size();
    const size_t n60 = build_atlas(m.p, m.i, {256, 4, 60.f}).chunks.size();
    EXPECT_GT(n15, n30);
    EXPECT_GT(n30, n60);
}

TEST(Atlas, ASingleTriangleFillsOneChunk) {
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const Atlas a = build_atlas(p, {0, 1, 2}, {128, 4, 30.f});
    ASSERT_EQ(a.chunks.size(), 1u);
    EXPECT_EQ(a.chunks[0].extent.x, 128 - 8);
    EXPECT_GT(a.fill_ratio, 0.3);  // half of the rectangle
    EXPECT_EQ(a.unfolded_border_texels, 0);
    EXPECT_GT(a.clamped_border_texels, 0);  // nothing beyond the edges: the nearest point of the triangle
}

TEST(Atlas, DegenerateTrianglesAreSkippedAndCounted) {
    std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {NAN, 0, 0}};
    const std::vector<uint32_t> i = {0, 1, 2, /*collinear*/ 0, 1, 3, /*repeated*/ 0, 0, 2, /*non-finite*/ 0, 4, 2, /*out of range*/ 0, 1, 9};
    const Atlas a = build_atlas(p, i, {128, 4, 30.f});
    EXPECT_EQ(a.skipped_degenerate, 4);
    EXPECT_EQ(a.chunks.size(), 1u);
    EXPECT_FALSE(a.warnings.empty());
    EXPECT_THROW(build_atlas(p, {0, 1, 3}, {128, 4, 30.f}), InputError);
}

TEST(Atlas, NonManifoldEdgesAndHolesAreHandled) {
    // Three triangles on one edge (a fin), and a sphere with faces removed.
    const std::vector<vec3> fin = {{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0.2f}, {0.5f, 0, 1}};
    const Atlas a = build_atlas(fin, {0, 1, 2, 1, 0, 3, 0, 1, 4}, {128, 4, 30.f});
    EXPECT_EQ(a.non_manifold_edges, 1);
    for (size_t f = 0; f < 3; ++f) EXPECT_GE(a.face_chunk[f], 0);

    Mesh m = welded(make_primitive(Primitive::Sphere, 32));
    m.i.erase(m.i.begin() + 3 * 200, m.i.begin() + 3 * 260);  // a hole
    const Atlas h = build_atlas(m.p, m.i, kParams);
    EXPECT_GT(h.clamped_border_texels, 0);
    for (size_t t = 0; t < h.texel_kind.size(); ++t) {
        if (h.texel_kind[t] != Atlas::kEmpty) {
            ASSERT_GE(h.texel_face[t], 0);
        }
    }
}

TEST(Atlas, BadSettingsNameTheirKeys) {
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const auto message = [&](AtlasParams ap) {
        try {
            build_atlas(p, {0, 1, 2}, ap);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message({8, 4, 30.f}).find("translucency.atlas_size"), std::string::npos);
    EXPECT_NE(message({128, 4, 95.f}).find("translucency.chunk_angle"), std::string::npos);
    EXPECT_NE(message({128, 40, 30.f}).find("translucency.kernel"), std::string::npos);
    // Too many chunks for the atlas.
    const Mesh m = welded(make_primitive(Primitive::Sphere, 200));
    try {
        build_atlas(m.p, m.i, {32, 7, 5.f});
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("translucency.atlas_size"), std::string::npos);
    }
}

// The illumination map is lit only where no other chunk holds the same surface: a border texel
// copies the inner texel of the chunk that owns its point, which lies within a texel of it on
// the surface. Lit and copied texels split the non-empty ones.
TEST(AtlasStageTest, BorderTexelsCopyTheInnerTexelThatHoldsTheirSurface) {
    const TriMesh s = make_primitive(Primitive::Sphere, 48);
    const PreparedMesh m = prepare_mesh(s.position, s.index, 600);
    const AtlasStage a = make_atlas_stage(m, AtlasParams{256, 4, 30.f});
    ASSERT_FALSE(a.copy.empty());
    EXPECT_EQ(a.lit.size() + a.copy.size(), a.nonempty.size());
    std::vector<int> seen(a.texel_position.size(), 0);
    for (int32_t t : a.lit) ++seen[size_t(t)];
    const float texel = 1.f / a.atlas.scale;  // scene units per texel in a chunk's plane
    for (const ivec2& c : a.copy) {
        ++seen[size_t(c.x)];
        EXPECT_EQ(a.atlas.texel_kind[size_t(c.y)], Atlas::kInner);
        EXPECT_NE(a.atlas.texel_kind[size_t(c.x)], Atlas::kInner);
        EXPECT_EQ(a.atlas.texel_chunk[size_t(c.y)], a.atlas.face_chunk[size_t(a.atlas.texel_face[size_t(c.x)])]) << "the chunk that owns the point";
        // Within a texel in the owning chunk's plane; a chunk tilts by up to 30°.
        EXPECT_LT(glm::length(a.texel_position[size_t(c.x)] - a.texel_position[size_t(c.y)]), 1.2f * texel) << c.x;
        EXPECT_GT(glm::dot(a.texel_normal[size_t(c.x)], a.texel_normal[size_t(c.y)]), 0.99f) << c.x;
    }
    for (int32_t t : a.nonempty) EXPECT_EQ(seen[size_t(t)], 1) << t;
    // On a sphere the copies are most of the borders.
    EXPECT_GT(a.copy.size(), (a.nonempty.size() - a.lit.size()) / 2);
}
