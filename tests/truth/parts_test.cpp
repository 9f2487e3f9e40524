// Truths in parts and to a noise target (core/truth/truth.h): sums kept exactly, so that parts of
// any split, merged in any order, are the bytes of the truth rendered at once (a path-traced scene
// and a translucent one, whose photon batches are per sample); merging refuses parts of another
// scene, seed, size or build, overlaps and gaps, and a bad file, each by name; a noise target stops
// at the noise and says so, a time limit stops in time, and both continue a cached truth.
#include "core/truth/cache.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/file.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/truth/truth.h"
#include "support/cli.h"
#include "support/truth.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

using namespace mesolab;

namespace {
Scene basic_scene() {
    const std::string text = R"({"schema": 1, "name": "parts-basic", "camera": {"mode": "orbit", "distance": 3.0, "orbit": [50, -60], "fov": 40},
        "lights": [{"type": "directional", "direction": [40, 10], "intensity": 2, "color": [1, 0.9, 0.8]}],
        "env": {"color": [1, 1, 1], "intensity": 0.4}, "effects": {"environment": true},
        "objects": [{"name": "torus", "geometry": {"type": "torus", "resolution": 32}, "material": {"technique": "basic", "kd": [0.8, 0.6, 0.4], "ks": [0.2, 0.2, 0.2]}}]})";
    return scene_from_json(nlohmann::json::parse(text), "parts-basic", test::source_path("presets"));
}

Scene translucent_scene() {
    const std::string text = R"({"schema": 1, "name": "parts-translucent", "camera": {"mode": "orbit", "distance": 4.0, "orbit": [60, -60], "fov": 40},
        "lights": [{"type": "point", "position": [2, 1, 2], "intensity": 8, "color": [1, 1, 1]}],
        "env": {"color": [1, 1, 1], "intensity": 0.3}, "effects": {"environment": true},
        "objects": [{"name": "ball", "geometry": {"type": "sphere", "resolution": 12}, "material": {"technique": "translucency", "material": "custom",
        "mm_per_unit": 1, "sigma_s": [1, 2, 4], "sigma_a": [0.1, 0.1, 0.1], "eta": 1.3}}]})";
    return scene_from_json(nlohmann::json::parse(text), "parts-translucent", test::source_path("presets"));
}

constexpr int kSize = 16;

// Samples [first, end) of `s` as a part.
TruthPart part(const Scene& s, int first, int end, uint64_t seed = 5) {
    Session session;
    const Evaluation ev = session.evaluate(s, truth_stages(s));
    TruthSettings st;
    st.first = first, st.spp = end, st.seed = seed;
    TruthPart p;
    p.scene = s.name;
    p.key = truth_cache_key(version_string(), s, kSize, kSize, seed);
    p.build = truth_build(version_string());
    p.sums = accumulate_truth(s, ev, kSize, kSize, st);
    return p;
}

void expect_same_bytes(const TruthAccumulator& a, const TruthAccumulator& b, const std::string& what) {
    EXPECT_EQ(a.first, b.first) << what;
    EXPECT_EQ(a.spp, b.spp) << what;
    EXPECT_TRUE(a.sum == b.sum) << what;
    EXPECT_TRUE(a.sum2 == b.sum2) << what;
    EXPECT_TRUE(a.exitance == b.exitance) << what;
    EXPECT_TRUE(a.irradiance == b.irradiance) << what;
    EXPECT_EQ(a.normal, b.normal) << what;
    const Frame fa = truth_frame(a), fb = truth_frame(b);
    for (const std::string& aov : truth_aovs()) EXPECT_EQ(fa.aov(aov).data, fb.aov(aov).data) << what << ", " << aov;
}

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}
}  // namespace

// Exact sums: rounding each sample once to 2^-64 and adding integers is associative.
TEST(TruthParts, FixedPointSumsDoNotDependOnTheOrderOfAdditions) {
    std::mt19937_64 rng(9);
    std::lognormal_distribution<double> L(0.0, 4.0);
    std::vector<double> v(2000);
    for (double& x : v) x = L(rng) * (rng() % 2 ? 1.0 : -1.0);
    TruthFixed forward = 0, backward = 0;
    for (double x : v) forward += to_fixed(x);
    for (auto it = v.rbegin(); it != v.rend(); ++it) backward += to_fixed(*it);
    std::shuffle(v.begin(), v.end(), rng);
    TruthFixed shuffled = 0;
    for (double x : v) shuffled += to_fixed(x);
    EXPECT_TRUE(forward == backward);
    EXPECT_TRUE(forward == shuffled);
    double exact = 0.0;
    for (double x : v) exact += x;
    EXPECT_NEAR(from_fixed(forward), exact, 1e-9 * std::fabs(exact) + 1e-12);
    EXPECT_EQ(from_fixed(to_fixed(0.375)), 0.375);
    EXPECT_TRUE(to_fixed(std::nan("")) == 0);
    EXPECT_EQ(from_fixed(to_fixed(1e300)), 0x1p62);  // clamped
}

// Parts of any split, merged in any order, are the bytes of the truth rendered at once (and of
// one continued from fewer samples): a path-traced scene and a translucent one.
TEST(TruthParts, PartsMergedInAnyOrderAreTheBytesOfOneRender) {
    for (const Scene& s : {basic_scene(), translucent_scene()}) {
        const TruthPart whole = part(s, 0, 11);
        const std::vector<std::pair<int, int>> split = {{0, 3}, {3, 4}, {4, 9}, {9, 11}};
        std::vector<std::pair<std::string, TruthPart>> parts;
        for (const auto& [a, b] : split) parts.emplace_back("part " + std::to_string(a) + ":" + std::to_string(b), part(s, a, b));
        std::reverse(parts.begin(), parts.end());
        std::swap(parts[1], parts[2]);
        const TruthPart merged = merge_truth_parts(parts);
        expect_same_bytes(merged.sums, whole.sums, s.name + ", merged");
        // Continued from 3 samples to 11, in one process.
        Session session;
        const Evaluation ev = session.evaluate(s, truth_stages(s));
        TruthSettings st;
        st.seed = 5, st.spp = 3;
        const TruthAccumulator three = accumulate_truth(s, ev, kSize, kSize, st);
        st.spp = 11;
        expect_same_bytes(accumulate_truth(s, ev, kSize, kSize, st, &three), whole.sums, s.name + ", continued");
        double most = 0.0;
        const Frame frame = truth_frame(whole.sums);
        for (float v : frame.aov("radiance").data) most = std::max(most, double(v));
        EXPECT_GT(most, 0.0) << s.name;
    }
}

// A part written to disk reads back the same; a truncated, foreign or trailing file is refused by
// name; merging refuses another scene, seed, size or build, an overlap and a gap, naming both parts.
TEST(TruthParts, MergeRefusesWhatIsNotOneTruthAndBadFilesByName) {
    const Scene s = basic_scene();
    test::TempDir dir("truth-parts");
    const TruthPart a = part(s, 0, 2), b = part(s, 2, 4);
    const std::string pa = dir.path.string() + "/a.truth";
    write_truth_part(pa, a);
    const TruthPart back = read_truth_part(pa);
    EXPECT_EQ(back.scene, a.scene);
    EXPECT_EQ(back.key, a.key);
    EXPECT_EQ(back.build, a.build);
    expect_same_bytes(back.sums, a.sums, "read back");

    std::string bytes;
    {
        std::ifstream in(pa, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    write_text_atomic(dir.path.string() + "/short.truth", bytes.substr(0, bytes.size() / 2));
    EXPECT_NE(error_of([&] { read_truth_part(dir.path.string() + "/short.truth"); }).find("short.truth: truncated"), std::string::npos);
    write_text_atomic(dir.path.string() + "/long.truth", bytes + "x");
    EXPECT_NE(error_of([&] { read_truth_part(dir.path.string() + "/long.truth"); }).find("bytes follow the end"), std::string::npos);
    write_text_atomic(dir.path.string() + "/preset.truth", R"({"schema": 1})");
    EXPECT_NE(error_of([&] { read_truth_part(dir.path.string() + "/preset.truth"); }).find("preset.truth: not a partial truth"), std::string::npos);
    EXPECT_NE(error_of([&] { read_truth_part(dir.path.string() + "/missing.truth"); }).find("missing.truth"), std::string::npos);

    auto refused = [&](TruthPart other, const std::string& words) {
        const std::string m = error_of([&] { merge_truth_parts({{"first.truth", a}, {"second.truth", other}}); });
        EXPECT_NE(m.find(words), std::string::npos) << m;
        EXPECT_NE(m.find("second.truth"), std::string::npos) << m;
    };
    TruthPart other_scene = b;
    other_scene.scene = "another";
    refused(other_scene, "the scene differs");
    refused(part(s, 2, 4, 6), "the seed differs");
    TruthPart other_build = b;
    other_build.build += " (another)";
    refused(other_build, "the build differs");
    TruthPart other_key = b;
    other_key.key = "0123456789abcdef";
    refused(other_key, "what the truth reads");
    refused(part(s, 1, 3), "overlaps");
    refused(part(s, 3, 5), "leave a gap: samples 2:3 are missing");
    {
        Session session;
        const Evaluation ev = session.evaluate(s, truth_stages(s));
        TruthSettings st;
        st.first = 2, st.spp = 4, st.seed = 5;
        TruthPart small = b;
        small.sums = accumulate_truth(s, ev, 8, 8, st);
        refused(small, "the size differs");
    }
    EXPECT_NE(error_of([] { merge_truth_parts({}); }).find("no partial truths"), std::string::npos);
}

// A noise target samples until noise_rel reaches it (from 16 samples on), says so, and continues
// a cached truth; a time limit stops within a block of its limit and says so.
TEST(TruthNoise, ANoiseTargetStopsThereAndATimeLimitStopsInTime) {
    const Scene s = basic_scene();
    Session session;
    const Evaluation ev = session.evaluate(s, truth_stages(s));
    TruthSettings st;
    st.seed = 2, st.spp = 1 << 20, st.noise = 0.05;
    const TruthAccumulator a = accumulate_truth(s, ev, kSize, kSize, st);
    EXPECT_EQ(a.ended, TruthEnd::Noise);
    EXPECT_GE(a.samples(), kNoiseMinSpp);
    EXPECT_LE(truth_noise_rel(a), 0.05);
    EXPECT_NEAR(truth_noise_rel(a), truth_noise_rel(truth_frame(a)), 1e-12);
    // One block fewer would not have reached it (it stops at the first block that does).
    if (a.spp > kNoiseMinSpp) {
        TruthSettings fewer = st;
        fewer.noise = 0, fewer.spp = a.spp - kTruthBlock;
        EXPECT_GT(truth_noise_rel(accumulate_truth(s, ev, kSize, kSize, fewer)), 0.05);
    }
    // Continued to a lower noise: the samples so far are kept.
    TruthSettings lower = st;
    lower.noise = 0.03;
    const TruthAccumulator b = accumulate_truth(s, ev, kSize, kSize, lower, &a);
    EXPECT_EQ(b.ended, TruthEnd::Noise);
    EXPECT_GT(b.spp, a.spp);
    TruthSettings same = st;
    same.noise = 0, same.spp = b.spp;
    EXPECT_TRUE(accumulate_truth(s, ev, kSize, kSize, same).sum == b.sum);
    // Reached already: nothing rendered.
    EXPECT_EQ(accumulate_truth(s, ev, kSize, kSize, st, &b).spp, b.spp);
    // A time limit shorter than a block: one block, then it stops.
    TruthSettings quick = st;
    quick.noise = 1e-6, quick.time_limit_s = 1e-9;
    const TruthAccumulator c = accumulate_truth(s, ev, kSize, kSize, quick);
    EXPECT_EQ(c.ended, TruthEnd::TimeLimit);
    EXPECT_EQ(c.spp, kTruthBlock);
    // Bad settings are errors naming the option.
    TruthSettings bad = st;
    bad.noise = 2.0;
    EXPECT_NE(error_of([&] { check_truth_request(s, kSize, kSize, bad, {}); }).find("--noise 2"), std::string::npos);
    bad = st, bad.first = 5, bad.spp = 5;
    EXPECT_NE(error_of([&] { check_truth_request(s, kSize, kSize, bad, {}); }).find("--samples 5:5"), std::string::npos);
}

// Through the workbench: a noise target continues the cached truth, and the result says what ended it.
TEST(TruthNoise, TheWorkbenchContinuesTheCachedTruthToTheTarget) {
    const Scene s = basic_scene();
    test::TempDir dir("truth-noise-cache");
    Workbench wb;
    wb.set_truth_cache(dir.path.string());
    RenderRequest req = test::truth_request("truth", kSize, 8, {"truth_stderr"}, 4);
    const RenderResult eight = wb.render(s, req);
    EXPECT_EQ(eight.sampled->spp, 8);
    EXPECT_EQ(eight.sampled->ended, TruthEnd::Samples);
    req.truth.spp = 1 << 20, req.truth.noise = 0.05;
    const RenderResult target = wb.render(s, req);
    EXPECT_EQ(target.sampled->cached_spp, 8);
    EXPECT_EQ(target.sampled->ended, TruthEnd::Noise);
    EXPECT_LE(truth_noise_rel(target.frame), 0.05);
    const RenderResult again = wb.render(s, req);
    EXPECT_EQ(again.sampled->cached_spp, target.sampled->spp);  // nothing rendered
    EXPECT_EQ(again.frame.aov("radiance").data, target.frame.aov("radiance").data);
}
