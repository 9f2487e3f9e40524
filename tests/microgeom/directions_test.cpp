// Direction sets (microgeom): Fibonacci lattice, convex-hull triangulation, solid-angle shares,
// locate / nearest queries.
#include "core/microgeom/directions.h"
#include "core/microgeom/stages.h"
#include "support/errors.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <thread>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

double det3(vec3 a, vec3 b, vec3 c) {
    const glm::dvec3 da(a), db(b), dc(c);
    return glm::dot(da, glm::cross(db, dc));
}

// [SECTION] Direction sets
TEST(Directions, BadCountsAreInputErrors) {
    for (int n : {-1, 0, 3, 65537}) test::expect_input_error([n] { make_direction_set(n); }, {"microgeom.directions"});
}

TEST(Directions, SphericalTriangleArea) {
    EXPECT_NEAR(spherical_triangle_area({1, 0, 0}, {0, 1, 0}, {0, 0, 1}), kPi / 2.f, 1e-6f);
    EXPECT_NEAR(spherical_triangle_area({1, 0, 0}, {0, 0, 1}, {0, 1, 0}), kPi / 2.f, 1e-6f);  // orientation-free
    const vec3 a = glm::normalize(vec3(1e-3f, 0, 1)), b = glm::normalize(vec3(0, 1e-3f, 1)), c(0, 0, 1);
    EXPECT_NEAR(spherical_triangle_area(a, b, c), 0.5e-6f, 1e-9f);  // small: the planar area
    // Three points on the equator 120 degrees apart bound a hemisphere (negative denominator).
    EXPECT_NEAR(spherical_triangle_area({1, 0, 0}, {-0.5f, 0.8660254f, 0}, {-0.5f, -0.8660254f, 0}), 2.f * kPi, 1e-5f);
    // A large triangle (> pi) against Girard's theorem (angle excess).
    const vec3 v[3] = {glm::normalize(vec3(1, 0, -0.2f)), glm::normalize(vec3(-0.5f, 0.866f, -0.2f)), glm::normalize(vec3(-0.5f, -0.866f, -0.3f))};
    double excess = -3.14159265358979323846;
    for (int k = 0; k < 3; ++k) {
        const glm::dvec3 a(v[k]), b(v[(k + 1) % 3]), c(v[(k + 2) % 3]);
        const glm::dvec3 tb = glm::normalize(b - glm::dot(a, b) * a), tc = glm::normalize(c - glm::dot(a, c) * a);
        excess += std::acos(glm::dot(tb, tc));
    }
    const float big = spherical_triangle_area(v[0], v[1], v[2]);
    EXPECT_GT(big, kPi);
    EXPECT_NEAR(double(big), excess, 1e-5);
}

void check_triangulation(const DirectionSet& s, int n, bool uniformity) {
    ASSERT_EQ(s.size(), n);
    for (vec3 d : s.d) ASSERT_NEAR(glm::length(d), 1.f, 1e-6f);
    ASSERT_EQ(s.triangles.size(), size_t(2 * n - 4));
    std::map<std::pair<int, int>, int> edges;  // directed edge -> count
    for (const auto& t : s.triangles) {
        ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]);
        for (int k = 0; k < 3; ++k) {
            ASSERT_GE(t[size_t(k)], 0);
            ASSERT_LT(t[size_t(k)], n);
            ++edges[{t[size_t(k)], t[size_t((k + 1) % 3)]}];
        }
        // Counter-clockwise seen from outside.
        EXPECT_GT(det3(s.d[size_t(t[0])], s.d[size_t(t[1])], s.d[size_t(t[2])]), 0.0);
    }
    // Every edge is shared by exactly two triangles, once in each direction.
    EXPECT_EQ(edges.size(), size_t(3 * (2 * n - 4)));
    for (const auto& [e, count] : edges) {
        ASSERT_EQ(count, 1);
        const auto it = edges.find({e.second, e.first});
        ASSERT_TRUE(it != edges.end()) << e.first << "-" << e.second;
        ASSERT_EQ(it->second, 1);
    }
    // Convex hull: no direction lies above a triangle's plane.
    if (n <= 1024)
        for (const auto& t : s.triangles) {
            const glm::dvec3 a(s.d[size_t(t[0])]), b(s.d[size_t(t[1])]), c(s.d[size_t(t[2])]);
            const glm::dvec3 nrm = glm::cross(b - a, c - a);
            for (int i = 0; i < n; ++i) ASSERT_LE(glm::dot(nrm, glm::dvec3(s.d[size_t(i)]) - a), 1e-9);
        }
    // Shares: positive, sum to 4 pi, nearly uniform; fans list the adjacent triangles.
    ASSERT_EQ(s.solid_angle.size(), size_t(n));
    ASSERT_EQ(s.fan.size(), size_t(n));
    double sum = 0.0;
    float lo = 1e9f, hi = 0.f;
    for (int i = 0; i < n; ++i) {
        EXPECT_GT(s.solid_angle[size_t(i)], 0.f);
        sum += double(s.solid_angle[size_t(i)]);
        lo = std::min(lo, s.solid_angle[size_t(i)]);
        hi = std::max(hi, s.solid_angle[size_t(i)]);
        ASSERT_GE(s.fan[size_t(i)].size(), 3u);
        for (int t : s.fan[size_t(i)]) {
            const auto& tri = s.triangles[size_t(t)];
            EXPECT_TRUE(tri[0] == i || tri[1] == i || tri[2] == i);
        }
    }
    EXPECT_NEAR(sum, 4.0 * 3.14159265358979323846, 1e-4);
    if (uniformity) {
        EXPECT_LT(hi / lo, 2.5f) << "min " << lo << " max " << hi;
    }
}

TEST(Directions, FibonacciTriangulationIsAValidHull) {
    for (int n : {4, 5, 6, 7, 16, 100, 1024}) {
        SCOPED_TRACE(n);
        const DirectionSet s = make_direction_set(n);
        check_triangulation(s, n, n >= 16);
        for (int i = 0; i < n; ++i) EXPECT_NEAR(s.d[size_t(i)].z, 1.f - (2.f * float(i) + 1.f) / float(n), 1e-6f);
    }
}

TEST(Directions, LargeSetsAreValidAndDoNotDependOnWhatWasBuiltBefore) {
    // The hull inserts the points in a shuffled order: the shuffle must come from the set's size
    // alone, not from state left by earlier sets or from the thread. A set built first on this
    // thread equals one built on another thread after sets of other sizes.
    const DirectionSet a = make_direction_set(16384);
    check_triangulation(a, 16384, true);
    DirectionSet b;
    std::thread other([&] {
        for (int n : {5, 100, 1023}) ASSERT_EQ(make_direction_set(n).size(), n);
        b = make_direction_set(16384);
    });
    other.join();
    ASSERT_EQ(b.d.size(), a.d.size());
    EXPECT_EQ(a.d, b.d);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.solid_angle, b.solid_angle);
    EXPECT_EQ(a.fan, b.fan);
}

TEST(Directions, LocateFindsTheContainingTriangle) {
    for (int n : {4, 16, 100, 1024}) {
        SCOPED_TRACE(n);
        const DirectionSet s = make_direction_set(n);
        std::mt19937 rng(42);
        std::normal_distribution<float> g;
        const float size = std::sqrt(4.f * kPi / float(n));  // typical spacing
        for (int k = 0; k < 10000; ++k) {
            vec3 w(g(rng), g(rng), g(rng));
            if (glm::length(w) < 1e-3f) continue;
            w = glm::normalize(w);
            vec3 bary;
            const int t = s.locate(w, bary);
            ASSERT_GE(t, 0);
            ASSERT_LT(t, int(s.triangles.size()));
            const auto& tri = s.triangles[size_t(t)];
            const vec3 a = s.d[size_t(tri[0])], b = s.d[size_t(tri[1])], c = s.d[size_t(tri[2])];
            ASSERT_GE(det3(a, b, w), -1e-6);
            ASSERT_GE(det3(b, c, w), -1e-6);
            ASSERT_GE(det3(c, a, w), -1e-6);
            ASSERT_GE(bary.x, 0.f);
            ASSERT_GE(bary.y, 0.f);
            ASSERT_GE(bary.z, 0.f);
            ASSERT_NEAR(bary.x + bary.y + bary.z, 1.f, 1e-5f);
            const vec3 r = glm::normalize(bary.x * a + bary.y * b + bary.z * c);
            ASSERT_LT(glm::length(r - w), 1e-4f * std::max(1.f, size));
            // nearest() agrees with brute force (up to ties).
            const int near = s.nearest(w);
            float best = -2.f;
            for (vec3 d : s.d) best = std::max(best, glm::dot(d, w));
            ASSERT_GE(glm::dot(s.d[size_t(near)], w), best - 1e-6f);
        }
        // At a direction itself: all the weight on that corner.
        for (int i = 0; i < n; ++i) {
            vec3 bary;
            const int t = s.locate(s.d[size_t(i)], bary);
            const auto& tri = s.triangles[size_t(t)];
            float wi = 0.f;
            for (int k = 0; k < 3; ++k)
                if (tri[size_t(k)] == i) wi = bary[k];
            EXPECT_NEAR(wi, 1.f, 1e-4f) << "direction " << i;
            EXPECT_EQ(s.nearest(s.d[size_t(i)]), i);
        }
    }
}
}  // namespace
