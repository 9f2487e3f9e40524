// Mesh preparation (core/translucency/mesh_prep.h): welding, cleaning, non-manifold repair,
// decimation that keeps the surface closed and its triangles well shaped.
#include "core/error.h"
#include "core/mesh.h"
#include "core/translucency/mesh_prep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <utility>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
size_t edge_count(const PreparedMesh& m) {
    std::set<std::pair<uint32_t, uint32_t>> e;
    for (size_t f = 0; f < m.triangle_count(); ++f)
        for (int j = 0; j < 3; ++j) {
            const uint32_t a = m.index[3 * f + size_t(j)], b = m.index[3 * f + size_t((j + 1) % 3)];
            e.insert({std::min(a, b), std::max(a, b)});
        }
    return e.size();
}

double area(const std::vector<vec3>& p, const std::vector<uint32_t>& i) {
    double a = 0.0;
    for (size_t f = 0; f + 2 < i.size(); f += 3) a += 0.5 * glm::length(glm::cross(p[i[f + 1]] - p[i[f]], p[i[f + 2]] - p[i[f]]));
    return a;
}

// Longest edge over the altitude onto it: 1.15 for an equilateral triangle, large for slivers.
double worst_shape(const PreparedMesh& m) {
    double worst = 0.0;
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const vec3 a = m.position[m.index[3 * f]], b = m.position[m.index[3 * f + 1]], c = m.position[m.index[3 * f + 2]];
        const double l = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
        const double twice_area = glm::length(glm::cross(b - a, c - a));
        worst = std::max(worst, l * l / twice_area);
    }
    return worst;
}
}  // namespace

TEST(MeshPrep, AWeldedSphereIsOneClosedSurface) {
    const TriMesh s = make_primitive(Primitive::Sphere, 64);
    const PreparedMesh m = prepare_mesh(s.position, s.index, 0);
    // 64 x 32 cells: the seam column and the two pole rows repeat vertices; each pole row has one
    // zero-area triangle per cell.
    EXPECT_EQ(m.vertex_count(), size_t(64 * 31 + 2));
    EXPECT_EQ(m.removed_triangles, 2 * 64);
    EXPECT_EQ(m.boundary_edges, 0);
    EXPECT_EQ(m.detached_triangles, 0);
    EXPECT_EQ(int64_t(m.vertex_count()) - int64_t(edge_count(m)) + int64_t(m.triangle_count()), 2);  // Euler: a sphere
    EXPECT_NEAR(area(m.position, m.index), area(s.position, s.index), 1e-4);
}

TEST(MeshPrep, DecimationReachesTheTargetKeepsTheSurfaceClosedAndTrianglesWellShaped) {
    const TriMesh s = make_primitive(Primitive::Sphere, 128);
    const PreparedMesh full = prepare_mesh(s.position, s.index, 0);
    for (int target : {2000, 500}) {
        const PreparedMesh m = prepare_mesh(s.position, s.index, target);
        EXPECT_LE(m.vertex_count(), size_t(target)) << target;
        EXPECT_GE(m.vertex_count(), size_t(target) * 95 / 100) << target;
        EXPECT_EQ(m.boundary_edges, 0);
        EXPECT_EQ(int64_t(m.vertex_count()) - int64_t(edge_count(m)) + int64_t(m.triangle_count()), 2);
        EXPECT_NEAR(area(m.position, m.index), area(full.position, full.index), 0.03 * area(full.position, full.index));
        EXPECT_LT(worst_shape(m), 8.0) << target;
        for (const vec3& n : m.normal) EXPECT_NEAR(glm::length(n), 1.f, 1e-4f);
    }
}

TEST(MeshPrep, DegenerateAndDuplicateTrianglesAreRemoved) {
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 0, 0}, {0, 0, 0}, {NAN, 0, 0}};
    const std::vector<uint32_t> i = {0, 1, 2, 1, 3, 2,
                                     /*duplicate*/ 2, 0, 1, /*collinear*/ 0, 1, 4, /*repeated corner*/ 0, 0, 3,
                                     /*welds to 0, 0*/ 5, 0, 1, /*non-finite*/ 0, 6, 1, /*out of range*/ 0, 1, 99};
    const PreparedMesh m = prepare_mesh(p, i, 0);
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_EQ(m.removed_triangles, 6);
    EXPECT_EQ(m.welded_vertices, 1);
    EXPECT_EQ(m.vertex_count(), 4u);
    EXPECT_EQ(m.boundary_edges, 4);
    EXPECT_FALSE(m.warnings.empty());
}

TEST(MeshPrep, NonManifoldEdgesKeepEveryTriangle) {
    // Three triangles on the edge (0, 1).
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0.2f}, {0.5f, 0, 1}};
    const PreparedMesh m = prepare_mesh(p, {0, 1, 2, 1, 0, 3, 0, 1, 4}, 0);
    EXPECT_EQ(m.triangle_count(), 3u);
    EXPECT_EQ(m.detached_triangles, 1);
    EXPECT_NEAR(area(m.position, m.index), area(p, {0, 1, 2, 1, 0, 3, 0, 1, 4}), 1e-6);
}

TEST(MeshPrep, HolesAreCountedAndSurviveDecimation) {
    TriMesh s = make_primitive(Primitive::Sphere, 64);
    s.index.erase(s.index.begin() + 3 * 1000, s.index.begin() + 3 * 1010);
    const PreparedMesh m = prepare_mesh(s.position, s.index, 600);
    EXPECT_GT(m.boundary_edges, 0);
    bool said = false;
    for (const std::string& w : m.warnings) said = said || w.find("boundary edges") != std::string::npos;
    EXPECT_TRUE(said);
    EXPECT_LE(m.vertex_count(), 600u);
}

TEST(MeshPrep, BadInputNamesTheKeyOrTheMesh) {
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    try {
        prepare_mesh(p, {0, 1, 2}, -5);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("translucency.vertices"), std::string::npos);
    }
    EXPECT_THROW(prepare_mesh(p, {0, 0, 1}, 0), InputError);
    EXPECT_THROW(prepare_mesh({}, {}, 0), InputError);
}

// The product of the vertex-to-vertex factors reads rows of vertices within the dipole's reach:
// numbered along a Hilbert curve, those are runs of nearby numbers (cache lines just used).
TEST(MeshPrep, VerticesAreNumberedAlongAHilbertCurveSoSurfaceNeighboursGetNearbyNumbers) {
    // A sphere whose vertices come in a random order (a scan's order may be anything).
    const TriMesh s = make_primitive(Primitive::Sphere, 128);
    std::vector<uint32_t> to(s.position.size());
    std::iota(to.begin(), to.end(), 0u);
    std::shuffle(to.begin(), to.end(), std::mt19937(7));
    std::vector<vec3> shuffled(s.position.size());
    for (size_t i = 0; i < to.size(); ++i) shuffled[to[i]] = s.position[i];
    std::vector<uint32_t> index = s.index;
    for (uint32_t& v : index) v = to[v];
    const PreparedMesh m = prepare_mesh(shuffled, index, 2000);
    const size_t n = m.vertex_count();
    // Positions and normals moved together: on a unit sphere the normal is the position.
    for (size_t i = 0; i < n; ++i) EXPECT_GT(glm::dot(m.normal[i], glm::normalize(m.position[i])), 0.99f) << i;
    // Edges join vertices whose numbers differ by little: the median gap is a few percent of n
    // (about n / 3 for a random numbering).
    std::vector<uint32_t> gap;
    double edge_len = 0.0;
    for (size_t f = 0; f < m.triangle_count(); ++f)
        for (int j = 0; j < 3; ++j) {
            const uint32_t a = m.index[3 * f + size_t(j)], b = m.index[3 * f + size_t((j + 1) % 3)];
            gap.push_back(a > b ? a - b : b - a);
            edge_len += glm::length(m.position[a] - m.position[b]);
        }
    edge_len /= double(gap.size());
    std::nth_element(gap.begin(), gap.begin() + std::ptrdiff_t(gap.size() / 2), gap.end());
    EXPECT_LT(gap[gap.size() / 2], n / 25) << "median gap between the numbers of an edge's ends";
    // Consecutive numbers are close on the surface: on average within two edge lengths.
    double step = 0.0;
    for (size_t i = 1; i < n; ++i) step += glm::length(m.position[i] - m.position[i - 1]);
    EXPECT_LT(step / double(n - 1), 2.0 * edge_len);
}

// Corner normals: on a sphere of 16 segments (neighbouring faces 23° apart) every corner keeps
// its vertex's area-weighted normal; on a box (90° edges) every corner takes its face's normal,
// where the vertex normal leans 8-24° off the 2 x 2 face (the thin sides weigh less).
TEST(MeshPrep, NormalsStaySmoothOnASphereAndSharpAlongABoxsEdges) {
    const TriMesh sp = make_primitive(Primitive::Sphere, 16);
    const PreparedMesh s = prepare_mesh(sp.position, sp.index, 0);
    ASSERT_EQ(s.corner_normal.size(), s.index.size());
    for (size_t k = 0; k < s.index.size(); ++k) EXPECT_LT(glm::length(s.corner_normal[k] - s.normal[s.index[k]]), 1e-5f) << k;

    std::vector<vec3> p;
    for (int k = 0; k < 8; ++k) p.push_back(vec3(k & 1 ? 1.f : -1.f, k & 2 ? 1.f : -1.f, k & 4 ? 0.2f : -0.2f));
    const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    std::vector<uint32_t> idx;
    for (const auto& f : q) idx.insert(idx.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
    const PreparedMesh b = prepare_mesh(p, idx, 0);
    ASSERT_EQ(b.vertex_count(), 8u);
    float leaned = 0.f;
    for (size_t f = 0; f < b.triangle_count(); ++f) {
        const vec3 n = glm::normalize(glm::cross(b.position[b.index[3 * f + 1]] - b.position[b.index[3 * f]],
                                                 b.position[b.index[3 * f + 2]] - b.position[b.index[3 * f]]));
        for (int k = 0; k < 3; ++k) {
            EXPECT_LT(glm::length(b.corner_normal[3 * f + size_t(k)] - n), 1e-6f) << f << " corner " << k;
            if (std::abs(n.z) > 0.5f) leaned = std::max(leaned, std::acos(std::min(1.f, glm::dot(b.normal[b.index[3 * f + size_t(k)]], n))));
        }
    }
    EXPECT_NEAR(leaned * 180.f / 3.14159265f, 24.1f, 0.1f);  // what a light grazing the top face used to meet
}
