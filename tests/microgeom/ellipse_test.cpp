// Ellipse shadows (microgeom, Heidrich et al. 2000 §4): agreement with the exact interpolated
// test on the bricks, flat and v-groove fields, degenerate visibility, independence of the thread count.
#include "core/microgeom/ellipse.h"
#include "core/microgeom/scatter.h"
#include "support/threads.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

Heightfield procedural(const char* name, int res, float vgroove_angle = 90.f) {
    ProceduralParams p;
    p.name = name;
    p.resolution = res;
    p.vgroove_angle = vgroove_angle;
    return make_procedural(p);
}

// 40 fixed light directions, theta in [0, 80] degrees (uniform in solid angle), all azimuths
// (golden-angle spiral).
std::vector<vec3> light_directions() {
    std::vector<vec3> l;
    for (int k = 0; k < 40; ++k) {
        const float t = float(k) / 39.f;
        const float theta = std::acos(1.f - t * (1.f - std::cos(radians(80.f)))) * 180.f / kPi;
        l.push_back(direction_from_degrees(theta, float(k) * 137.50776f));
    }
    return l;
}

// A visibility of W x H texels over dirs with every entry given by flag(direction, x, y).
template <class F>
Visibility synthetic_visibility(int W, int H, const DirectionSet& dirs, F flag) {
    Visibility v;
    v.width = W;
    v.height = H;
    v.count = dirs.size();
    v.hit.resize(size_t(W) * size_t(H) * size_t(dirs.size()));
    for (int i = 0; i < dirs.size(); ++i)
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) v.hit[(size_t(i) * size_t(H) + size_t(y)) * size_t(W) + size_t(x)] = flag(i, x, y);
    return v;
}

bool well_formed(const Ellipse& e) {
    return std::isfinite(e.centre.x) && std::isfinite(e.centre.y) && std::isfinite(e.angle) && std::isfinite(e.a) &&
           std::isfinite(e.b) && e.a >= e.b && e.b > 0.f && e.angle >= 0.f && e.angle < kPi;
}

// Upward probe directions over the whole hemisphere (theta up to 89 degrees).
std::vector<vec3> hemisphere_probes() {
    std::vector<vec3> w;
    for (int t = 0; t <= 89; t += 7)
        for (int p = 0; p < 360; p += 15) w.push_back(direction_from_degrees(float(t), float(p)));
    w.push_back(direction_from_degrees(89.f, 33.f));
    return w;
}
}  // namespace

TEST(Ellipse, BricksAgreeWithExactShadowTest) {
    const Heightfield hf = procedural("bricks", 128);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    const EllipseMap map = fit_ellipses(hf, dirs, vis);
    ASSERT_EQ(map.e.size(), size_t(128 * 128));
    for (const Ellipse& e : map.e) ASSERT_TRUE(well_formed(e));
    size_t agree = 0, total = 0;
    for (const vec3& l : light_directions()) {
        const std::vector<float> exact = visibility_texture(hf, dirs, vis, l);
        const std::vector<float> approx = ellipse_visibility_texture(map, hf, l);
        for (size_t p = 0; p < exact.size(); ++p) {
            agree += (exact[p] >= 0.5f) == (approx[p] >= 0.5f) ? 1 : 0;
            ++total;
        }
    }
    const double fraction = double(agree) / double(total);
    std::printf("[ ellipse  ] bricks 128x128, N = 100: binary agreement with the exact test %.2f%% (%zu of %zu texel-lights)\n",
                100.0 * fraction, agree, total);
    EXPECT_GE(fraction, 0.90);
}

TEST(Ellipse, FlatFieldIsLitFromEveryUpwardDirection) {
    const Heightfield hf = procedural("flat", 16);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    const EllipseMap map = fit_ellipses(hf, dirs, vis);
    ASSERT_EQ(map.e.size(), size_t(16 * 16));
    for (const vec3& w : hemisphere_probes()) {
        const std::vector<float> v = ellipse_visibility_texture(map, hf, w);
        ASSERT_EQ(v.size(), size_t(16 * 16));
        for (float x : v) ASSERT_EQ(x, 1.f) << "w = (" << w.x << ", " << w.y << ", " << w.z << ")";
        for (const Ellipse& e : map.e) ASSERT_EQ(ellipse_visibility(e, w), 1.f);
    }
    EXPECT_EQ(ellipse_visibility(map.e[0], vec3(0.f, 0.f, -1.f)), 0.f);
    EXPECT_EQ(ellipse_visibility(map.e[0], vec3(1.f, 0.f, 0.f)), 0.f);
}

TEST(Ellipse, VgrooveBottomShadowedAcrossLitFromAbove) {
    const int n = 64;
    const Heightfield hf = procedural("vgrooves", n, 20.f);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    const EllipseMap map = fit_ellipses(hf, dirs, vis);
    // Grooves run along y; the bottom of the first lies between texels 7 and 8 (period 16).
    const int y = n / 2;
    for (int x : {7, 8}) {
        SCOPED_TRACE(x);
        const Ellipse& e = map.at(x, y);
        for (const vec3& w : {vec3(0.f, 0.f, 1.f), direction_from_degrees(5.f, 0.f), direction_from_degrees(5.f, 90.f)}) {
            EXPECT_GE(visibility_fraction(hf, dirs, vis, x, y, w), 0.5f) << "exact test";
            EXPECT_GE(ellipse_visibility(e, w, map.edge), 0.5f);
            EXPECT_EQ(ellipse_visibility(e, w), 1.f);
        }
        for (float theta : {60.f, 75.f, 85.f})
            for (float phi : {0.f, 180.f}) {
                const vec3 w = direction_from_degrees(theta, phi);
                EXPECT_LT(visibility_fraction(hf, dirs, vis, x, y, w), 0.5f) << "exact test";
                EXPECT_LT(ellipse_visibility(e, w, map.edge), 0.5f) << theta << " " << phi;
                EXPECT_EQ(ellipse_visibility(e, w), 0.f) << theta << " " << phi;
            }
    }
}

TEST(Ellipse, DegenerateVisibilityStaysFinite) {
    const Heightfield hf = procedural("flat", 8);
    for (int n : {16, 100}) {
        SCOPED_TRACE(n);
        const DirectionSet dirs = make_direction_set(n);
        // Column x selects the case: 0 all shadowed, 1 all lit, 2 one lit, 3 two lit, 4 only the
        // lowest upper direction lit, 5 alternate, 6 every direction below, 7 real visibility.
        const Visibility real = compute_visibility(hf, dirs);
        int last_up = 0;
        for (int i = 0; i < dirs.size(); ++i)
            if (dirs.d[size_t(i)].z > 0.f) last_up = i;
        const Visibility vis = synthetic_visibility(8, 8, dirs, [&](int i, int x, int y) -> uint32_t {
            const uint32_t shadow = Visibility::encode(1.f, 1.f);
            switch (x) {
                case 0: return shadow;
                case 1: return Visibility::kNoHit;
                case 2: return i == 0 ? Visibility::kNoHit : shadow;
                case 3: return i == 1 || i == 2 ? Visibility::kNoHit : shadow;
                case 4: return i == last_up ? Visibility::kNoHit : shadow;
                case 5: return (i + y) % 2 ? Visibility::kNoHit : shadow;
                case 6: return Visibility::kBelow;
                default: return real.at(i, x, y);
            }
        });
        const EllipseMap map = fit_ellipses(hf, dirs, vis);
        ASSERT_EQ(map.e.size(), size_t(64));
        for (const Ellipse& e : map.e) EXPECT_TRUE(well_formed(e));
        for (const vec3& w : hemisphere_probes())
            for (int y = 0; y < 8; ++y) {
                for (int x = 0; x < 8; ++x) {
                    const float v = ellipse_visibility(map.at(x, y), w, map.edge);
                    ASSERT_TRUE(v >= 0.f && v <= 1.f) << x << " " << y;
                }
                EXPECT_EQ(ellipse_visibility(map.at(0, y), w, map.edge), 0.f) << "all shadowed";
                EXPECT_EQ(ellipse_visibility(map.at(6, y), w, map.edge), 0.f) << "all below";
                EXPECT_EQ(ellipse_visibility(map.at(1, y), w, map.edge), 1.f) << "all lit";
            }
        // One lit direction: that direction is lit, the opposite one is not.
        const vec3 d0 = dirs.d[0];
        EXPECT_EQ(ellipse_visibility(map.at(2, 0), d0), 1.f);
        EXPECT_EQ(ellipse_visibility(map.at(2, 0), vec3(-d0.x, -d0.y, d0.z)), 0.f);
        EXPECT_EQ(ellipse_visibility(map.at(4, 0), dirs.d[size_t(last_up)]), 1.f);
    }
    // A texel at the bottom of a deep one-texel hole: every direction hits the walls.
    Heightfield hole = procedural("flat", 9);
    for (float& h : hole.h) h = 1000.f;
    hole.h[hole.index(4, 4)] = 0.f;
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hole, dirs);
    const EllipseMap map = fit_ellipses(hole, dirs, vis);
    ASSERT_EQ(map.e.size(), size_t(9 * 9));
    for (const Ellipse& e : map.e) EXPECT_TRUE(well_formed(e));
    for (const vec3& w : hemisphere_probes()) EXPECT_EQ(ellipse_visibility(map.at(4, 4), w, map.edge), 0.f);
    // Mismatched sizes are rejected.
    EXPECT_THROW(fit_ellipses(procedural("flat", 16), dirs, vis), std::invalid_argument);
}

TEST(Ellipse, FitIsIndependentOfTheThreadCountAndOfProgressReporting) {
    // The fit runs in parallel over rows: one thread (reporting progress) and many threads (not
    // reporting) split the work differently and must give the same bytes.
    const Heightfield hf = procedural("bumps", 32);
    const DirectionSet dirs = make_direction_set(100);
    const Visibility vis = compute_visibility(hf, dirs);
    std::vector<double> fractions;
    const EllipseMap a = test::with_threads(1, [&] { return fit_ellipses(hf, dirs, vis, [&](double f) { fractions.push_back(f); }); });
    const EllipseMap b = test::with_threads(test::kManyThreads, [&] { return fit_ellipses(hf, dirs, vis); });
    ASSERT_EQ(a.e.size(), size_t(32 * 32));
    ASSERT_EQ(a.e.size(), b.e.size());
    EXPECT_EQ(0, std::memcmp(a.e.data(), b.e.data(), a.bytes()));
    EXPECT_EQ(a.edge, b.edge);
    ASSERT_FALSE(fractions.empty());
    EXPECT_EQ(fractions.front(), 0.0);
    EXPECT_EQ(fractions.back(), 1.0);
    // Cancellation by throwing from progress propagates.
    EXPECT_THROW(fit_ellipses(hf, dirs, vis, [](double f) { if (f > 0.3) throw std::runtime_error("cancel"); }),
                 std::runtime_error);
}
