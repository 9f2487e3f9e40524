// The global response (core/translucency/global.h): the tabulated R_d, the vertex-to-vertex
// factors against R_d(r_ij) A_j / 3 and the interpolation correction, the threshold, the parallel
// product against Eigen's, the projection, units, bad settings.
#include "core/error.h"
#include "core/mesh.h"
#include "core/translucency/atlas.h"
#include "core/translucency/global.h"
#include "core/translucency/mesh_prep.h"

#include "shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

using namespace mesolab;
using namespace mesolab::translucency;

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

TEST(HalfFloat, EveryHalfSurvivesTheRoundTripAndFloatsRoundToTheNearestHalf) {
    for (uint32_t h = 0; h < 0x10000u; ++h) {
        const float v = half_value(uint16_t(h));
        if (std::isnan(v)) continue;
        ASSERT_EQ(half_bits(v), uint16_t(h)) << h;
    }
    EXPECT_EQ(half_value(half_bits(1.f)), 1.f);
    EXPECT_EQ(half_value(half_bits(65504.f)), 65504.f);
    EXPECT_TRUE(std::isinf(half_value(half_bits(1e6f))));
    EXPECT_TRUE(std::isnan(half_value(half_bits(NAN))));
    EXPECT_EQ(half_value(half_bits(1e-9f)), 0.f);
    // Random floats over the half's range: the nearest of the two neighbouring halves.
    uint32_t state = 12345u;
    for (int k = 0; k < 200000; ++k) {
        state = state * 1664525u + 1013904223u;
        const float f = std::ldexp(float(state >> 8) / 16777216.f + 0.5f, int(state % 40u) - 25);
        const uint16_t h = half_bits(f);
        const float v = half_value(h), up = half_value(uint16_t(h + 1)), down = h > 0 ? half_value(uint16_t(h - 1)) : 0.f;
        ASSERT_LE(std::abs(f - v), std::abs(f - up)) << f;
        ASSERT_LE(std::abs(f - v), std::abs(f - down)) << f;
    }
}

TEST(VertexFactors, EqualRdAtTheVertexDistanceTimesAThirdOfTheVertexArea) {
    const PreparedMesh m = test::prepared_sphere(16);
    const Dipole d(measured_material("skin1").medium);
    const double mm = 10.0;  // a sphere of radius 10 mm
    FactorParams p{mm, 0.f, false};
    p.interpolation_correction = false;  // the paper's factors
    const VertexFactors F = build_vertex_factors(m.position, m.index, d, p);
    const int n = int(m.vertex_count());
    ASSERT_EQ(F.count(), size_t(n) * size_t(n));  // every factor is positive
    ASSERT_EQ(F.pairs(), size_t(n) * size_t(n + 1) / 2);
    // Vertex areas: independent sum over triangles.
    std::vector<double> A(size_t(n), 0.0);
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const vec3 a = m.position[m.index[3 * f]], b = m.position[m.index[3 * f + 1]], c = m.position[m.index[3 * f + 2]];
        for (int j = 0; j < 3; ++j) A[m.index[3 * f + size_t(j)]] += 0.5 * glm::length(glm::cross(b - a, c - a)) * mm * mm;
    }
    // Half floats (≤ 4.9e-4) on the table (1e-4).
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const dvec3 expect = d.Rd(glm::length(m.position[size_t(i)] - m.position[size_t(j)]) * mm) * (A[size_t(j)] / 3.0);
            const vec3 got = F.factor(i, j);
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(got[c], expect[c], 6e-4 * expect[c] + 1e-12) << i << "," << j;
        }
    EXPECT_EQ(F.bytes(), size_t(n + 1) * 4 + F.pairs() * 8);
}

// R̂_ij = R_d(r_ij) / (ρ(q_i L) ρ(q_j L)), L = ∇²R_d / R_d, 1 / ρ(x) = tanh(b) / b with
// b = sqrt(3x), q_i the area-weighted Σ e² / 48 around i. Recomputed here from the triangles and
// Dipole::laplacian_ratio. The diagonal and the pairs that share an edge, whose hats overlap,
// are the hat-pair means (tested below).
TEST(VertexFactors, InterpolationCorrectionShrinksRdByTheSmoothingOfBothSides) {
    const PreparedMesh m = test::prepared_sphere(16);
    const Dipole d(measured_material("skin1").medium);
    const double mm = 10.0;
    const VertexFactors F = build_vertex_factors(m.position, m.index, d, {mm, 0.f, false});
    const int n = int(m.vertex_count());
    std::vector<double> A(size_t(n), 0.0), q(size_t(n), 0.0);
    for (size_t f = 0; f < m.triangle_count(); ++f) {
        const dvec3 a = dvec3(m.position[m.index[3 * f]]) * mm, b = dvec3(m.position[m.index[3 * f + 1]]) * mm, c = dvec3(m.position[m.index[3 * f + 2]]) * mm;
        const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
        const double e2 = glm::dot(b - a, b - a) + glm::dot(c - b, c - b) + glm::dot(a - c, a - c);
        for (int j = 0; j < 3; ++j) A[m.index[3 * f + size_t(j)]] += area, q[m.index[3 * f + size_t(j)]] += area * e2 / 48.0;
    }
    std::set<std::pair<int, int>> edges;
    for (size_t f = 0; f < m.triangle_count(); ++f)
        for (int k = 0; k < 3; ++k) {
            const int a = int(m.index[3 * f + size_t(k)]), b = int(m.index[3 * f + size_t((k + 1) % 3)]);
            edges.insert({a, b}), edges.insert({b, a});
        }
    const auto inv_rho = [](double x) {
        const double b = std::sqrt(3.0 * std::max(0.0, x));
        return b < 1e-6 ? 1.0 : std::tanh(b) / b;
    };
    int shrunk = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            if (i == j || edges.count({i, j})) continue;
            const double r = glm::length(m.position[size_t(i)] - m.position[size_t(j)]) * mm;
            const dvec3 L = d.laplacian_ratio(r);
            dvec3 expect = d.Rd(r) * (A[size_t(j)] / 3.0);
            for (int c = 0; c < 3; ++c) expect[c] *= inv_rho(q[size_t(i)] / A[size_t(i)] * L[c]) * inv_rho(q[size_t(j)] / A[size_t(j)] * L[c]);
            const vec3 got = F.factor(i, j);
            // Half floats (4.9e-4; normal down to 2e-9 R_d(0)), the tables of R_d (1e-4) and of
            // ∇²R_d / R_d (linear between samples).
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(got[c], expect[c], 2e-3 * expect[c] + 4e-9 * d.Rd(0.0, c) * A[size_t(j)] / 3.0) << i << "," << j << " channel " << c;
            if (got.z < 0.9f * float(d.Rd(r, 2) * A[size_t(j)] / 3.0)) ++shrunk;
        }
    EXPECT_GT(shrunk, n);  // blue's R_d is convex enough to lose over 10% on many pairs
}

namespace {
// A regular icosahedron (12 vertices, 20 equilateral triangles), circumradius 1.
PreparedMesh icosahedron() {
    const float t = (1.f + std::sqrt(5.f)) / 2.f;
    std::vector<vec3> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                           {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (vec3& v : p) v = glm::normalize(v);
    const std::vector<uint32_t> f = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                                     3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    return prepare_mesh(p, f, 0);
}
}  // namespace

// Without blending the diagonal and the pairs that share an edge are R̄_ij, the mean of R_d over
// both hats (9 / (A_i A_j) ∫∫ φ_i φ_j R_d). Triangles far larger than the diffusion length: R_d
// lands within its hat, so F_ii = R̄_ii A_i / 3 → R_total (3 / A_i) ∫ φ_i² = R_total / 2 (∫ φ_i² =
// A_i / 6), an edge's F_ij → R_total (3 / A_i)(A_T + A_T') / 12 = R_total / 10 on the icosahedron
// (five equal triangles around a vertex), and every column keeps R_total (Σ_i F_ij A_i / 3 =
// R_total A_j / 3): the global part alone conserves energy. Triangles far smaller than z_r: R̄ is
// R_d at the vertex distance.
TEST(VertexFactors, WithoutBlendingOverlappingHatsAverageRdOverBothSupports) {
    const PreparedMesh ico = icosahedron();
    const Dipole d(measured_material("skin1").medium);
    const dvec3 Rt = d.total_reflectance();
    // Edges of 1051 mm: 8 x 8 sub-triangles of 131 mm, each kept as a disk of 36 mm radius that
    // holds R_d but for its tail beyond (below 1e-4 of R_total in skin1); the centroid rule
    // misses 1 / (3 n²) of ∫ φ_i² (0.52% for n = 8: measured 0.9948 R_total / 2) and adds half
    // that to ∫ φ_i φ_j (measured 1.005 R_total / 10); the columns hold R_total to 1e-4.
    const double mm = 1000.0;
    const VertexFactors F = build_vertex_factors(ico.position, ico.index, d, {mm, 0.f, false});
    ASSERT_EQ(F.n, 12);
    for (int i = 0; i < F.n; ++i) {
        vec3 column(0.f);
        for (int j = 0; j < F.n; ++j) column += F.factor(j, i) * (F.vertex_area[size_t(j)] / F.vertex_area[size_t(i)]);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(F.factor(i, i)[c], Rt[c] / 2.0, 5e-3 * Rt[c]) << i << " channel " << c;
            EXPECT_NEAR(column[c], Rt[c], 5e-3 * Rt[c]) << i << " channel " << c;
        }
    }
    std::set<std::pair<int, int>> edges;
    for (size_t f = 0; f < ico.triangle_count(); ++f)
        for (int k = 0; k < 3; ++k) edges.insert({int(ico.index[3 * f + size_t(k)]), int(ico.index[3 * f + size_t((k + 1) % 3)])});
    for (const auto& [i, j] : edges)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(F.factor(i, j)[c], Rt[c] / 10.0, 5e-3 * Rt[c]) << i << "," << j << " channel " << c;

    // A sphere of 10 µm: the hats are 5e-3 of skin1's smallest z_r across, R_d is flat over them
    // to (5e-3)², below the half floats' 4.9e-4 and the table's 1e-4.
    const PreparedMesh m = test::prepared_sphere(12);
    const double tiny = 0.01;
    const VertexFactors S = build_vertex_factors(m.position, m.index, d, {tiny, 0.f, false});
    for (int i = 0; i < S.n; ++i)
        for (int j = 0; j < S.n; ++j) {
            const dvec3 expect = d.Rd(glm::length(m.position[size_t(i)] - m.position[size_t(j)]) * tiny) * (double(S.vertex_area[size_t(j)]) / 3.0);
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(S.factor(i, j)[c], expect[c], 1e-3 * expect[c]) << i << "," << j << " channel " << c;
        }
}

TEST(VertexFactors, TheThresholdKeepsExactlyThePairsWithAFactorAboveIt) {
    const PreparedMesh m = test::prepared_sphere(24);
    const Dipole d(measured_material("marble").medium);
    const VertexFactors all = build_vertex_factors(m.position, m.index, d, {20.0, 0.f, false});
    auto largest = [](vec3 v) { return std::max({v.x, v.y, v.z}); };
    // Per kept pair: the mean of F_ij and F_ji, and whether it is on the diagonal.
    std::vector<std::pair<float, bool>> pairs;
    for (int i = 0; i < all.n; ++i)
        for (int k = all.outer[size_t(i)]; k < all.outer[size_t(i) + 1]; ++k) {
            const int j = all.column(size_t(k));
            pairs.emplace_back(0.5f * (largest(all.factor(i, j)) + largest(all.factor(j, i))), i == j);
        }
    size_t prev = all.count();
    for (float thr : {1e-6f, 1e-5f, 1e-4f, 1e-3f}) {
        const VertexFactors F = build_vertex_factors(m.position, m.index, d, {20.0, thr, false});
        size_t expect = 0;
        for (const auto& [v, diag] : pairs)
            if (v >= thr) expect += diag ? 1 : 2;
        EXPECT_NEAR(double(F.count()), double(expect), 2e-3 * double(expect) + 4) << thr;  // halves and table vs exact at the edge
        EXPECT_LE(F.count(), prev);
        prev = F.count();
        for (int i = 0; i < F.n; i += 7)
            for (int j = 0; j < F.n; j += 5) {
                const float v = 0.5f * (largest(all.factor(i, j)) + largest(all.factor(j, i)));
                if (v > 1.01f * thr) {
                    ASSERT_NE(F.factor(i, j), vec3(0.f)) << thr << " " << i << "," << j;
                }
                if (v < 0.99f * thr) {
                    ASSERT_EQ(F.factor(i, j), vec3(0.f)) << thr << " " << i << "," << j;
                }
            }
    }
    // A threshold above every factor drops them all; the product is then zero, not NaN.
    const VertexFactors none = build_vertex_factors(m.position, m.index, d, {20.0, 1e9f, false});
    EXPECT_EQ(none.count(), 0u);
    for (const vec3& b : none.multiply(std::vector<vec3>(m.vertex_count(), vec3(1.f)))) EXPECT_EQ(b, vec3(0.f));
}

TEST(VertexFactors, ZeroDiagonalWhenBlending) {
    const PreparedMesh m = test::prepared_sphere(16);
    const VertexFactors F = build_vertex_factors(m.position, m.index, Dipole(measured_material("marble").medium), {5.0, 0.f, true});
    for (int i = 0; i < F.n; ++i) {
        for (int k = F.outer[size_t(i)]; k < F.outer[size_t(i) + 1]; ++k) ASSERT_GT(F.column(size_t(k)), i);
        ASSERT_EQ(F.factor(i, i), vec3(0.f));
    }
    EXPECT_EQ(F.diagonal, 0u);
    EXPECT_EQ(F.count(), size_t(F.n) * size_t(F.n - 1));
}

// The symmetric half-float product (F16C and portable) against Eigen's product of the decoded
// matrices, and the complete rows the GPU reads against both; also with the columns' high bits.
TEST(VertexFactors, SymmetricProductEqualsEigensAndTheCompleteRows) {
    const PreparedMesh m = test::prepared_sphere(32);
    for (bool blend : {true, false})
        for (bool wide : {false, true}) {
            const VertexFactors F =
                build_vertex_factors(m.position, m.index, Dipole(measured_material("skin2").medium), {15.0, 1e-6f, blend, wide});
            ASSERT_EQ(F.col_hi.size(), wide ? F.pairs() : 0u);
            std::vector<vec3> E(m.vertex_count());
            for (size_t i = 0; i < E.size(); ++i) E[i] = vec3(float(i % 7), float(i % 3) + 0.5f, float((i * 13) % 11)) * 0.1f;
            const std::vector<vec3> B = F.multiply(E), Bp = F.multiply(E, false);
            const DirectedFactors D = expand_directed(F);
            ASSERT_EQ(D.entry.size(), F.count());
            const std::vector<vec3> Bd = multiply_directed(F, D, E);
            for (int c = 0; c < 3; ++c) {
                Eigen::VectorXf e(F.n);
                for (int i = 0; i < F.n; ++i) e[i] = E[size_t(i)][c] * F.vertex_area[size_t(i)] / 3.f;
                const Eigen::SparseMatrix<float, Eigen::RowMajor> U = F.upper(c);
                const Eigen::VectorXf b = U.selfadjointView<Eigen::Upper>() * e;
                for (int i = 0; i < F.n; ++i) {
                    ASSERT_NEAR(B[size_t(i)][c], b[i], 1e-5f * std::max(1.f, std::abs(b[i]))) << i << " blend " << blend << " wide " << wide;
                    ASSERT_NEAR(Bd[size_t(i)][c], b[i], 1e-5f * std::max(1.f, std::abs(b[i]))) << i;
                    ASSERT_NEAR(Bp[size_t(i)][c], b[i], 1e-5f * std::max(1.f, std::abs(b[i]))) << i;
                }
            }
        }
}

TEST(VertexFactors, MillimetresPerUnitScaleDistancesAndAreas) {
    const PreparedMesh m = test::prepared_sphere(12);
    const Dipole d(measured_material("potato").medium);
    FactorParams pa{3.0, 0.f, false}, pb{6.0, 0.f, false};
    pa.interpolation_correction = pb.interpolation_correction = false;
    const VertexFactors a = build_vertex_factors(m.position, m.index, d, pa);
    const VertexFactors b = build_vertex_factors(m.position, m.index, d, pb);
    // Factor (0, j): R_d(6 r) 4 A / 3 against R_d(3 r) A / 3.
    for (int j = 0; j < a.n; ++j) {
        const double r = glm::length(m.position[0] - m.position[size_t(j)]);
        const double ratio = d.Rd(6.0 * r, 0) * 4.0 / d.Rd(3.0 * r, 0);
        EXPECT_NEAR(b.factor(0, j)[0] / a.factor(0, j)[0], ratio, 1.2e-3 * ratio);
    }
}

TEST(Projection, ConstantIrradianceProjectsToTheSameValueAtEveryVertexAndPowerIsKept) {
    const PreparedMesh m = test::prepared_sphere(20);
    const Atlas atlas = build_atlas(m.position, m.index, {512, 4, 30.f});
    const double mm = 10.0;
    const std::vector<float> A = vertex_areas(m.position, m.index, mm);
    const std::vector<vec3> E = project_to_vertices(atlas, m.index, std::vector<vec3>(atlas.texel_kind.size(), vec3(2.f, 1.f, 0.5f)), A, mm);
    std::vector<float> err;
    for (const vec3& e : E) err.push_back(std::abs(e.x / 2.f - 1.f));
    std::sort(err.begin(), err.end());
    // Texel quadrature of λ over triangles of ~300 texels each.
    EXPECT_LT(err[err.size() / 2], 0.02f);
    EXPECT_LT(err[err.size() * 95 / 100], 0.06f);
    for (const vec3& e : E) {
        EXPECT_NEAR(e.y / e.x, 0.5f, 1e-5f);
        EXPECT_GT(e.x, 0.f);
    }
    // Any irradiance, a sharp spot included: Σ_j E_j A_j / 3 = Σ_t E_t A_t, and never negative.
    std::vector<vec3> spot(atlas.texel_kind.size(), vec3(0.f));
    double power = 0.0;
    for (size_t t = 0; t < spot.size(); ++t)
        if (atlas.texel_kind[t] == Atlas::kInner && texel_position(atlas, m.position, m.index, t).z > 0.7f) {
            spot[t] = vec3(1.f);
            power += double(atlas.texel_area[t]) * mm * mm;
        }
    const std::vector<vec3> Es = project_to_vertices(atlas, m.index, spot, A, mm);
    double projected = 0.0;
    for (size_t j = 0; j < Es.size(); ++j) {
        EXPECT_GE(Es[j].x, 0.f) << j;
        projected += double(Es[j].x) * double(A[j]) / 3.0;
    }
    EXPECT_NEAR(projected, power, 1e-5 * power);
}

TEST(VertexFactors, BadSettingsNameTheirKeys) {
    const PreparedMesh m = test::prepared_sphere(8);
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
