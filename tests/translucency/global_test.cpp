// The global response (core/translucency/global.h): the tabulated R_d, the vertex-to-vertex
// factors against R_d(r_ij) A_j / 3, the threshold, the parallel product against Eigen's, the
// dual-basis projection, units, bad settings.
#include "core/error.h"
#include "core/mesh.h"
#include "core/translucency/atlas.h"
#include "core/translucency/global.h"
#include "core/translucency/mesh_prep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
PreparedMesh sphere(int resolution) {
    const TriMesh s = make_primitive(Primitive::Sphere, resolution);
    return prepare_mesh(s.position, s.index, 0);
}
}  // namespace

TEST(RdTable, AgreesWithTheDipoleWithin1e4) {
    for (const char* name : {"marble", "skin1", "ketchup", "spectralon"}) {
        const Dipole d(measured_material(name).medium);
        const RdTable table(d, 50.0);
        const dvec3 R0 = d.Rd(0.0);
        for (double r = 0.0; r <= 50.0; r += 0.0137) {
            const vec3 t = table.at_r2(float(r * r));
            const dvec3 e = d.Rd(r);
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(t[c], e[c], 1e-4 * e[c] + 1e-7 * R0[c]) << name << " r=" << r << " c=" << c;
        }
        EXPECT_EQ(table.at_r2(51.f * 51.f), vec3(0.f));
    }
}

TEST(VertexFactors, EqualRdAtTheVertexDistanceTimesAThirdOfTheVertexArea) {
    const PreparedMesh m = sphere(16);
    const Dipole d(measured_material("skin1").medium);
    const double mm = 10.0;  // a sphere of radius 10 mm
    const VertexFactors F = build_vertex_factors(m.position, m.index, d, {mm, 0.f, false});
    const int n = int(m.vertex_count());
    ASSERT_EQ(F.count(), size_t(n) * size_t(n));  // every factor is positive
    // Vertex areas: independent sum over triangles.
    std::vector<double> A(size_t(n), 0.0);
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const vec3 a = m.position[m.index[3 * f]], b = m.position[m.index[3 * f + 1]], c = m.position[m.index[3 * f + 2]];
        for (int j = 0; j < 3; ++j) A[m.index[3 * f + size_t(j)]] += 0.5 * glm::length(glm::cross(b - a, c - a)) * mm * mm;
    }
    for (int i = 0; i < n; ++i)
        for (int k = F.outer[size_t(i)]; k < F.outer[size_t(i) + 1]; ++k) {
            const int j = F.inner[size_t(k)];
            const dvec3 expect = d.Rd(glm::length(m.position[size_t(i)] - m.position[size_t(j)]) * mm) * (A[size_t(j)] / 3.0);
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(F.value[size_t(c)][size_t(k)], expect[c], 2e-4 * expect[c] + 1e-12) << i << "," << j;
        }
    EXPECT_EQ(F.bytes(), size_t(n + 1) * 4 + F.count() * 16);
}

TEST(VertexFactors, TheThresholdKeepsExactlyTheFactorsAboveIt) {
    const PreparedMesh m = sphere(24);
    const Dipole d(measured_material("marble").medium);
    const VertexFactors all = build_vertex_factors(m.position, m.index, d, {20.0, 0.f, false});
    std::vector<float> largest;
    for (size_t k = 0; k < all.count(); ++k) largest.push_back(std::max({all.value[0][k], all.value[1][k], all.value[2][k]}));
    size_t prev = all.count();
    for (float thr : {1e-6f, 1e-5f, 1e-4f, 1e-3f}) {
        const VertexFactors F = build_vertex_factors(m.position, m.index, d, {20.0, thr, false});
        const size_t expect = size_t(std::count_if(largest.begin(), largest.end(), [&](float v) { return v >= thr; }));
        EXPECT_NEAR(double(F.count()), double(expect), 1e-3 * double(expect) + 2) << thr;  // table vs exact at the edge
        EXPECT_LE(F.count(), prev);
        prev = F.count();
    }
    // A threshold above every factor drops them all; the product is then zero, not NaN.
    const VertexFactors none = build_vertex_factors(m.position, m.index, d, {20.0, 1e9f, false});
    EXPECT_EQ(none.count(), 0u);
    for (const vec3& b : none.multiply(std::vector<vec3>(m.vertex_count(), vec3(1.f)))) EXPECT_EQ(b, vec3(0.f));
}

TEST(VertexFactors, ZeroDiagonalWhenBlending) {
    const PreparedMesh m = sphere(16);
    const VertexFactors F = build_vertex_factors(m.position, m.index, Dipole(measured_material("marble").medium), {5.0, 0.f, true});
    for (int i = 0; i < F.n; ++i)
        for (int k = F.outer[size_t(i)]; k < F.outer[size_t(i) + 1]; ++k) ASSERT_NE(F.inner[size_t(k)], i);
    EXPECT_EQ(F.count(), size_t(F.n) * size_t(F.n - 1));
}

TEST(VertexFactors, ParallelProductEqualsEigensProduct) {
    const PreparedMesh m = sphere(32);
    const VertexFactors F = build_vertex_factors(m.position, m.index, Dipole(measured_material("skin2").medium), {15.0, 1e-6f, true});
    std::vector<vec3> E(m.vertex_count());
    for (size_t i = 0; i < E.size(); ++i) E[i] = vec3(float(i % 7), float(i % 3) + 0.5f, float((i * 13) % 11)) * 0.1f;
    const std::vector<vec3> B = F.multiply(E);
    for (int c = 0; c < 3; ++c) {
        Eigen::VectorXf e(F.n);
        for (int i = 0; i < F.n; ++i) e[i] = E[size_t(i)][c];
        const Eigen::VectorXf b = F.channel(c) * e;
        for (int i = 0; i < F.n; ++i) ASSERT_NEAR(B[size_t(i)][c], b[i], 1e-5f * std::max(1.f, std::abs(b[i])));
    }
}

TEST(VertexFactors, MillimetresPerUnitScaleDistancesAndAreas) {
    const PreparedMesh m = sphere(12);
    const Dipole d(measured_material("potato").medium);
    const VertexFactors a = build_vertex_factors(m.position, m.index, d, {3.0, 0.f, false});
    const VertexFactors b = build_vertex_factors(m.position, m.index, d, {6.0, 0.f, false});
    // Factor (0, j): R_d(6 r) 4 A / 3 against R_d(3 r) A / 3.
    for (int k = a.outer[0]; k < a.outer[1]; ++k) {
        const int j = a.inner[size_t(k)];
        const double r = glm::length(m.position[0] - m.position[size_t(j)]);
        const double ratio = d.Rd(6.0 * r, 0) * 4.0 / d.Rd(3.0 * r, 0);
        EXPECT_NEAR(b.value[0][size_t(k)] / a.value[0][size_t(k)], ratio, 3e-4 * ratio);
    }
}

TEST(DualBasis, ConstantIrradianceProjectsToTheSameValueAtEveryVertex) {
    const PreparedMesh m = sphere(20);
    const Atlas atlas = build_atlas(m.position, m.index, {512, 4, 30.f});
    const double mm = 10.0;
    const std::vector<float> A = vertex_areas(m.position, m.index, mm);
    const std::vector<vec3> E = project_to_vertices(atlas, m.index, std::vector<vec3>(atlas.texel_kind.size(), vec3(2.f, 1.f, 0.5f)), A, mm);
    std::vector<float> err;
    for (const vec3& e : E) err.push_back(std::abs(e.x / 2.f - 1.f));
    std::sort(err.begin(), err.end());
    // Texel quadrature of (4 λ − 1) over triangles of ~300 texels each.
    EXPECT_LT(err[err.size() / 2], 0.02f);
    EXPECT_LT(err[err.size() * 95 / 100], 0.06f);
    for (const vec3& e : E) EXPECT_NEAR(e.y / e.x, 0.5f, 1e-5f);
}

TEST(VertexFactors, BadSettingsNameTheirKeys) {
    const PreparedMesh m = sphere(8);
    const Dipole d(measured_material("marble").medium);
    const auto message = [&](FactorParams p) {
        try {
            build_vertex_factors(m.position, m.index, d, p);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message({0.0, 0.f, false}).find("translucency.mm_per_unit"), std::string::npos);
    EXPECT_NE(message({-1.0, 0.f, false}).find("translucency.mm_per_unit"), std::string::npos);
    EXPECT_NE(message({1.0, -1.f, false}).find("translucency.threshold"), std::string::npos);
    EXPECT_NE(message({1.0, NAN, false}).find("translucency.threshold"), std::string::npos);
}
