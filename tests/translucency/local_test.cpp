// The local response (core/translucency/local.h): kernel weights on a plane against R_d, the
// self term as a disk, the convolution against a direct sum, bounds on a kernel's total, bad K.
#include "core/error.h"
#include "core/mesh.h"
#include "core/translucency/local.h"
#include "core/translucency/mesh_prep.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
// The unit square as two triangles, in an atlas with a border wide enough for K = 15.
struct Plane {
    std::vector<vec3> p{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    std::vector<uint32_t> i{0, 1, 2, 0, 2, 3};
    Atlas atlas = build_atlas(p, i, {128, 8, 30.f});
};

// An inner texel whose whole K x K block is inner (away from the square's edges).
size_t interior_texel(const Atlas& a, int K) {
    const int h = (K - 1) / 2;
    for (int y = 0; y < a.size; ++y)
        for (int x = 0; x < a.size; ++x) {
            bool all = true;
            for (int dy = -h; dy <= h && all; ++dy)
                for (int dx = -h; dx <= h && all; ++dx) {
                    const int X = x + dx, Y = y + dy;
                    all = X >= 0 && Y >= 0 && X < a.size && Y < a.size && a.texel_kind[a.texel(X, Y)] == Atlas::kInner;
                }
            if (all && x > a.size / 3 && y > a.size / 3) return a.texel(x, y);
        }
    return SIZE_MAX;
}
}  // namespace

TEST(LocalKernels, WeightsOnAPlaneAreRdAtTheTexelDistanceTimesTheTexelArea) {
    const Plane pl;
    const Dipole d(measured_material("skin1").medium);
    const double mm = 20.0, h = mm / pl.atlas.scale;  // texel size, mm
    const LocalKernels L = build_local_kernels(pl.atlas, pl.p, pl.i, d, mm, 7);
    const size_t t = interior_texel(pl.atlas, 7);
    ASSERT_NE(t, SIZE_MAX);
    const size_t k = size_t(L.slot[t]);
    for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx) {
            const dvec3 expect = dx == 0 && dy == 0 ? d.reflectance_within(h / std::sqrt(M_PI)) : d.Rd(h * std::hypot(dx, dy)) * (h * h);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(L.weight(k, dx, dy, c), expect[c], 5e-4 * expect[c]) << dx << "," << dy << " c" << c;
        }
    // 7 rows of 7 RGB taps, each padded from 21 to 24 floats.
    EXPECT_EQ(L.row, 24);
    EXPECT_EQ(L.bytes(), L.texel.size() * 4 + L.slot.size() * 4 + L.texel.size() * 7 * 24 * 4);
}

TEST(LocalKernels, ConvolutionEqualsTheDirectSum) {
    const Plane pl;
    const Dipole d(measured_material("marble").medium);
    const double mm = 10.0, h = mm / pl.atlas.scale;
    const LocalKernels L = build_local_kernels(pl.atlas, pl.p, pl.i, d, mm, 5);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<vec3> E(pl.atlas.texel_kind.size());
    for (vec3& e : E) e = vec3(u(rng), u(rng), u(rng));
    const std::vector<vec3> B = convolve_local(L, E);
    const size_t t = interior_texel(pl.atlas, 5);
    const int N = pl.atlas.size, tx = int(t) % N, ty = int(t) / N;
    dvec3 sum(0.0);
    for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
            const dvec3 w = dx == 0 && dy == 0 ? d.reflectance_within(h / std::sqrt(M_PI)) : d.Rd(h * std::hypot(dx, dy)) * (h * h);
            sum += w * dvec3(E[size_t(ty + dy) * size_t(N) + size_t(tx + dx)]);
        }
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(B[t][c], sum[c], 5e-4 * sum[c]);
    // Texels that are not inner get nothing.
    for (size_t s = 0; s < B.size(); ++s) {
        if (pl.atlas.texel_kind[s] != Atlas::kInner) {
            ASSERT_EQ(B[s], vec3(0.f));
        }
    }
}

// The SIMD convolution reads padded kernel rows and texels past each row's end; on a curved
// mesh, for every kernel size, every inner texel must still get exactly its K x K weighted sum.
TEST(LocalKernels, PaddedRowsGiveTheWeightedSumForEveryKernelSize) {
    const TriMesh s = make_primitive(Primitive::Torus, 40);
    const PreparedMesh m = prepare_mesh(s.position, s.index, 0);
    const Atlas a = build_atlas(m.position, m.index, {256, 8, 30.f});
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<vec3> E(a.texel_kind.size());
    for (vec3& e : E) e = vec3(u(rng), u(rng), u(rng));
    for (int K : {3, 5, 7, 9, 11, 13, 15}) {
        const LocalKernels L = build_local_kernels(a, m.position, m.index, Dipole(measured_material("ketchup").medium), 40.0, K);
        ASSERT_GT(L.texel.size(), 500u);
        EXPECT_EQ(L.row % 12, 0);
        EXPECT_GE(L.row, 3 * K);
        const std::vector<vec3> B = convolve_local(L, E);
        const int h = (K - 1) / 2, N = a.size;
        double worst = 0.0;
        for (size_t k = 0; k < L.texel.size(); ++k) {
            const int t = L.texel[k], tx = t % N, ty = t / N;
            dvec3 sum(0.0);
            for (int dy = -h; dy <= h; ++dy)
                for (int dx = -h; dx <= h; ++dx)
                    for (int c = 0; c < 3; ++c) sum[c] += double(L.weight(k, dx, dy, c)) * E[size_t(ty + dy) * size_t(N) + size_t(tx + dx)][c];
            for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(double(B[size_t(t)][c]) - sum[c]) / std::max(sum[c], 1e-30));
        }
        EXPECT_LT(worst, 1e-5) << "K = " << K;
    }
}

TEST(LocalKernels, AKernelHoldsTheReflectanceOfItsDisk) {
    // Constant irradiance: the kernel's total lies between the reflectance within its inscribed
    // circle (less a texel) and within its circumscribed one.
    const Plane pl;
    for (const char* name : {"marble", "skin1", "ketchup"}) {
        const Dipole d(measured_material(name).medium);
        for (double mm : {2.0, 20.0}) {
            const double h = mm / pl.atlas.scale;
            const LocalKernels L = build_local_kernels(pl.atlas, pl.p, pl.i, d, mm, 15);
            const size_t t = interior_texel(pl.atlas, 15);
            const std::vector<vec3> B = convolve_local(L, std::vector<vec3>(pl.atlas.texel_kind.size(), vec3(1.f)));
            const dvec3 lo = d.reflectance_within(7.5 * h - h), hi = d.reflectance_within(std::sqrt(2.0) * 7.5 * h);
            for (int c = 0; c < 3; ++c) {
                EXPECT_GE(B[t][c], lo[c] * (1 - 1e-3)) << name << " " << mm << " c" << c;
                EXPECT_LE(B[t][c], hi[c] * (1 + 1e-3)) << name << " " << mm << " c" << c;
            }
        }
    }
}

TEST(LocalKernels, EveryKernelOnACurvedMeshIsFiniteAndNonNegative) {
    const TriMesh s = make_primitive(Primitive::Torus, 48);
    const PreparedMesh m = prepare_mesh(s.position, s.index, 0);
    const Atlas a = build_atlas(m.position, m.index, {256, 4, 30.f});
    const LocalKernels L = build_local_kernels(a, m.position, m.index, Dipole(measured_material("wholemilk").medium), 30.0, 7);
    EXPECT_GT(L.texel.size(), 1000u);
    for (float w : L.w) ASSERT_TRUE(std::isfinite(w) && w >= 0.f);
}

TEST(LocalKernels, BadKernelSizesNameTheKey) {
    const Plane pl;
    const Dipole d(measured_material("marble").medium);
    for (int K : {2, 4, 1, 17}) {
        try {
            build_local_kernels(pl.atlas, pl.p, pl.i, d, 1.0, K);
            FAIL() << K;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("translucency.kernel"), std::string::npos);
        }
    }
    const Atlas narrow = build_atlas(pl.p, pl.i, {128, 4, 30.f});
    EXPECT_THROW(build_local_kernels(narrow, pl.p, pl.i, d, 1.0, 9), InputError);  // needs a border of 5
    EXPECT_NO_THROW(build_local_kernels(narrow, pl.p, pl.i, d, 1.0, 7));
}
