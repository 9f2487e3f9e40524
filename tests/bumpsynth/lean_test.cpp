// bumpsynth's method lean (core/bumpsynth/lean.h): LEAN mapping of the synthesised bumps. Its mip
// levels hold exactly the moments of the finest texels under them; over a footprint its lobe is the
// histogram of the baked normals there (the bumps drawn from a Beckmann NDF have Gaussian slopes);
// a flat map gives the base lobe, the NDF's own Beckmann; the lobe is normalised; CPU and GPU
// frames agree; only its stages run, and its keys are errors under the paper's method.
#include "core/bumpsynth/lean.h"
#include "core/bumpsynth/ndf.h"
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/technique.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/technique.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace mesolab;
using namespace mesolab::bumpsynth;

namespace {
Scene fig1(std::initializer_list<std::pair<const char*, const char*>> sets) {
    Scene s = load_preset(test::source_path("presets/bumpsynth/fig1-sphere-distances.json"));
    apply_set(s, "bumpsynth.method", "lean");
    for (const auto& [k, v] : sets) apply_set(s, k, v);
    return s;
}

// The evaluation of a small CPU frame of `s` (its stages).
RenderResult evaluate(Workbench& wb, const Scene& s) {
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 32;
    return wb.render(s, req);
}

// A smooth periodic bump field with slopes up to ~0.6 and detail at several scales.
vec3 wavy(vec2 uv) {
    const float t = 2.f * kPi;
    const float bx = 0.4f * std::sin(t * 3.f * uv.x) + 0.2f * std::cos(t * 17.f * (uv.x + uv.y));
    const float by = 0.3f * std::cos(t * 5.f * uv.y) + 0.15f * std::sin(t * 29.f * uv.x);
    return glm::normalize(vec3(bx, by, 1.f));
}
}  // namespace

// Every level's texel holds the mean of the finest texels under it (the moments filter linearly),
// and bilinear look-ups at texel centres return the texels.
TEST(BumpsynthLean, MipLevelsHoldTheMomentsOfTheTexelsUnderThem) {
    const LeanMap map = LeanMap::bake(wavy, 64, 2, vec3(0.f));
    ASSERT_EQ(map.levels.size(), 7u);
    const LeanMap::Level& l0 = map.levels[0];
    for (size_t l = 1; l < map.levels.size(); ++l) {
        const LeanMap::Level& L = map.levels[l];
        const int span = 64 / L.n;
        for (int y = 0; y < L.n; y += std::max(1, L.n / 4))
            for (int x = 0; x < L.n; x += std::max(1, L.n / 4)) {
                glm::dvec4 a(0.0), b(0.0);
                for (int j = 0; j < span; ++j)
                    for (int i = 0; i < span; ++i) {
                        const size_t k = size_t(y * span + j) * 64 + size_t(x * span + i);
                        a += glm::dvec4(l0.a[k]), b += glm::dvec4(l0.b[k]);
                    }
                a /= double(span * span), b /= double(span * span);
                const vec4 ga = L.a[size_t(y) * size_t(L.n) + size_t(x)], gb = L.b[size_t(y) * size_t(L.n) + size_t(x)];
                for (int c = 0; c < 4; ++c) {
                    EXPECT_NEAR(ga[c], a[c], 1e-5 + 1e-5 * std::fabs(a[c])) << "level " << l << " texel " << x << "," << y;
                    EXPECT_NEAR(gb[c], b[c], 1e-5 + 1e-5 * std::fabs(b[c])) << "level " << l << " texel " << x << "," << y;
                }
                // The texel's centre, looked up.
                const vec2 uv((float(x) + 0.5f) / float(L.n), 1.f - (float(y) + 0.5f) / float(L.n));
                const LeanMoments mo = map.at_level(int(l), uv);
                EXPECT_NEAR(mo.B.x, ga.x, 1e-6);
                EXPECT_NEAR(mo.M.z, gb.x, 1e-6);
            }
    }
    // Supersampling puts detail finer than a texel into its second moments: M - B² > 0 at level 0.
    double var = 0.0;
    for (size_t k = 0; k < l0.a.size(); ++k) var += l0.a[k].z - l0.a[k].x * l0.a[k].x;
    EXPECT_GT(var / double(l0.a.size()), 1e-4);
}

// Over a footprint, the lobe is the histogram of the baked normals there: the synthesised bumps of a
// Beckmann NDF have Gaussian slopes of the NDF's covariance, so the map's coarsest level (the whole
// map) has mean slope ~0, the NDF's covariance, and its Gaussian matches the histogram of the finest
// level's slopes bin by bin (total variation over a 16 x 16 grid of slope bins).
TEST(BumpsynthLean, TheLobeOverAFootprintIsTheHistogramOfItsNormals) {
    Workbench wb;
    const Scene s = fig1({{"bumpsynth.lean_size", "256"}, {"bumpsynth.lean_supersample", "1"}});
    const RenderResult r = evaluate(wb, s);
    const auto map = r.eval.get(stages::lean_map, 0);
    ASSERT_TRUE(map);
    const vec3 sigma = map->sigma0;  // the NDF's covariance
    const LeanMoments top = map->at_level(int(map->levels.size()) - 1, vec2(0.5f));
    const double cxx = top.M.x - top.B.x * top.B.x, cyy = top.M.y - top.B.y * top.B.y, cxy = top.M.z - top.B.x * top.B.y;
    const double scale = std::sqrt(sigma.x + sigma.y);
    EXPECT_LT(std::fabs(top.B.x), 0.05 * scale);
    EXPECT_LT(std::fabs(top.B.y), 0.05 * scale);
    EXPECT_NEAR(cxx, sigma.x, 0.08 * sigma.x);
    EXPECT_NEAR(cyy, sigma.y, 0.08 * sigma.y);
    EXPECT_NEAR(cxy, sigma.z, 0.08 * std::sqrt(sigma.x * sigma.y));

    // Histogram of the finest level's slopes against the top level's Gaussian, over ±3 σ.
    const LeanMap::Level& l0 = map->levels[0];
    constexpr int kBins = 16;
    const double wx = 6.0 * std::sqrt(cxx) / kBins, wy = 6.0 * std::sqrt(cyy) / kBins;
    std::vector<double> hist(kBins * kBins, 0.0);
    for (const vec4& a : l0.a) {
        const int i = int(std::floor((a.x - top.B.x) / wx + kBins / 2.0)), j = int(std::floor((a.y - top.B.y) / wy + kBins / 2.0));
        if (i >= 0 && i < kBins && j >= 0 && j < kBins) hist[size_t(j * kBins + i)] += 1.0 / double(l0.a.size());
    }
    const double det = cxx * cyy - cxy * cxy;
    double tv = 0.0;
    for (int j = 0; j < kBins; ++j)
        for (int i = 0; i < kBins; ++i) {
            double p = 0.0;  // the Gaussian's mass in the bin (4 x 4 midpoint rule)
            for (int b = 0; b < 4; ++b)
                for (int a = 0; a < 4; ++a) {
                    const double dx = (i - kBins / 2 + (a + 0.5) / 4.0) * wx, dy = (j - kBins / 2 + (b + 0.5) / 4.0) * wy;
                    p += std::exp(-0.5 * (cyy * dx * dx - 2.0 * cxy * dx * dy + cxx * dy * dy) / det) / (2.0 * kPi * std::sqrt(det)) * wx * wy / 16.0;
                }
            tv += 0.5 * std::fabs(p - hist[size_t(j * kBins + i)]);
        }
    EXPECT_LT(tv, 0.06) << "total variation between the baked slopes' histogram and the lobe";
}

// A flat map has no moments at any level, and its lobe is the NDF's own: for a Beckmann NDF
// (α 0.2 x 0.5, rotated 30°), Σ0 is the rotated diag(α²/2) and D the closed form.
TEST(BumpsynthLean, AFlatMapGivesTheBaseLobe) {
    const Lobe beckmann = Lobe::anisotropic(LobeKind::beckmann, 0.2f, 0.5f, 30.f);
    const Ndf ndf = Ndf::from_lobe(beckmann, 512);
    const vec3 s0 = slope_covariance(ndf);
    const double c = std::cos(30.0 * kPi / 180.0), sn = std::sin(30.0 * kPi / 180.0);
    const double a = 0.02, b = 0.125;  // α²/2
    EXPECT_NEAR(s0.x, c * c * a + sn * sn * b, 0.02 * b);
    EXPECT_NEAR(s0.y, sn * sn * a + c * c * b, 0.02 * b);
    EXPECT_NEAR(s0.z, c * sn * (a - b), 0.02 * b);

    const LeanMap map = LeanMap::bake([](vec2) { return vec3(0, 0, 1); }, 16, 1, s0);
    for (const LeanMap::Level& l : map.levels)
        for (size_t k = 0; k < l.a.size(); ++k) {
            ASSERT_EQ(l.a[k], vec4(0.f));
            ASSERT_EQ(l.b[k], vec4(0, 0, 0, 1));
        }
    const LeanMoments mo = map.filter(vec2(0.3f, 0.7f), vec2(0.01f, 0.f), vec2(0.f, 0.003f), 4);
    const LeanLobe lobe(mo, map.sigma0);
    for (float th : {0.f, 0.1f, 0.2f, 0.35f})
        for (float ph : {0.f, 1.f, 2.5f, 4.f}) {
            const vec3 h(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
            const double want = beckmann.D(h);
            EXPECT_NEAR(lobe.D(h), want, 0.03 * want + 1e-4) << "theta " << th << " phi " << ph;
        }
}

// ∫ D(h) h_z dω = 1 for the lobe, off-centre and correlated (the Gaussian in slope space is normalised).
TEST(BumpsynthLean, TheLobeIsNormalised) {
    LeanMoments mo;
    mo.B = vec2(0.15f, -0.1f);
    mo.M = vec3(0.15f * 0.15f + 0.02f, 0.01f + 0.01f, -0.015f + 0.005f);
    const LeanLobe lobe(mo, vec3(0.01f, 0.02f, 0.003f));
    // Over the slope plane via h = normalize(-s...): dω = ds / (1 + |s|²)^{3/2}, h_z = 1/√(1 + |s|²).
    double sum = 0.0;
    const int n = 800;
    const double L = 2.5, d = 2.0 * L / n;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double sx = -L + (i + 0.5) * d, sy = -L + (j + 0.5) * d;
            const double q = 1.0 + sx * sx + sy * sy;
            const vec3 h = glm::normalize(vec3(float(sx), float(sy), 1.f));
            sum += double(lobe.D(h)) * double(h.z) * d * d / std::pow(q, 1.5);
        }
    EXPECT_NEAR(sum, 1.0, 2e-3);
}

// The CPU reference and the GPU pass agree, with content in both frames: near (the finest level
// magnified), at the preset's distance, far (the coarse levels), with masking and Fresnel, isotropic.
TEST(BumpsynthLean, CpuAndGpuFramesAgree) {
    Workbench wb;
    const std::vector<std::pair<std::string, Scene>> cases = {
        {"near", fig1({{"camera.distance", "1.2"}, {"bumpsynth.lean_size", "256"}})},
        {"preset distance", fig1({{"bumpsynth.lean_size", "256"}})},
        {"far", fig1({{"camera.distance", "12"}, {"bumpsynth.lean_size", "256"}})},
        {"masking, fresnel, isotropic", fig1({{"bumpsynth.masking", "true"}, {"bumpsynth.fresnel", "true"}, {"bumpsynth.lean_anisotropy", "1"},
                                               {"bumpsynth.lean_size", "128"}})},
    };
    for (const auto& [name, s] : cases) {
        SCOPED_TRACE(name);
        const auto [cpu, gpu] = test::render_cpu_and_gpu(wb, s, 160, 120, {"radiance", "normal"});
        test::expect_frames_agree(s, cpu, gpu, {"radiance", "normal"});
    }
}

// Only the stages a method reads run: the LEAN map for lean objects, the paper's NDF table and
// look-up table for the paper's; in one scene with both, each for its own object. The truth's NDF,
// which LEAN bakes from, serves both (one truth for every method).
TEST(BumpsynthLean, EachMethodRunsOnlyItsStages) {
    Scene s = load_preset(test::source_path("presets/bumpsynth/fig1-sphere-distances.json"));
    SceneObject second = s.objects[0];
    second.name = "lean";
    second.material.set("method", std::string("lean"));
    second.material.set("lean_size", int64_t(64));
    second.geometry.set("position", std::array<double, 3>{1.5, 0.0, 0.0});
    s.objects.push_back(second);
    Workbench wb;
    const RenderResult r = evaluate(wb, s);
    EXPECT_TRUE(r.eval.get(stages::lut, 0));
    EXPECT_FALSE(r.eval.get(stages::lut, 1)) << "the paper's look-up table for the lean object";
    EXPECT_FALSE(r.eval.get(stages::ndf, 1)) << "the paper's NDF table for the lean object";
    EXPECT_FALSE(r.eval.get(stages::lean_map, 0)) << "a LEAN map for the paper's object";
    EXPECT_TRUE(r.eval.get(stages::lean_map, 1));
    const StageDecl& truth_ndf = Registry::instance().stages().at(std::string(stages::truth_ndf));
    EXPECT_TRUE(truth_ndf.methods.empty()) << "the truth's NDF serves every method";
}

// lean's keys are used only under it and the paper's table sizes only under the paper's; a size
// that is not a power of two is refused, naming the key.
TEST(BumpsynthLean, KeysOfAnotherMethodAndBadSizesAreErrors) {
    const auto refused = [](std::initializer_list<std::pair<const char*, const char*>> sets, const std::string& key) {
        try {
            Scene s = load_preset(test::source_path("presets/bumpsynth/fig1-sphere-distances.json"));
            std::vector<std::string> a;
            for (const auto& [k, v] : sets) a.push_back(std::string(k) + "=" + v);
            apply_sets(s, a);
            Workbench wb;
            evaluate(wb, s);
            ADD_FAILURE() << key << " was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
        }
    };
    refused({{"bumpsynth.lean_size", "256"}}, "lean_size");
    refused({{"bumpsynth.method", "lean"}, {"bumpsynth.lut_size", "512"}}, "lut_size");
    refused({{"bumpsynth.method", "lean"}, {"bumpsynth.lean_size", "500"}}, "bumpsynth.lean_size");
    EXPECT_EQ(Registry::instance().technique("bumpsynth")->method_names(), (std::vector<std::string>{"kautz", "lean", "kautz-consistent"}));
}
