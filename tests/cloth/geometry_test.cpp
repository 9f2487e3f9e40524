// Marching cubes and the stitch geometry (core/cloth/marching_cubes.h, stitch.h): closed
// surfaces give watertight, consistently oriented meshes of the right size and topology.
#include "core/cloth/marching_cubes.h"
#include "core/cloth/stitch.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <utility>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
ScalarGrid sample(glm::ivec3 n, vec3 origin, float h, const std::function<float(vec3)>& f) {
    ScalarGrid g;
    g.n = n, g.origin = origin, g.h = h;
    g.v.resize(size_t(n.x) * size_t(n.y) * size_t(n.z));
    for (int k = 0; k < n.z; ++k)
        for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) g.v[g.at(i, j, k)] = f(g.point(i, j, k));
    return g;
}

struct Topology {
    bool oriented_closed = true;  // every directed edge once, and its reverse once
    long euler = 0;               // V − E + F over the vertices the triangles use
    size_t degenerate = 0;        // triangles repeating a vertex
};

Topology topology(const TriMesh& m) {
    Topology t;
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    std::set<uint32_t> used;
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const uint32_t v[3] = {m.index[3 * f], m.index[3 * f + 1], m.index[3 * f + 2]};
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) ++t.degenerate;
        for (int e = 0; e < 3; ++e) ++directed[{v[e], v[(e + 1) % 3]}], used.insert(v[e]);
    }
    for (const auto& [e, n] : directed) {
        auto r = directed.find({e.second, e.first});
        if (n != 1 || r == directed.end() || r->second != 1) t.oriented_closed = false;
    }
    t.euler = long(used.size()) - long(directed.size() / 2) + long(m.triangle_count());
    return t;
}

double volume(const TriMesh& m) {
    double v = 0.0;
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const glm::dvec3 a(m.position[m.index[3 * f]]), b(m.position[m.index[3 * f + 1]]), c(m.position[m.index[3 * f + 2]]);
        v += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    return v;
}
}  // namespace

TEST(MarchingCubes, SphereIsWatertightOutwardAndOfTheRightVolume) {
    const float R = 0.8f;
    const ScalarGrid g = sample({41, 41, 41}, vec3(-1.f), 0.05f, [&](vec3 p) { return glm::length(p) - R; });
    const TriMesh m = marching_cubes(g);
    ASSERT_GT(m.triangle_count(), 1000u);
    const Topology t = topology(m);
    EXPECT_TRUE(t.oriented_closed);
    EXPECT_EQ(t.euler, 2);
    EXPECT_NEAR(volume(m), 4.0 / 3.0 * M_PI * R * R * R, 0.01 * 4.0 / 3.0 * M_PI * R * R * R);  // > 0: outward
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        EXPECT_NEAR(glm::length(m.position[v]), R, 0.01f);
        EXPECT_GT(glm::dot(m.normal[v], m.position[v]), 0.99f * R);
    }
}

TEST(MarchingCubes, TorusHasGenusOne) {
    const ScalarGrid g = sample({48, 48, 20}, vec3(-1.2f, -1.2f, -0.5f), 0.05f, [](vec3 p) {
        const float q = std::sqrt(p.x * p.x + p.y * p.y) - 0.8f;
        return std::sqrt(q * q + p.z * p.z) - 0.3f;
    });
    const Topology t = topology(marching_cubes(g));
    EXPECT_TRUE(t.oriented_closed);
    EXPECT_EQ(t.euler, 0);
}

// Random values make many faces ambiguous (alternating corners) and many cubes of every
// configuration: the face decider must agree between neighbours for the mesh to close.
TEST(MarchingCubes, RandomFieldsWithAmbiguousFacesStayWatertight) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (int trial = 0; trial < 4; ++trial) {
        ScalarGrid g = sample({18, 17, 16}, vec3(0.f), 1.f, [&](vec3) { return u(rng); });
        for (int k = 0; k < g.n.z; ++k)
            for (int j = 0; j < g.n.y; ++j)
                for (int i = 0; i < g.n.x; ++i)
                    if (i == 0 || j == 0 || k == 0 || i == g.n.x - 1 || j == g.n.y - 1 || k == g.n.z - 1) g.v[g.at(i, j, k)] = 1.f;
        const TriMesh m = marching_cubes(g);
        ASSERT_GT(m.triangle_count(), 5000u);
        const Topology t = topology(m);
        EXPECT_TRUE(t.oriented_closed) << "trial " << trial;
        EXPECT_EQ(t.euler % 2, 0) << "trial " << trial;  // closed orientable surfaces: 2 − 2g per component
        EXPECT_GT(volume(m), 0.0);
    }
}

TEST(MarchingCubes, AFieldWithNoCrossingGivesNoTriangles) {
    EXPECT_EQ(marching_cubes(sample({5, 5, 5}, vec3(0.f), 1.f, [](vec3) { return 1.f; })).triangle_count(), 0u);
    EXPECT_EQ(marching_cubes(sample({5, 5, 5}, vec3(0.f), 1.f, [](vec3) { return -1.f; })).triangle_count(), 0u);
    EXPECT_EQ(marching_cubes(ScalarGrid{}).triangle_count(), 0u);
}

TEST(Stitches, EveryStitchIsAWatertightMeshOfYarnsOverItsTile) {
    for (const std::string& name : stitch_names()) {
        StitchParams p;
        p.stitch = name;
        const StitchPattern pat = make_stitch(p);
        ASSERT_FALSE(pat.yarns.empty()) << name;
        const StitchMesh s = build_stitch_mesh(pat, 24);
        ASSERT_GT(s.mesh.triangle_count(), 2000u) << name;
        EXPECT_TRUE(topology(s.mesh).oriented_closed) << name;
        EXPECT_GT(volume(s.mesh), 0.0) << name;
        // The surface stays within the yarns' reach of their skeletons in z.
        for (const vec3& x : s.mesh.position) {
            ASSERT_GE(x.z, s.lo.z - 0.1f) << name;
            ASSERT_LE(x.z, s.hi.z + 0.1f) << name;
        }
        // The centre tile is covered: some surface over most of its area (seen from above).
        const int G = 8;
        int covered = 0;
        std::vector<bool> hit(G * G, false);
        for (const vec3& x : s.mesh.position)
            if (x.x >= 0.f && x.y >= 0.f && x.x < s.tile.x && x.y < s.tile.y) hit[size_t(int(x.y / s.tile.y * G) * G + int(x.x / s.tile.x * G))] = true;
        for (bool b : hit) covered += b;
        EXPECT_GT(covered, G * G / 2) << name;
    }
}

TEST(Stitches, TwoColourLoopsCarryBothColoursAndWeavesTheirThreads) {
    StitchParams p;
    p.stitch = "loops2";
    StitchMesh s = build_stitch_mesh(make_stitch(p), 24);
    size_t a = 0, b = 0;
    for (const vec3& c : s.color) a += c == p.color_a, b += c == p.color_b;
    EXPECT_GT(a, s.color.size() / 4);
    EXPECT_GT(b, s.color.size() / 4);
    EXPECT_EQ(a + b, s.color.size());
    p.stitch = "weave";
    s = build_stitch_mesh(make_stitch(p), 24);
    a = b = 0;
    for (const vec3& c : s.color) a += c == p.color_a, b += c == p.color_b;
    EXPECT_GT(a, s.color.size() / 4);  // warp
    EXPECT_GT(b, s.color.size() / 4);  // weft
}

TEST(Stitches, BadParametersNameTheirKey) {
    auto err = [](StitchParams p, int cells = 24) {
        try {
            build_stitch_mesh(make_stitch(p), cells);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    StitchParams p;
    p.stitch = "crochet";
    EXPECT_NE(err(p).find("cloth.stitch: \"crochet\""), std::string::npos);
    p = StitchParams{};
    p.yarn_radius = 0.f;
    EXPECT_NE(err(p).find("cloth.yarn_radius"), std::string::npos);
    p = StitchParams{};
    p.loop_height = 10.f;
    EXPECT_NE(err(p).find("cloth.loop_height"), std::string::npos);
    EXPECT_NE(err(StitchParams{}, 4).find("cloth.stitch_resolution"), std::string::npos);
}
