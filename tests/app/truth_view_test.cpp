// The window's Truth view without a window (app/gui/truth_view.h): passes of doubling samples up
// to the target, each the bytes of one render of as many; a higher target continues, another
// scene starts over, cancel keeps the last finished pass; the error's colours and legend scale.
#include "app/gui/truth_view.h"
#include "app/truth_figures.h"
#include "core/scene.h"
#include "core/session.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>

using namespace mesolab;
using namespace std::chrono_literals;

namespace {
Scene torus(float kd) {
    const std::string text = R"({"schema": 1, "name": "view", "camera": {"mode": "orbit", "distance": 3.0, "orbit": [50, -60], "fov": 40},
        "lights": [{"type": "directional", "direction": [40, 10], "intensity": 2, "color": [1, 1, 1]}],
        "env": {"color": [1, 1, 1], "intensity": 0.5}, "effects": {"environment": true},
        "objects": [{"name": "torus", "geometry": {"type": "torus", "resolution": 32},
          "material": {"technique": "basic", "kd": [)" + std::to_string(kd) + ", 0.5, 0.5], \"ks\": [0, 0, 0]}}]}";
    return scene_from_json(nlohmann::json::parse(text), "view", test::source_path("presets"));
}

Frame fresh(const Scene& s, int size, int spp) {
    TruthSettings st;
    st.spp = spp;
    Session session;
    return render_truth(s, session.evaluate(s, truth_stages(s)), size, size, st);
}

std::optional<Frame> last_frame(gui::TruthRunner& r) {
    std::optional<Frame> f;
    while (auto g = r.take_frame()) f = std::move(g->frame);
    return f;
}
}  // namespace

TEST(TruthView, RefinesToTheTargetAndContinuesToAHigherOne) {
    gui::TruthRunner r;
    TruthSettings st;
    st.spp = 6;
    const Scene s = torus(0.5f);
    r.want(s, 16, 16, st);
    ASSERT_TRUE(r.wait_idle(60s));
    std::optional<Frame> f = last_frame(r);
    ASSERT_TRUE(f);
    EXPECT_EQ(r.status().spp, 6);
    EXPECT_GT(r.status().noise_rel, 0.0);
    EXPECT_EQ(f->aov("radiance").data, fresh(s, 16, 6).aov("radiance").data);  // passes 1, 2, 4, 6: the bytes of one render
    st.spp = 12;
    r.want(s, 16, 16, st);  // continues
    ASSERT_TRUE(r.wait_idle(60s));
    f = last_frame(r);
    ASSERT_TRUE(f);
    EXPECT_EQ(r.status().spp, 12);
    EXPECT_EQ(f->aov("radiance").data, fresh(s, 16, 12).aov("radiance").data);
    r.want(torus(0.9f), 16, 16, st);  // another truth: starts over
    ASSERT_TRUE(r.wait_idle(60s));
    f = last_frame(r);
    ASSERT_TRUE(f);
    EXPECT_EQ(f->aov("radiance").data, fresh(torus(0.9f), 16, 12).aov("radiance").data);
}

TEST(TruthView, CancelKeepsTheLastFinishedPass) {
    gui::TruthRunner r;
    TruthSettings st;
    st.spp = 1 << 20;  // far more than it will reach
    const Scene s = torus(0.5f);
    r.want(s, 24, 24, st);
    for (int i = 0; i < 600 && r.status().spp < 2; ++i) std::this_thread::sleep_for(10ms);
    r.cancel();
    ASSERT_TRUE(r.wait_idle(60s));
    const gui::TruthRunner::Status status = r.status();
    EXPECT_TRUE(status.cancelled);
    EXPECT_GE(status.spp, 2);
    EXPECT_LT(status.spp, st.spp);
    const std::optional<Frame> f = last_frame(r);
    ASSERT_TRUE(f);
    EXPECT_EQ(f->aov("radiance").data, fresh(s, 24, status.spp).aov("radiance").data);
    r.want(s, 24, 24, st);  // the same request again: not restarted
    EXPECT_TRUE(r.wait_idle(1s));
    EXPECT_EQ(r.status().spp, status.spp);
}

TEST(TruthView, ASceneWithoutTruthIsSaidInTheStatus) {
    gui::TruthRunner r;
    Scene s = load_preset(test::source_path("presets/cloth/stitch-knit.json"));
    apply_set(s, "cloth.samples", test::source_path("presets/cloth/stitch-knit.json"));  // samples only: no yarns to trace
    r.want(s, 8, 8, TruthSettings{});
    ASSERT_TRUE(r.wait_idle(10s));
    EXPECT_NE(r.status().error.find("cloth.samples"), std::string::npos) << r.status().error;
    EXPECT_FALSE(r.take_frame());
}

TEST(TruthView, ErrorColoursAreWhiteAtZeroAndSaturateAtTheScale) {
    Frame truth = make_frame({{"radiance", 3, ""}, {"normal", 3, ""}, {"truth_stderr", 3, ""}}, 3, 1);
    for (int x = 0; x < 3; ++x) truth.aov("normal").at(x, 0)[2] = 1.f;
    Image err(3, 1, 3);
    for (int c = 0; c < 3; ++c) err.at(1, 0)[c] = 0.3f, err.at(2, 0)[c] = -0.05f;
    EXPECT_FLOAT_EQ(error_scale(err, truth), 0.5f);  // p99 of |error| 0.3: rounded up to 0.5
    const Image c = error_colors(err, truth, 0.3f);
    EXPECT_FLOAT_EQ(c.at(0, 0)[0], 1.f);   // zero: white
    EXPECT_FLOAT_EQ(c.at(0, 0)[2], 1.f);
    EXPECT_FLOAT_EQ(c.at(1, 0)[0], 1.f);   // +scale: red
    EXPECT_NEAR(c.at(1, 0)[2], 0.05f, 1e-6f);
    EXPECT_LT(c.at(2, 0)[0], 1.f);        // below the truth: towards blue
    EXPECT_FLOAT_EQ(c.at(2, 0)[2], 1.f);
}
