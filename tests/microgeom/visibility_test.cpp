// Visibility textures S_i (microgeom, Heidrich et al. 2000 §3): the accelerated walk against a
// brute-force ray/triangle reference, periodic wrap, degenerate fields, encoding, cancellation.
#include "core/error.h"
#include "core/microgeom/visibility.h"
#include "support/threads.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

using namespace mesolab;
using namespace mesolab::microgeom;

namespace {

// [SECTION] Helpers
// A field of W x H texels with heights height(x, y) given in texels (world = texels * s).
Heightfield make_field(int W, int H, bool periodic, const std::function<float(int, int)>& height, float s = 1.f) {
    Heightfield f;
    f.width = W;
    f.height = H;
    f.texel_size = s;
    f.periodic = periodic;
    f.h.resize(size_t(W) * size_t(H));
    f.albedo.assign(f.h.size(), vec3(0.5f));
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) f.h[f.index(x, y)] = height(x, y) * s;
    return f;
}

Heightfield random_field(int W, int H, bool periodic, uint32_t seed, float max_height) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, max_height);
    std::vector<float> v(size_t(W) * size_t(H));
    for (float& x : v) x = u(rng);
    return make_field(W, H, periodic, [&](int x, int y) { return v[size_t(y) * size_t(W) + size_t(x)]; });
}

// Height (texels) of the triangulated surface at continuous texel coordinates (c, r): cell
// diagonal from (x, y) to (x+1, y+1).
double surface_at(const Heightfield& f, double c, double r) {
    const int W = f.width, H = f.height;
    const int Wc = f.periodic ? W : W - 1, Hc = f.periodic ? H : H - 1;
    int i = std::clamp(int(std::floor(c)), 0, Wc - 1), j = std::clamp(int(std::floor(r)), 0, Hc - 1);
    const double u = c - i, v = r - j;
    auto h = [&](int x, int y) { return double(f.h[f.index(x % W, y % H)]) / f.texel_size; };
    const double h00 = h(i, j), h10 = h(i + 1, j), h01 = h(i, j + 1), h11 = h(i + 1, j + 1);
    return u >= v ? h00 + u * (h10 - h00) + v * (h11 - h10) : h00 + u * (h11 - h01) + v * (h01 - h00);
}

// Local-frame point for texel coordinates (c, r) and height z (texels).
vec3 local_point(const Heightfield& f, double c, double r, double z) {
    return {float((c + 0.5) * f.texel_size), float((f.height - 0.5 - r) * f.texel_size), float(z * f.texel_size)};
}
// Local-frame direction for a texel-space direction (dc, dr, dz): rows grow down, local y up.
vec3 local_dir(double dc, double dr, double dz) { return glm::normalize(vec3(float(dc), float(-dr), float(dz))); }

vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> n(0.f, 1.f);
    for (;;) {
        const vec3 v(n(rng), n(rng), n(rng));
        const float l = glm::length(v);
        if (l > 1e-3f) return v / l;
    }
}

// Per-axis differences between texel coordinates, modulo the period for periodic fields.
vec2 texel_delta(const Heightfield& f, vec2 a, vec2 b) {
    double dx = std::abs(double(a.x) - b.x), dy = std::abs(double(a.y) - b.y);
    if (f.periodic) {
        dx = std::min(dx, f.width - dx);
        dy = std::min(dy, f.height - dy);
    }
    return vec2(float(dx), float(dy));
}
double texel_distance(const Heightfield& f, vec2 a, vec2 b) { return glm::length(texel_delta(f, a, b)); }

DirectionSet random_directions(int n, uint32_t seed) {
    std::mt19937 rng(seed);
    DirectionSet d;
    for (int i = 0; i < n; ++i) d.d.push_back(random_unit(rng));
    // A few exact axis and grazing directions as well.
    d.d.push_back({1, 0, 0});
    d.d.push_back({0, 0, 1});
    d.d.push_back({0, 0, -1});
    d.d.push_back(glm::normalize(vec3(0.6f, -0.8f, 1e-4f)));
    return d;
}

struct Mismatch {
    int count = 0;
    std::string first;
};

// Compare trace() with trace_brute_force() for one ray.
void compare_ray(const Heightfield& f, vec3 o, vec3 d, Mismatch& m) {
    vec2 a(-1), b(-1);
    const bool ha = trace(f, o, d, a), hb = trace_brute_force(f, o, d, b);
    bool ok = ha == hb;
    if (ok && ha) {
        ok = texel_distance(f, a, b) < 1e-3 && a.x >= 0 && a.y >= 0 && a.x < f.width && a.y < f.height;
        ok = ok && std::isfinite(a.x) && std::isfinite(a.y);
    }
    if (!ok && m.count++ == 0) {
        char buf[512];
        std::snprintf(buf, sizeof buf, "origin (%.9g %.9g %.9g) dir (%.9g %.9g %.9g): trace %d (%.6f %.6f), brute %d (%.6f %.6f)", o.x,
                      o.y, o.z, d.x, d.y, d.z, int(ha), a.x, a.y, int(hb), b.x, b.y);
        m.first = buf;
    }
}

// Random rays from origins on or above the surface.
Mismatch random_rays(const Heightfield& f, int n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    Mismatch m;
    const double cmax = f.periodic ? f.width : f.width - 1, rmax = f.periodic ? f.height : f.height - 1;
    for (int k = 0; k < n; ++k) {
        const double c = u01(rng) * cmax, r = u01(rng) * rmax;
        const double lift = k % 10 == 0 ? 0.0 : 3.0 * u01(rng) * u01(rng);
        const vec3 o = local_point(f, c, r, surface_at(f, c, r) + lift);
        vec3 d = random_unit(rng);
        if (k % 20 == 1) d = glm::normalize(vec3(d.x, d.y, (d.z < 0 ? -1e-4f : 1e-4f) * glm::length(vec2(d.x, d.y))));
        compare_ray(f, o, d, m);
    }
    return m;
}

Heightfield spike_field(bool periodic) {
    return make_field(24, 20, periodic, [](int x, int y) { return x == 10 && y == 10 ? 20.f : 0.f; });
}
Heightfield ridge_field(bool periodic) {
    return make_field(24, 20, periodic, [](int x, int) { return x == 12 ? 6.f : 0.f; });
}

// What compute_visibility must store for direction d at texel (x, y), from the brute force.
uint32_t expected_entry(const Heightfield& f, vec3 d, int x, int y, vec2& hit) {
    const vec3 n = f.normal(x, y);
    if (glm::dot(d, n) <= 0.f) return Visibility::kBelow;
    const vec3 o = f.position(x, y) + 1e-3f * f.texel_size * n;
    return trace_brute_force(f, o, d, hit) ? 0u : Visibility::kNoHit;
}

// [SECTION] Tests
TEST(MicrogeomVisibility, EncodeDecodeRoundTrip) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 4095.f);
    for (int k = 0; k < 10000; ++k) {
        const float c = u(rng), r = u(rng);
        const vec2 q = Visibility::decode(Visibility::encode(c, r));
        EXPECT_LE(std::abs(q.x - c), 1.f / 32.f + 1e-3f);
        EXPECT_LE(std::abs(q.y - r), 1.f / 32.f + 1e-3f);
    }
    EXPECT_EQ(Visibility::decode(Visibility::encode(0.f, 0.f)), vec2(0.f));
    EXPECT_EQ(Visibility::decode(Visibility::encode(12.5f, 3.0625f)), vec2(12.5f, 3.0625f));
    // Out of range clamps instead of wrapping into the other coordinate.
    EXPECT_EQ(Visibility::decode(Visibility::encode(-3.f, 5.f)), vec2(0.f, 5.f));
    EXPECT_EQ(Visibility::encode(1e9f, 0.f) & 0xFFFFu, 0u);
    // The sentinels are never a hit in a field of at most 4095 texels a side.
    EXPECT_LT(Visibility::encode(4094.99f, 4094.99f), Visibility::kBelow);
}

TEST(MicrogeomVisibility, TraceMatchesBruteForceOnRandomFields) {
    struct Case {
        const char* name;
        Heightfield f;
    };
    const std::vector<Case> cases = {
        {"random periodic", random_field(24, 20, true, 11, 3.f)},
        {"random non-periodic", random_field(24, 20, false, 12, 3.f)},
        {"spike periodic", spike_field(true)},
        {"spike non-periodic", spike_field(false)},
        {"ridge periodic", ridge_field(true)},
        {"ridge non-periodic", ridge_field(false)},
    };
    uint32_t seed = 100;
    for (const Case& c : cases) {
        const Mismatch m = random_rays(c.f, 3400, seed++);
        EXPECT_EQ(m.count, 0) << c.name << ": " << m.first;
    }
}

TEST(MicrogeomVisibility, ComputeVisibilityMatchesBruteForce) {
    for (bool periodic : {true, false}) {
        const Heightfield f = random_field(12, 10, periodic, periodic ? 21 : 22, 3.f);
        const DirectionSet dirs = random_directions(32, 5);
        const Visibility vis = compute_visibility(f, dirs);
        ASSERT_EQ(vis.width, 12);
        ASSERT_EQ(vis.height, 10);
        ASSERT_EQ(vis.count, dirs.size());
        ASSERT_EQ(vis.hit.size(), size_t(dirs.size()) * 12 * 10);
        int bad = 0, hits = 0, nohits = 0, below = 0;
        for (int i = 0; i < dirs.size(); ++i)
            for (int y = 0; y < f.height; ++y)
                for (int x = 0; x < f.width; ++x) {
                    vec2 hit(0);
                    const uint32_t want = expected_entry(f, dirs.d[size_t(i)], x, y, hit);
                    const uint32_t got = vis.at(i, x, y);
                    bool ok;
                    if (want == 0u) {
                        ++hits;
                        const vec2 q = Visibility::decode(got);
                        ok = got != Visibility::kNoHit && got != Visibility::kBelow && glm::all(glm::lessThanEqual(texel_delta(f, q, hit), vec2(1.f / 32.f + 1e-3f))) &&
                             q.x < f.width && q.y < f.height;
                    } else {
                        (want == Visibility::kBelow ? below : nohits)++;
                        ok = got == want;
                    }
                    if (!ok && bad++ < 5)
                        ADD_FAILURE() << (periodic ? "periodic" : "non-periodic") << " dir " << i << " texel (" << x << ", " << y << "): got "
                                      << got << " want " << want << " hit (" << hit.x << ", " << hit.y << ")";
                }
        EXPECT_EQ(bad, 0);
        EXPECT_GT(hits, 100);
        EXPECT_GT(nohits, 100);
        EXPECT_GT(below, 100);
    }
}

TEST(MicrogeomVisibility, ProceduralFieldsMatchBruteForce) {
    const DirectionSet dirs = random_directions(12, 15);
    for (const char* name : {"bricks", "vgrooves"}) {
        ProceduralParams p;
        p.name = name;
        p.resolution = 16;
        const Heightfield f = make_procedural(p);
        const Visibility vis = compute_visibility(f, dirs);
        int bad = 0;
        for (int i = 0; i < dirs.size(); ++i)
            for (int y = 0; y < f.height; ++y)
                for (int x = 0; x < f.width; ++x) {
                    vec2 hit(0);
                    const uint32_t want = expected_entry(f, dirs.d[size_t(i)], x, y, hit), got = vis.at(i, x, y);
                    const bool ok = want == 0u ? got < Visibility::kBelow &&
                                                     glm::all(glm::lessThanEqual(texel_delta(f, Visibility::decode(got), hit), vec2(1.f / 32.f + 1e-3f)))
                                               : got == want;
                    if (!ok && bad++ < 3) ADD_FAILURE() << name << " dir " << i << " texel (" << x << ", " << y << "): got " << got << " want " << want;
                }
        EXPECT_EQ(bad, 0) << name;
    }
}

TEST(MicrogeomVisibility, PeriodicWrapHitsTheFarSide) {
    // A tall wall at column 1; a ray from column W-2 going +x leaves the right edge and must hit
    // the wall's slope just after re-entering at the left edge.
    for (bool periodic : {true, false}) {
        const Heightfield f = make_field(24, 20, periodic, [](int x, int) { return x == 1 ? 10.f : 0.f; });
        const vec3 o = local_point(f, 22, 10, 1.0);
        const vec3 d = local_dir(1, 0, 0.01);
        vec2 hit(-1), ref(-1);
        const bool h = trace(f, o, d, hit);
        ASSERT_EQ(h, trace_brute_force(f, o, d, ref));
        if (!periodic) {
            EXPECT_FALSE(h);
            continue;
        }
        ASSERT_TRUE(h);
        // z = 1 + 0.01 (2 + c) meets the slope z = 10 c at c ~ 0.102.
        EXPECT_NEAR(hit.x, 0.1020, 1e-3);
        EXPECT_NEAR(hit.y, 10.0, 1e-4);
        EXPECT_LT(texel_distance(f, hit, ref), 1e-4);
    }
    // The same along the rows: a wall at row 1, a ray from row H-2 going down the image (-y local).
    const Heightfield f = make_field(24, 20, true, [](int, int y) { return y == 1 ? 10.f : 0.f; });
    vec2 hit(-1);
    ASSERT_TRUE(trace(f, local_point(f, 7, 18, 1.0), local_dir(0, 1, 0.01), hit));
    EXPECT_NEAR(hit.x, 7.0, 1e-4);
    EXPECT_NEAR(hit.y, 0.1020, 1e-3);
    EXPECT_GE(hit.y, 0.f);
    // And backwards: from column 3.5 going -x the ray meets the wall's right slope (z = 10 (2 - c))
    // at c = 1.8 directly; from column 0.1 it leaves the left border, wraps to the right edge and
    // goes once round into the same slope.
    const Heightfield g = make_field(24, 20, true, [](int x, int) { return x == 1 ? 10.f : 0.f; });
    for (double start : {3.5, 0.1}) {
        ASSERT_TRUE(trace(g, local_point(g, start, 4, 2.0), local_dir(-1, 0, 0.0), hit)) << start;
        EXPECT_NEAR(hit.x, 1.8, 1e-4) << start;
        EXPECT_NEAR(hit.y, 4.0, 1e-4) << start;
    }
}

TEST(MicrogeomVisibility, PeriodicReachIsCapped) {
    // A horizontal ray at height 1 drifting slowly towards a wall (right slope z = 10 (2 - c) meets
    // z = 1 at c = 1.9) wraps round the rows many times: found within the documented reach of
    // 4 (W + H) = 176 texels of horizontal travel, reported as no hit beyond it.
    const Heightfield f = make_field(24, 20, true, [](int x, int) { return x == 1 ? 10.f : 0.f; });
    for (double travel : {30.0, 150.0, 200.0}) {
        const double a = std::asin(1.1 / travel);
        const vec3 o = local_point(f, 3.0, 5.0, 1.0), d = local_dir(-std::sin(a), std::cos(a), 0.0);
        vec2 hit(-1), ref(-1);
        const bool h = trace(f, o, d, hit);
        EXPECT_EQ(h, trace_brute_force(f, o, d, ref)) << travel;
        EXPECT_EQ(h, travel < 176) << travel;
        if (h) {
            EXPECT_NEAR(hit.x, 1.9, 1e-3) << travel;
            EXPECT_NEAR(hit.y, std::fmod(5.0 + travel * std::cos(a), 20.0), 1e-2) << travel;
            EXPECT_LT(texel_distance(f, hit, ref), 1e-3) << travel;
        }
    }
}

TEST(MicrogeomVisibility, FlatFieldSeesTheSkyOrIsBelow) {
    for (bool periodic : {true, false}) {
        const Heightfield f = make_field(16, 8, periodic, [](int, int) { return 0.5f; });
        const DirectionSet dirs = random_directions(64, 9);
        const Visibility vis = compute_visibility(f, dirs);
        for (int i = 0; i < dirs.size(); ++i)
            for (int y = 0; y < 8; ++y)
                for (int x = 0; x < 16; ++x) {
                    const uint32_t want = dirs.d[size_t(i)].z > 0 ? Visibility::kNoHit : Visibility::kBelow;
                    ASSERT_EQ(vis.at(i, x, y), want) << "dir " << i << " texel " << x << "," << y;
                }
    }
}

TEST(MicrogeomVisibility, ThinRidgeIsNeverSteppedOver) {
    // A one-texel ridge at column 12 (the surface rises from c = 11 to the peak at c = 12, 6 texels
    // high, and falls to c = 13). Rays from both sides aimed at points inside the ridge, steep and
    // grazing, must all hit it before reaching the target.
    for (bool periodic : {true, false}) {
        const Heightfield f = ridge_field(periodic);
        std::mt19937 rng(periodic ? 31 : 32);
        std::uniform_real_distribution<double> u01(0.0, 1.0);
        int misses = 0;
        for (int k = 0; k < 4000; ++k) {
            const bool left = k % 2 == 0;
            const double oc = left ? 1 + 9 * u01(rng) : 14 + 8 * u01(rng), orow = 1 + 17 * u01(rng);
            const double oz = k % 4 < 2 ? 0.01 + 0.2 * u01(rng) : 6 * u01(rng);  // low origins give grazing rays
            const double tc = 12 + (u01(rng) - 0.5) * 1.6, tr = 1 + 17 * u01(rng);
            const double tz = surface_at(f, tc, tr) * (k % 3 == 0 ? 0.999 : u01(rng));
            const vec3 o = local_point(f, oc, orow, oz), t = local_point(f, tc, tr, tz);
            vec2 hit(-1);
            const bool h = trace(f, o, glm::normalize(t - o), hit);
            const bool ok = h && hit.x >= 11.f - 1e-4f && hit.x <= 13.f + 1e-4f &&
                            (left ? hit.x <= tc + 1e-4 : hit.x >= tc - 1e-4);
            if (!ok && misses++ < 5)
                ADD_FAILURE() << "ray " << k << " from (" << oc << ", " << orow << ", " << oz << ") to (" << tc << ", " << tr << ", " << tz
                              << "): hit " << h << " at (" << hit.x << ", " << hit.y << ")";
        }
        EXPECT_EQ(misses, 0);
    }
}

TEST(MicrogeomVisibility, SpikeIsHitWhenAimedAt) {
    const Heightfield f = spike_field(true);
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    int misses = 0;
    for (int k = 0; k < 4000; ++k) {
        const double oc = 10 + (u01(rng) - 0.5) * 16, orow = 10 + (u01(rng) - 0.5) * 16, oz = 25 * u01(rng);
        const double tc = 10 + (u01(rng) - 0.5) * 1.5, tr = 10 + (u01(rng) - 0.5) * 1.5;
        const double tz = surface_at(f, tc, tr) * 0.999 * u01(rng);
        if (std::abs(oc - 10) < 1.5 && std::abs(orow - 10) < 1.5) continue;  // possibly inside the spike
        const vec3 o = local_point(f, oc, orow, oz), t = local_point(f, tc, tr, tz);
        vec2 hit(-1);
        const bool h = trace(f, o, glm::normalize(t - o), hit);
        const bool ok = h && std::abs(hit.x - 10.f) <= 1.f + 1e-4f && std::abs(hit.y - 10.f) <= 1.f + 1e-4f;
        if (!ok && misses++ < 5) ADD_FAILURE() << "ray " << k << ": hit " << h << " at (" << hit.x << ", " << hit.y << ")";
    }
    EXPECT_EQ(misses, 0);
}

TEST(MicrogeomVisibility, GrazingDirectionsTerminateAndAgree) {
    for (bool periodic : {true, false}) {
        const Heightfield f = random_field(24, 20, periodic, periodic ? 51 : 52, 3.f);
        Mismatch m;
        for (int k = 0; k < 96; ++k) {
            const float phi = 2.f * kPi * float(k) / 96.f + 0.1f;
            const float dz = k % 2 ? 1e-4f : -1e-4f;
            const int x = (k * 7) % 24, y = (k * 5) % 20;
            const vec3 n = f.normal(x, y);
            const vec3 d = glm::normalize(vec3(std::cos(phi), std::sin(phi), dz));
            compare_ray(f, f.position(x, y) + 1e-3f * n, d, m);
            // Exactly horizontal, above the whole field: no hit, and no endless walk.
            vec2 hit;
            EXPECT_FALSE(trace(f, local_point(f, x, y, 3.5), vec3(std::cos(phi), std::sin(phi), 0.f), hit));
        }
        EXPECT_EQ(m.count, 0) << m.first;
        DirectionSet dirs;
        for (int k = 0; k < 16; ++k) {
            const float phi = 2.f * kPi * float(k) / 16.f + 0.05f;
            dirs.d.push_back(glm::normalize(vec3(std::cos(phi), std::sin(phi), k % 2 ? 1e-4f : -1e-4f)));
        }
        const Visibility vis = compute_visibility(f, dirs);
        EXPECT_EQ(vis.hit.size(), size_t(16) * 24 * 20);
    }
}

TEST(MicrogeomVisibility, DegenerateFieldsStayFiniteAndTerminate) {
    const DirectionSet dirs = random_directions(48, 61);
    auto check = [&](const Heightfield& f, const char* name) {
        const Visibility vis = compute_visibility(f, dirs);
        ASSERT_EQ(vis.hit.size(), size_t(dirs.size()) * size_t(f.width) * size_t(f.height)) << name;
        for (uint32_t v : vis.hit) {
            if (v == Visibility::kNoHit || v == Visibility::kBelow) continue;
            const vec2 q = Visibility::decode(v);
            ASSERT_TRUE(q.x >= 0 && q.y >= 0 && q.x <= f.width && q.y <= f.height) << name << ": " << q.x << ", " << q.y;
        }
        std::mt19937 rng(3);
        for (int k = 0; k < 300; ++k) {
            vec2 hit(0);
            const vec3 o = local_point(f, 0.5 + (f.width - 2) * (k % 17) / 17.0, 0.5 + (f.height - 2) * (k % 13) / 13.0, 2e4 * (k % 5) / 4.0);
            if (trace(f, o, random_unit(rng), hit)) {
                ASSERT_TRUE(std::isfinite(hit.x) && std::isfinite(hit.y)) << name;
            }
        }
    };
    for (bool periodic : {true, false}) {
        check(make_field(16, 16, periodic, [](int, int) { return 0.f; }), "all zero");
        check(random_field(16, 16, periodic, 62, 1e4f), "heights up to 1e4 texels");
        check(make_field(1, 1, periodic, [](int, int) { return 1.f; }), "one texel");
        check(make_field(5, 1, periodic, [](int x, int) { return float(x); }), "one row");
    }
    // Flat zero field: every upward direction sees the sky.
    const Heightfield z = make_field(16, 16, true, [](int, int) { return 0.f; });
    const Visibility vz = compute_visibility(z, dirs);
    for (int i = 0; i < dirs.size(); ++i)
        EXPECT_EQ(vz.at(i, 3, 4), dirs.d[size_t(i)].z > 0 ? Visibility::kNoHit : Visibility::kBelow);
    // Rays with NaN or zero direction are no hit.
    vec2 hit;
    EXPECT_FALSE(trace(z, vec3(1), vec3(0), hit));
    EXPECT_FALSE(trace(z, vec3(1), vec3(NAN, 0, 1), hit));
    EXPECT_FALSE(trace_brute_force(z, vec3(1), vec3(0), hit));
}

TEST(MicrogeomVisibility, TexelSizeDoesNotChangeTheTextures) {
    const Heightfield a = random_field(12, 10, true, 71, 3.f);
    Heightfield b = a;
    b.texel_size = 0.25f;
    for (float& h : b.h) h *= 0.25f;
    const DirectionSet dirs = random_directions(24, 72);
    EXPECT_EQ(compute_visibility(a, dirs).hit, compute_visibility(b, dirs).hit);
}

TEST(MicrogeomVisibility, ProgressIsReportedAndCancelsAndTheThreadCountChangesNothing) {
    const Heightfield f = random_field(32, 32, true, 81, 3.f);
    const DirectionSet dirs = random_directions(40, 82);
    std::vector<double> seen;
    const Visibility vis = test::with_threads(test::kManyThreads, [&] { return compute_visibility(f, dirs, [&](double p) { seen.push_back(p); }); });
    ASSERT_GE(seen.size(), 2u);
    EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
    EXPECT_GE(seen.front(), 0.0);
    EXPECT_DOUBLE_EQ(seen.back(), 1.0);
    // One thread, without a progress callback: the same entries.
    ASSERT_EQ(vis.hit.size(), size_t(32 * 32) * size_t(dirs.size()));
    EXPECT_EQ(vis.hit, test::with_threads(1, [&] { return compute_visibility(f, dirs); }).hit);
    int calls = 0;
    EXPECT_THROW(compute_visibility(f, dirs,
                                    [&](double p) {
                                        ++calls;
                                        if (p > 0.25) throw Cancelled();
                                    }),
                 Cancelled);
    EXPECT_LT(calls, int(seen.size()));
}
}  // namespace
