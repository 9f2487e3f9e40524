// The accuracy-time frontier (app/api.h, frontier_scene; `mesolab frontier`): the lower envelope
// is the one no faster point beats; every setting is measured against the truth of its distance
// (one per physical description), with the grid around the preset and the diagonal; files and
// plots per distance; the budget and bad input.
#include "app/api.h"
#include "app/commands.h"
#include "app/gui/frontier_view.h"
#include "core/error.h"
#include "core/scene.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <chrono>
#include <limits>
#include <thread>

using namespace mesolab;

namespace {
FrontierPoint point(double d, double ms, double err) {
    FrontierPoint p;
    p.distance = d, p.frame_ms = ms, p.rmse_rel = err;
    return p;
}

FrontierOptions small() {
    FrontierOptions o;
    o.width = o.height = 32;
    o.truth.spp = 8;
    o.repeat = 1;
    o.quiet = true;
    return o;
}
}  // namespace

TEST(Frontier, TheEnvelopeIsWhatNoFasterPointBeats) {
    std::vector<FrontierPoint> p = {point(1, 1.0, 0.5), point(1, 2.0, 0.6), point(1, 3.0, 0.2), point(1, 0.5, 0.9), point(1, 4.0, 0.2),
                                    point(2, 2.0, 0.8), point(2, 1.0, 0.1)};
    mark_frontier(p);
    EXPECT_TRUE(p[0].on_frontier);
    EXPECT_FALSE(p[1].on_frontier) << "slower and worse than a point before it";
    EXPECT_TRUE(p[2].on_frontier);
    EXPECT_TRUE(p[3].on_frontier) << "the fastest is always on it";
    EXPECT_FALSE(p[4].on_frontier) << "as accurate as a faster one";
    EXPECT_TRUE(p[6].on_frontier);
    EXPECT_FALSE(p[5].on_frontier) << "each distance has its own frontier";
}

TEST(Frontier, EverySettingIsMeasuredAgainstItsDistancesTruth) {
    const Scene s = load_preset(test::source_path("presets/basic/sphere.json"));
    FrontierOptions o = small();
    o.distances = {3.0, 8.0};
    test::TempDir dir("frontier");
    o.out_dir = dir.path.string();
    const FrontierResult r = frontier_scene(s, o, true);
    EXPECT_EQ(r.knobs, std::vector<std::string>{"geometry.resolution"});
    ASSERT_GE(r.points.size(), 10u) << "the preset and four steps of its one knob, at two distances, then refinements";
    ASSERT_EQ(r.truth_noise.size(), 2u);
    for (double n : r.truth_noise) EXPECT_GT(n, 0.0);
    for (size_t d = 0; d < 2; ++d) {
        double best = std::numeric_limits<double>::infinity();
        std::vector<const FrontierPoint*> at;
        for (const auto& p : r.points)
            if (p.distance == o.distances[d]) at.push_back(&p);
        ASSERT_GE(at.size(), 5u);
        EXPECT_EQ(at.front()->varied, "preset");
        for (size_t i = 5; i < at.size(); ++i) EXPECT_EQ(at[i]->varied.rfind("between ", 0), 0u) << at[i]->varied;
        std::sort(at.begin(), at.end(), [](auto* a, auto* b) { return a->frame_ms < b->frame_ms; });
        for (const FrontierPoint* p : at) {
            EXPECT_GT(p->frame_ms, 0.0);
            EXPECT_GE(p->precompute_ms, 0.0);
            EXPECT_TRUE(std::isfinite(p->rmse_rel) && p->rmse_rel > 0.0);
            EXPECT_EQ(p->on_frontier, p->rmse_rel < best) << p->varied;
            best = std::min(best, p->rmse_rel);
        }
    }
    // The coarsest tessellation is further from the truth than the finest, near.
    double coarse = 0, fine = 0;
    for (const auto& p : r.points)
        if (p.distance == 3.0) {
            if (p.varied == "all x0.25") coarse = p.rmse_rel;
            if (p.varied == "all x4") fine = p.rmse_rel;
        }
    EXPECT_GT(coarse, fine);
    for (const char* f : {"basic-sphere.frontier.md", "basic-sphere.frontier.csv", "basic-sphere.frontier.json", "basic-sphere.frontier.d3.png",
                          "basic-sphere.frontier.d8.svg"})
        EXPECT_TRUE(std::filesystem::exists(dir.path / f)) << f;
    const nlohmann::json j = nlohmann::json::parse(test::slurp(dir / "basic-sphere.frontier.json"));
    EXPECT_EQ(j["points"].size(), r.points.size());
    EXPECT_EQ(j["points"][0]["knobs"]["geometry.resolution"], "96");
}

// A knob declared as taking only powers of two (a texture's size) gets only those, on the grid
// and between neighbours, so no setting is refused by its stage.
TEST(Frontier, PowerOfTwoKnobsGetOnlyPowersOfTwo) {
    Scene s = load_preset(test::source_path("presets/bumpsynth/lean-sphere-far.json"));
    for (const char* set : {"bumpsynth.lean_size=32", "bumpsynth.lean_supersample=1", "bumpsynth.octaves_max=3", "geometry.resolution=24"}) apply_set(s, set);
    FrontierOptions o = small();
    o.width = o.height = 24;
    o.truth.spp = 4;
    const FrontierResult r = frontier_scene(s, o, false);
    EXPECT_TRUE(r.skipped.empty()) << r.skipped.front();
    int lean = 0;
    for (const FrontierPoint& p : r.points)
        for (const auto& [key, value] : p.settings)
            if (key == "bumpsynth.lean_size") {
                const long n = std::stol(value);
                EXPECT_TRUE(n > 0 && (n & (n - 1)) == 0) << p.varied << ": " << value;
                ++lean;
            }
    EXPECT_GT(lean, 6);
}

TEST(Frontier, TheBudgetLeavesOnlyThePresetAndBadInputIsSaid) {
    const Scene s = load_preset(test::source_path("presets/basic/sphere.json"));
    FrontierOptions o = small();
    o.budget_s = 0;
    const FrontierResult r = frontier_scene(s, o, false);
    ASSERT_EQ(r.points.size(), 1u);
    EXPECT_EQ(r.points[0].varied, "preset");
    EXPECT_TRUE(r.budget_reached);
    o.backend = "truth";
    EXPECT_THROW(frontier_scene(s, o, false), InputError);
    o.backend = "cpu";
    Scene tex = load_preset(test::source_path("presets/basic/plane-texture.json"));
    o.distances = {2.0};
    try {
        frontier_scene(tex, o, false);
        ADD_FAILURE() << "--distance on a texture-space camera was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("camera.mode"), std::string::npos) << e.what();
    }
}

TEST(Frontier, TheCommandWritesItsTableAndPlots) {
    test::TempDir dir("frontier-cli");
    const test::CliResult r = test::run_mesolab("frontier presets/basic/sphere.json --size 24x24 --spp 4 --repeat 1 --budget 0 -o '" + dir.path.string() + "'");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("| 3.2 | basic | `preset` |"), std::string::npos) << r.out;
    EXPECT_TRUE(std::filesystem::exists(dir.path / "basic-sphere.frontier.png"));
    const test::CliResult bad = test::run_mesolab("frontier presets/basic/sphere.json --backend truth -o '" + dir.path.string() + "'");
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("real-time renderer"), std::string::npos) << bad.err;
}

// The window's worker: the points arrive as they are measured, the frontier marked among them;
// cancel keeps what was measured; a bad scene is said in the status.
TEST(FrontierView, PointsArriveMarkedAndCancelKeepsThem) {
    using namespace std::chrono_literals;
    const Scene s = load_preset(test::source_path("presets/basic/sphere.json"));
    gui::FrontierRunner r;
    FrontierOptions o = small();
    r.start(s, o);
    ASSERT_TRUE(r.wait_idle(120s));
    const std::vector<FrontierPoint> all = r.points();
    ASSERT_GE(all.size(), 5u);
    EXPECT_TRUE(std::any_of(all.begin(), all.end(), [](const FrontierPoint& p) { return p.on_frontier; }));
    EXPECT_GT(r.status().truth_noise, 0.0);
    EXPECT_TRUE(r.status().error.empty()) << r.status().error;
    o.width = o.height = 256;
    o.repeat = 100;  // slow enough to be cancelled part-way: a setting takes a good part of a second
    r.start(s, o);
    for (int i = 0; i < 2000 && r.points().empty(); ++i) std::this_thread::sleep_for(5ms);
    r.cancel();
    ASSERT_TRUE(r.wait_idle(120s));
    EXPECT_TRUE(r.status().cancelled);
    EXPECT_GE(r.points().size(), 1u);
    EXPECT_LT(r.points().size(), all.size());
    o.backend = "truth";
    r.start(s, o);
    ASSERT_TRUE(r.wait_idle(60s));
    EXPECT_NE(r.status().error.find("real-time renderer"), std::string::npos) << r.status().error;
}
