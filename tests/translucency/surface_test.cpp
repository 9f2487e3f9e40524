// The dipole over the object's own surface (core/translucency/surface.h): one triangle against a
// fine midpoint sum, a plane (R_total), a sphere (the reflectance within its diameter), and the
// tree against every triangle integrated exactly.
#include "core/translucency/surface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
// ∫ R_d(|x − y|) dA over triangle abc as the sum over n² equal sub-triangles at their centroids.
dvec3 midpoint_sum(const Dipole& d, dvec3 a, dvec3 b, dvec3 c, dvec3 y, int n) {
    dvec3 s(0.0);
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a)) / (double(n) * double(n));
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n - i; ++j) {
            s += d.Rd(glm::length(a + (b - a) * ((i + 1.0 / 3.0) / n) + (c - a) * ((j + 1.0 / 3.0) / n) - y)) * area;
            if (j < n - i - 1) s += d.Rd(glm::length(a + (b - a) * ((i + 2.0 / 3.0) / n) + (c - a) * ((j + 2.0 / 3.0) / n) - y)) * area;
        }
    return s;
}

// A grid of n x n squares of side h (mm), two triangles each, folded by 90° along y = 0.
void folded_grid(int n, float h, std::vector<vec3>& p, std::vector<uint32_t>& index) {
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float x = float(i) * h - float(n) * h / 2.f, s = float(j) * h - float(n) * h / 2.f;
            p.push_back(s < 0.f ? vec3(x, s, 0.f) : vec3(x, 0.f, s));
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t a = uint32_t(j * (n + 1) + i), w = uint32_t(n + 1);
            index.insert(index.end(), {a, a + 1, a + w + 1, a, a + w + 1, a + w});
        }
}
}  // namespace

// The polar sum against 700² sub-triangles, for points inside the triangle, near its corner and
// an edge, above it and beside it, in a material of short reach (skin1, blue: 0.7 mm) and one of
// long reach (spectralon, no absorption). A far triangle is placed so that the table covers every
// distance. 700² sub-triangles (29 µm) resolve spectralon's peak (z_r 49–86 µm) to about 1e-3
// near the corner (1,500²: 2.5e-4, towards the polar sum).
TEST(SurfaceReflectance, OneTriangleMatchesAFineMidpointSum) {
    const std::vector<vec3> p = {vec3(0, 0, 0), vec3(20, 0, 0), vec3(3, 17, 0), vec3(-40, -40, -40), vec3(-39, -40, -40), vec3(-40, -39, -40)};
    const std::vector<uint32_t> index = {0, 1, 2, 3, 4, 5};
    for (const char* material : {"skin1", "spectralon"}) {
        const Dipole d(measured_material(material).medium);
        const SurfaceReflectance S(p, index, 1.0, d);
        ASSERT_EQ(S.triangles(), 2u);
        for (const dvec3 y : {dvec3(8, 5, 0), dvec3(0.1, 0.05, 0), dvec3(10, 0.02, 0), dvec3(10, -0.3, 0), dvec3(8, 5, 2), dvec3(30, 10, 1)}) {
            const dvec3 exact = S.triangle(0, y), sum = midpoint_sum(d, dvec3(p[0]), dvec3(p[1]), dvec3(p[2]), y, 700);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(exact[c], sum[c], 2e-3 * sum[c] + 1e-9) << material << " at " << y.x << ", " << y.y << ", " << y.z << ", channel " << c;
        }
    }
}

// A plane far larger than the diffusion length holds R_total: 100 x 100 squares of 4 mm, the
// point near its centre.
TEST(SurfaceReflectance, OnALargePlaneItIsTheTotalDiffuseReflectance) {
    std::vector<vec3> p;
    std::vector<uint32_t> index;
    folded_grid(100, 4.f, p, index);
    for (vec3& v : p) v = vec3(v.x, v.y + v.z, 0.f);  // unfolded
    for (const char* material : {"skin1", "skin2", "marble"}) {
        const Dipole d(measured_material(material).medium);
        const dvec3 R = SurfaceReflectance(p, index, 1.0, d)(vec3(0.3f, -0.7f, 0.f)), Rt = d.total_reflectance();
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(R[c] / Rt[c], 1.0, 1e-3) << material << ", channel " << c;
    }
}

// On a sphere of radius a every point sees its surface at chords s ∈ [0, 2a], and the area between
// chords s and s + ds is 2π s ds (Archimedes: s² = 2a² (1 − cos θ), dA = 2π a² sin θ dθ), so
// R_S = ∫_0^{2a} 2π s R_d(s) ds, the dipole's power within the diameter: less than R_total, the
// less the smaller the sphere. An icosphere of 5,120 triangles (its flat faces 0.3% short of the
// sphere's area) at radii of 1, 10 and 100 mm.
TEST(SurfaceReflectance, OnASphereItIsTheReflectanceWithinTheDiameter) {
    const float g = (1.f + std::sqrt(5.f)) / 2.f;
    std::vector<vec3> p = {vec3(-1, g, 0), vec3(1, g, 0), vec3(-1, -g, 0), vec3(1, -g, 0), vec3(0, -1, g), vec3(0, 1, g),
                           vec3(0, -1, -g), vec3(0, 1, -g), vec3(g, 0, -1), vec3(g, 0, 1), vec3(-g, 0, -1), vec3(-g, 0, 1)};
    for (vec3& v : p) v = glm::normalize(v);
    std::vector<uint32_t> index = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                                   3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int level = 0; level < 4; ++level) {
        std::vector<uint32_t> next;
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            if (auto it = mid.find(key); it != mid.end()) return it->second;
            p.push_back(glm::normalize(p[a] + p[b]));
            return mid[key] = uint32_t(p.size() - 1);
        };
        for (size_t f = 0; f < index.size(); f += 3) {
            const uint32_t a = index[f], b = index[f + 1], c = index[f + 2];
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        index = std::move(next);
    }
    for (const char* material : {"skin1", "marble"}) {
        const Dipole d(measured_material(material).medium);
        for (const double radius : {1.0, 10.0, 100.0}) {
            const SurfaceReflectance S(p, index, radius, d);
            const dvec3 R = S(p[0] * float(radius)), within = d.reflectance_within(2.0 * radius);
            std::printf("%s, sphere of radius %g mm: R_S / R_total %.4f %.4f %.4f, reflectance within the diameter / R_total %.4f %.4f %.4f\n",
                        material, radius, R.x / d.total_reflectance().x, R.y / d.total_reflectance().y, R.z / d.total_reflectance().z,
                        within.x / d.total_reflectance().x, within.y / d.total_reflectance().y, within.z / d.total_reflectance().z);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(R[c] / within[c], 1.0, 5e-3) << material << ", radius " << radius << ", channel " << c;
        }
    }
}

// The tree's expansions against every triangle integrated exactly, on a 90° fold of 80 x 80
// squares of 2 mm and 0.5 mm, points on either side of the fold (measured: within 2.3e-3). And
// 1 mm from the fold the surface holds more than R_total (measured: skin1 1.11, 1.11, 1.07;
// marble 1.08 in every channel): the other side is nearer in 3D than along the surface.
TEST(SurfaceReflectance, TheTreeAgreesWithEveryTriangleIntegratedExactly) {
    for (const float h : {2.f, 0.5f}) {
        std::vector<vec3> p;
        std::vector<uint32_t> index;
        folded_grid(80, h, p, index);
        for (const char* material : {"skin1", "marble", "spectralon"}) {
            const Dipole d(measured_material(material).medium);
            const SurfaceReflectance S(p, index, 1.0, d);
            for (const vec3 y : {vec3(0.3f, -0.7f, 0.f), vec3(1.1f, -3.3f, 0.f), vec3(-2.f, -0.05f, 0.f), vec3(5.f, 0.f, 2.2f)}) {
                dvec3 exact(0.0);
                for (size_t f = 0; f < S.triangles(); ++f) exact += S.triangle(f, dvec3(y));
                const dvec3 tree = S(y);
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(tree[c] / exact[c], 1.0, 3e-3) << material << ", squares of " << h << " mm, channel " << c;
            }
            if (std::string(material) == "spectralon") continue;  // its reach exceeds the 40-160 mm grid
            const dvec3 at_fold = S(vec3(0.3f, -1.f, 0.f)), Rt = d.total_reflectance();
            for (int c = 0; c < 3; ++c) EXPECT_GT(at_fold[c], 1.05 * Rt[c]) << material << ", channel " << c;
        }
    }
}
