// The tables the GPU passes read (core/translucency/gpu_layout.h), checked without GL: padded factor
// rows give the product of the factors, pieces cover every row within a buffer texture's size at
// aligned offsets, and the shown texels name each texel's source, triangle and barycentrics.
#include "core/mesh.h"
#include "core/translucency/dipole.h"
#include "core/translucency/gpu_layout.h"
#include "core/translucency/mesh_prep.h"

#include "shapes.h"

#include <gtest/gtest.h>
#include <algorithm>
#include <cstring>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
VertexFactors factors(const PreparedMesh& m, bool wide) {
    return build_vertex_factors(m.position, m.index, Dipole(measured_material("skin2").medium), {15.0, 1e-6f, true, wide});
}
}  // namespace

TEST(GpuLayout, PaddedRowsStartOnTheQuantumAndGiveTheProductOfTheFactors) {
    const PreparedMesh m = test::prepared_sphere(24);
    for (bool wide : {false, true}) {
        SCOPED_TRACE(wide);
        const VertexFactors F = factors(m, wide);
        const PaddedFactors P = pad_factor_rows(F);
        ASSERT_EQ(P.outer.size(), size_t(F.n) + 1);
        EXPECT_EQ(P.wide(), wide);
        const DirectedFactors D = expand_directed(F);
        size_t padding = 0;
        for (int i = 0; i < F.n; ++i) {
            const int b = P.outer[size_t(i)], e = P.outer[size_t(i) + 1];
            EXPECT_EQ(b % PaddedFactors::kRowQuantum, 0) << "row " << i;
            const int n = D.outer[size_t(i) + 1] - D.outer[size_t(i)];
            ASSERT_EQ(e - b, (n + PaddedFactors::kRowQuantum - 1) / PaddedFactors::kRowQuantum * PaddedFactors::kRowQuantum) << "row " << i;
            // The row's own entries, then zeros.
            EXPECT_TRUE(std::equal(D.entry.begin() + D.outer[size_t(i)], D.entry.begin() + D.outer[size_t(i) + 1], P.entry.begin() + b));
            for (int k = b + n; k < e; ++k) EXPECT_EQ(P.entry[size_t(k)], 0u);
            padding += size_t(e - b - n);
        }
        EXPECT_EQ(P.entry.size(), size_t(P.outer.back()) + 2) << "two zero entries after the rows";
        EXPECT_EQ(P.col_hi.size(), wide ? P.entry.size() : 0u);
        // The product over the padded rows is the factors' product: a zero entry adds nothing.
        DirectedFactors padded{P.outer, std::vector<uint64_t>(P.entry.begin(), P.entry.end() - 2), {}};
        if (wide) padded.col_hi.assign(P.col_hi.begin(), P.col_hi.end() - 2);
        std::vector<vec3> E(m.vertex_count());
        for (size_t i = 0; i < E.size(); ++i) E[i] = vec3(float(i % 5) + 0.25f, float(i % 3), float((i * 7) % 11)) * 0.1f;
        const std::vector<vec3> want = F.multiply(E), got = multiply_directed(F, padded, E);
        for (size_t i = 0; i < want.size(); ++i)
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(got[i][c], want[i][c], 1e-5f * std::max(1.f, std::abs(want[i][c]))) << i;
        std::printf("padding: %zu of %zu entries (%.1f%%)\n", padding, D.entry.size(), 100.0 * double(padding) / double(D.entry.size()));
    }
}

TEST(GpuLayout, PiecesCoverEveryRowAtAlignedOffsetsWithinTheBufferTextureSize) {
    const PaddedFactors P = pad_factor_rows(factors(test::prepared_sphere(24), true));
    const int n = int(P.outer.size()) - 1;
    // One piece where the buffer texture holds every pair.
    const std::vector<FactorPiece> one = factor_pieces(P, int64_t(1) << 27, 4);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0].r0, 0);
    EXPECT_EQ(one[0].r1, n);
    EXPECT_EQ(one[0].base, 0);
    EXPECT_EQ(one[0].count, P.pairs());
    // Several where it holds 2048 texels (pairs): contiguous, aligned, each row's pairs inside its piece.
    for (int64_t align : {1, 4, 16}) {
        SCOPED_TRACE(align);
        const int64_t max_texels = 2048;
        const std::vector<FactorPiece> pieces = factor_pieces(P, max_texels, align);
        ASSERT_GT(pieces.size(), 2u);
        int next = 0;
        for (const FactorPiece& p : pieces) {
            EXPECT_EQ(p.r0, next);
            EXPECT_GT(p.r1, p.r0);
            EXPECT_EQ(p.base % align, 0);
            EXPECT_LE(p.count, max_texels);
            EXPECT_LE(p.base + p.count, P.pairs() + 1) << "within the entries (and the two zeros after them)";
            for (int r = p.r0; r < p.r1; ++r) {
                EXPECT_GE(int64_t(P.outer[size_t(r)]) / 2, p.base) << "row " << r;
                EXPECT_LE(int64_t(P.outer[size_t(r) + 1]) / 2, p.base + p.count) << "row " << r;
            }
            next = p.r1;
        }
        EXPECT_EQ(next, n);
    }
}

TEST(GpuLayout, ShownTexelsNameTheirSourceTriangleAndBarycentrics) {
    const PreparedMesh m = test::prepared_sphere(16);
    const AtlasStage A = make_atlas_stage(m, AtlasParams{128, 4, 30.f});
    const ShownTexels T = shown_texels(A, m.index);
    ASSERT_EQ(T.shown.size(), A.nonempty.size());
    ASSERT_EQ(T.bary.size(), A.nonempty.size());
    size_t filled = 0;
    for (size_t k = 0; k < T.shown.size(); ++k) {
        const int t = A.nonempty[k];
        const int s = A.fill[size_t(t)] >= 0 ? A.fill[size_t(t)] : t;
        filled += s != t;
        EXPECT_EQ(T.shown[k].x, t);
        EXPECT_EQ(T.shown[k].y, s);
        const int f = A.atlas.texel_face[size_t(s)];
        int32_t v2 = 0;
        std::memcpy(&v2, &T.bary[k].w, sizeof v2);
        if (f < 0) {
            EXPECT_EQ(T.shown[k].z, -1);
            EXPECT_EQ(v2, -1);
            continue;
        }
        EXPECT_EQ(T.shown[k].z, int(m.index[3 * size_t(f)]));
        EXPECT_EQ(T.shown[k].w, int(m.index[3 * size_t(f) + 1]));
        EXPECT_EQ(v2, int(m.index[3 * size_t(f) + 2]));
        EXPECT_EQ(vec3(T.bary[k]), A.atlas.texel_bary[size_t(s)]);
    }
    EXPECT_GT(filled, 0u) << "border texels show their fill source";
}
