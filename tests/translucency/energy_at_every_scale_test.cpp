// Energy at every scale (core/translucency/blend.h, surface.h): random closed meshes, from a few
// triangles to a few hundred, at 1 to 1000 mm per unit, in Jensen et al.'s measured materials,
// under a point or a directional light. The blended real-time radiosity, Σ B A / Σ E A over the
// atlas's inner texels, must be within 5% of the brute-force reference's on the same atlas in every
// channel. Fixed seeds; the worst case is printed.
#include "tests/translucency/energy.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <map>
#include <random>
#include <string>

using namespace mesolab;
using namespace mesolab::translucency;
using namespace mesolab::translucency::test;

namespace {
// The convex hull of points in general position (random points: no four coplanar), by testing
// every triple: O(n⁴), for the few dozen points used here. Faces wound outwards.
Shape convex_hull(const std::vector<vec3>& p) {
    Shape s;
    s.position = p;
    const size_t n = p.size();
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n; ++j)
            for (size_t k = j + 1; k < n; ++k) {
                const dvec3 a(p[i]), b(p[j]), c(p[k]);
                const dvec3 nrm = glm::cross(b - a, c - a);
                int above = 0, below = 0;
                for (size_t m = 0; m < n && !(above && below); ++m) {
                    if (m == i || m == j || m == k) continue;
                    const double side = glm::dot(dvec3(p[m]) - a, nrm);
                    (side > 0.0 ? above : below)++;
                }
                if (above && below) continue;
                if (above) s.index.insert(s.index.end(), {uint32_t(i), uint32_t(k), uint32_t(j)});
                else s.index.insert(s.index.end(), {uint32_t(i), uint32_t(j), uint32_t(k)});
            }
    return s;
}

// The icosahedron (unit circumradius), its triangles split `levels` times into four and pushed
// onto the unit sphere.
Shape icosphere(int levels) {
    const float g = (1.f + std::sqrt(5.f)) / 2.f;
    Shape s;
    s.position = {vec3(-1, g, 0), vec3(1, g, 0), vec3(-1, -g, 0), vec3(1, -g, 0), vec3(0, -1, g), vec3(0, 1, g),
                  vec3(0, -1, -g), vec3(0, 1, -g), vec3(g, 0, -1), vec3(g, 0, 1), vec3(-g, 0, -1), vec3(-g, 0, 1)};
    for (vec3& v : s.position) v = glm::normalize(v);
    s.index = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
               3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int l = 0; l < levels; ++l) {
        std::vector<uint32_t> next;
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            if (auto it = mid.find(key); it != mid.end()) return it->second;
            s.position.push_back(glm::normalize(s.position[a] + s.position[b]));
            return mid[key] = uint32_t(s.position.size() - 1);
        };
        for (size_t f = 0; f < s.index.size(); f += 3) {
            const uint32_t a = s.index[f], b = s.index[f + 1], c = s.index[f + 2];
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        s.index = std::move(next);
    }
    return s;
}

Shape octahedron() {
    return {{vec3(1, 0, 0), vec3(-1, 0, 0), vec3(0, 1, 0), vec3(0, -1, 0), vec3(0, 0, 1), vec3(0, 0, -1)},
            {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5}};
}

Shape tetrahedron() {
    return {{vec3(1, 1, 1), vec3(1, -1, -1), vec3(-1, 1, -1), vec3(-1, -1, 1)}, {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2}};
}

// 12 triangles, half extents 1.
Shape cube() {
    Shape s;
    for (int k = 0; k < 8; ++k) s.position.push_back(vec3(k & 1 ? 1.f : -1.f, k & 2 ? 1.f : -1.f, k & 4 ? 1.f : -1.f));
    const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : q) s.index.insert(s.index.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
    return s;
}

// Every vertex moved along its direction from the centre by a factor in [1 − a, 1 + a], and the
// whole stretched per axis by factors in [0.6, 1.4]: closed, not necessarily convex.
Shape perturbed(Shape s, float a, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.f, 1.f), axis(0.6f, 1.4f);
    const vec3 stretch(axis(rng), axis(rng), axis(rng));
    for (vec3& v : s.position) v *= (1.f + a * u(rng)) * stretch;
    return s;
}

Shape random_hull(int points, std::mt19937& rng) {
    std::normal_distribution<float> n(0.f, 1.f);
    std::uniform_real_distribution<float> axis(0.6f, 1.4f);
    const vec3 stretch(axis(rng), axis(rng), axis(rng));
    std::vector<vec3> p;
    for (int k = 0; k < points; ++k) {
        const vec3 d = glm::normalize(vec3(n(rng), n(rng), n(rng)));
        p.push_back(d * (0.7f + 0.3f * std::abs(n(rng))) * stretch);
    }
    return convex_hull(p);
}

struct Case {
    std::string shape, material;
    double mm = 1.0;
    bool point = false;
    Shape mesh;
    Light light;
};

// A light outside the object: a directional one, or a point light beyond its bounding sphere,
// half of them within 0.15 units of it (where it gets no shadow map, ShadowMap::valid) and half
// 0.6-2.1 units away.
Light random_light(bool point, const Shape& s, std::mt19937& rng) {
    std::normal_distribution<float> n(0.f, 1.f);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const vec3 d = glm::normalize(vec3(n(rng), n(rng), n(rng)));
    if (!point) return directional_light(d);
    float radius = 0.f;
    for (const vec3& v : s.position) radius = std::max(radius, glm::length(v));
    return point_light(d * (radius + (u(rng) < 0.5f ? 0.15f * u(rng) : 0.6f + 1.5f * u(rng))));
}

// A convex hull of 8 random points with a 3.8 mm edge (at 50 mm per unit) between triangles of
// 60-110 mm: the edge's factor R_d(r_ij) A_j / 3 was 9 times R_total in ketchup's red.
Shape hull_with_a_short_edge() {
    return {{vec3(0.534076f, 0.522396f, 0.462599f), vec3(0.643065f, -0.216935f, 0.744175f), vec3(0.389496f, -0.436913f, -0.264419f),
             vec3(-0.275953f, 0.231262f, 0.569440f), vec3(0.492733f, 0.484889f, 0.412258f), vec3(-0.547442f, -0.256361f, -0.315612f),
             vec3(0.070848f, 0.510125f, 0.462572f), vec3(0.944306f, 0.057442f, 0.782334f)},
            {0, 2, 4, 0, 7, 2, 0, 4, 6, 0, 6, 7, 1, 5, 2, 1, 2, 7, 1, 3, 5, 1, 7, 3, 2, 5, 4, 3, 6, 5, 3, 7, 6, 4, 5, 6}};
}
}  // namespace

// Per scale (1, 10, 50, 200 and 1000 mm per unit) five random shapes in turn: an octahedron, a
// tetrahedron, a cube and an icosahedron (80 triangles) with their vertices moved and stretched,
// and a convex hull of 8-40 random points or an icosphere of 320 triangles; directional and point
// lights in turn; Jensen et al.'s twelve materials in turn. Then the cases furthest off before:
// the regular octahedron at 10 mm per unit in skin1 (0.93-0.98 of the reference: the closure held
// each texel to R_total, the surface holds 1.03-1.09 R_total there) and at 1 mm (2.6 in red: the
// surface holds 0.39 R_total); at 1,000 mm in marble (0.71: the reference's texels of two chunks a
// fraction of a texel apart); and the hull with a short edge in ketchup at 50 mm (1.75).
// A 128² atlas, K = 7: texels of 0.03 mm (1 mm per unit) to 35 mm (1,000 mm per unit).
namespace {
void expect_energy_at_every_scale(bool burley) {
    const char* materials[] = {"skin1", "skin2", "marble", "apple", "ketchup", "skimmilk", "potato", "chicken1", "wholemilk", "spectralon", "cream", "chicken2"};
    std::vector<Case> cases;
    std::mt19937 rng(20240611);
    int m = 0, k = 0;
    for (const double mm : {1.0, 10.0, 50.0, 200.0, 1000.0})
        for (int i = 0; i < 5; ++i, ++k) {
            Case c;
            c.mm = mm, c.point = k % 2 == 1, c.material = materials[m++ % std::size(materials)];
            switch ((i + k / 5) % 5) {
            case 0: c.shape = "octahedron", c.mesh = perturbed(octahedron(), 0.25f, rng); break;
            case 1: c.shape = "tetrahedron", c.mesh = perturbed(tetrahedron(), 0.2f, rng); break;
            case 2: c.shape = "cube", c.mesh = perturbed(cube(), 0.2f, rng); break;
            case 3: c.shape = "icosahedron", c.mesh = perturbed(icosphere(1), 0.15f, rng); break;
            default:
                if (k % 3 == 0) {
                    c.shape = "icosphere", c.mesh = perturbed(icosphere(2), 0.05f, rng);
                } else {
                    const int points = 8 + 8 * (k % 5);
                    c.shape = "hull of " + std::to_string(points) + " points", c.mesh = random_hull(points, rng);
                }
            }
            c.light = random_light(c.point, c.mesh, rng);
            cases.push_back(std::move(c));
        }
    const Light sun = directional_light(vec3(0.3f, 0.2f, 1.f));
    cases.push_back({"regular octahedron", "skin1", 10.0, false, octahedron(), sun});
    cases.push_back({"regular octahedron", "skin1", 1.0, false, octahedron(), sun});
    cases.push_back({"regular octahedron", "marble", 1000.0, true, octahedron(), point_light(vec3(0.5f, 0.4f, 1.2f))});
    cases.push_back({"hull with a short edge", "ketchup", 50.0, true, hull_with_a_short_edge(), point_light(vec3(1.081f, 1.027f, -1.075f))});

    double worst = 0.0;
    std::string worst_case;
    for (const Case& c : cases) {
        EnergySettings s;
        s.material = c.material, s.atlas = 128, s.unblended = false, s.rmse = false, s.burley = burley;
        const Energy e = energy(c.mesh, c.mm, c.light, s);
        const std::string what = c.shape + " (" + std::to_string(c.mesh.index.size() / 3) + " triangles), " + c.material + ", " +
                                 std::to_string(int(c.mm)) + " mm per unit, " + (c.point ? "point" : "directional") + " light";
        ASSERT_TRUE(e.lit) << what;
        const dvec3 q = e.ratio();
        std::printf("%-82s blended / reference %.3f %.3f %.3f\n", what.c_str(), q.x, q.y, q.z);
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(q[ch], 1.0, 0.05) << what << ", channel " << ch;
            if (std::abs(q[ch] - 1.0) > worst) worst = std::abs(q[ch] - 1.0), worst_case = what + ", channel " + "RGB"[ch];
        }
    }
    std::printf("worst: %.1f%% off the reference, %s\n", 100.0 * worst, worst_case.c_str());
}
}  // namespace

TEST(EnergyAtEveryScale, RandomClosedMeshesKeepTheReferencesEnergyWithinFivePercent) { expect_energy_at_every_scale(false); }

// The same cases with Christensen and Burley's profile (lensch-burley): the pipeline's closures
// hold for a profile infinite at r = 0 as for the dipole.
TEST(EnergyAtEveryScale, WithBurleysProfileTooRandomClosedMeshesKeepTheReferencesEnergyWithinFivePercent) { expect_energy_at_every_scale(true); }
